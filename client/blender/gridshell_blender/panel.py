# SPDX-License-Identifier: GPL-3.0-or-later
"""The sidebar panel of the 3D viewport (N panel, tab "gridshell"), with a sub-panel for the
daemon's address and credentials (closed by default)."""

from array import array

import bpy

from . import results
from .operators import STATE

DRAWS = [0]  # how often the panel was drawn (for tests of the UI)


def corners_text(obj):
    if obj is None or obj.type != "MESH":
        return "Target: select a mesh object"
    if obj.mode == "EDIT" or len(obj.data.vertices) > 500000:
        return "%s: select 4 corners or none" % obj.name
    flags = array("b", bytes(len(obj.data.vertices)))
    obj.data.vertices.foreach_get("select", flags)
    selected = sum(flags)
    if selected == 0 or selected == len(obj.data.vertices):
        return "%s: automatic corners" % obj.name
    if selected == 4:
        return "%s: 4 corners selected" % obj.name
    return "%s: select 4 corners (%d are)" % (obj.name, selected)


class VIEW3D_PT_gridshell(bpy.types.Panel):
    bl_label = "gridshell"
    bl_idname = "VIEW3D_PT_gridshell"
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "gridshell"

    def draw(self, context):
        DRAWS[0] += 1
        layout = self.layout
        settings = context.scene.gridshell
        layout.label(text=corners_text(context.active_object), icon="MESH_DATA")

        box = layout.box()
        box.label(text="Design", icon="MOD_LATTICE")
        row = box.row()
        row.prop(settings, "alpha_mode", expand=True)
        if settings.alpha_mode == "value":
            box.prop(settings, "alpha_value")
        col = box.column(align=True)
        col.prop(settings, "members_u")
        col.prop(settings, "members_v")
        col = box.column(align=True)
        col.prop(settings, "lamella_width", text="Width")
        col.prop(settings, "lamella_thickness", text="Thickness")
        box.prop(settings, "resolution")
        box.prop(settings, "interior_anchors")

        box = layout.box()
        box.label(text="Simulation", icon="PHYSICS")
        box.prop(settings, "unit")
        box.prop(settings, "material")
        row = box.row()
        row.prop(settings, "notches", expand=True)
        box.prop(settings, "auto_anchors")

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
                split = box.split(factor=0.4)
                split.label(text=label)
                split.label(text=str(value))


class VIEW3D_PT_gridshell_daemon(bpy.types.Panel):
    bl_label = "Daemon"
    bl_idname = "VIEW3D_PT_gridshell_daemon"
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "gridshell"
    bl_parent_id = "VIEW3D_PT_gridshell"
    bl_options = {"DEFAULT_CLOSED"}

    def draw(self, context):
        settings = context.scene.gridshell
        layout = self.layout
        layout.prop(settings, "server")
        layout.prop(settings, "token")
        layout.prop(settings, "ca_file")
        layout.prop(settings, "timeout")


CLASSES = (VIEW3D_PT_gridshell, VIEW3D_PT_gridshell_daemon)
register, unregister = bpy.utils.register_classes_factory(CLASSES)
