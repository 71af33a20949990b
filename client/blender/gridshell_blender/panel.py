# SPDX-License-Identifier: GPL-3.0-or-later
"""The sidebar panel of the 3D viewport (N panel, tab "gridshell")."""

import bpy

from . import results
from .operators import STATE


class VIEW3D_PT_gridshell(bpy.types.Panel):
    bl_label = "gridshell"
    bl_idname = "VIEW3D_PT_gridshell"
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "gridshell"

    def draw(self, context):
        layout = self.layout
        settings = context.scene.gridshell
        obj = context.active_object

        box = layout.box()
        box.label(text="Daemon", icon="URL")
        box.prop(settings, "server")
        box.prop(settings, "token")
        box.prop(settings, "ca_file")
        box.prop(settings, "timeout")

        box = layout.box()
        box.label(text="Target: %s" % (obj.name if obj is not None and obj.type == "MESH" else "(select a mesh)"),
                  icon="MESH_DATA")
        box.label(text="Corners: 4 selected vertices, in order; none: automatic")

        box = layout.box()
        box.label(text="Design", icon="MOD_LATTICE")
        row = box.row()
        row.prop(settings, "alpha_mode", expand=True)
        if settings.alpha_mode == "value":
            box.prop(settings, "alpha_value")
        row = box.row(align=True)
        row.prop(settings, "members_u")
        row.prop(settings, "members_v")
        box.prop(settings, "lamella_width")
        box.prop(settings, "lamella_thickness")
        box.prop(settings, "resolution")
        box.prop(settings, "interior_anchors")

        box = layout.box()
        box.label(text="Simulation", icon="PHYSICS")
        box.prop(settings, "unit")
        box.prop(settings, "material")
        row = box.row()
        row.prop(settings, "notches", expand=True)

        if STATE["call"] is not None:
            box = layout.box()
            box.label(text="%s: %s" % (STATE["label"], STATE["text"]), icon="TIME")
            box.operator("gridshell.cancel", icon="CANCEL")
        else:
            row = layout.row(align=True)
            row.operator("gridshell.design")
            row.operator("gridshell.simulate")
            layout.operator("gridshell.run")

        rows = results.summary(context.scene)
        if rows:
            box = layout.box()
            box.label(text="Results", icon="INFO")
            for label, value in rows:
                split = box.split(factor=0.42)
                split.label(text=label)
                split.label(text=str(value))


def register():
    bpy.utils.register_class(VIEW3D_PT_gridshell)


def unregister():
    bpy.utils.unregister_class(VIEW3D_PT_gridshell)
