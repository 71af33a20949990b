# SPDX-License-Identifier: GPL-3.0-or-later
"""The sidebar panel of the 3D viewport (N panel, tab "gridshell"), with a sub-panel for the
daemon's address and credentials (closed by default). Its first draw with a server starts
reading that daemon's description (materials, option ranges) in the background (described.py)."""

from array import array

import bpy

from . import described, layouts, results
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
        described.ensure(settings)
        description = described.description(settings)

        def field(column, name, group="design", option=None, value=None, **kwargs):
            """An option's field, red when the daemon's description refuses its value."""
            row = column.row()
            option = option or name
            if description is not None and description.option(group, option) is not None:
                value = getattr(settings, name) if value is None else value
                row.alert = description.check(group, option, value) is not None
            row.prop(settings, name, **kwargs)

        layout.label(text=corners_text(context.active_object), icon="MESH_DATA")

        box = layout.box()
        box.label(text="Design", icon="MOD_LATTICE")
        row = box.row()
        row.prop(settings, "alpha_mode", expand=True)
        if settings.alpha_mode == "value":
            box.prop(settings, "alpha_value")
        col = box.column(align=True)
        field(col, "members_u")
        field(col, "members_v")
        col = box.column(align=True)
        field(col, "lamella_width", text="Width")
        field(col, "lamella_thickness", text="Thickness")
        field(box, "resolution")
        field(box, "interior_anchors")

        box = layout.box()
        row = box.row()
        row.label(text="Simulation", icon="PHYSICS")
        # Reads the daemon's materials (its description) again.
        row.operator("gridshell.refresh_options", text="", icon="FILE_REFRESH", emboss=False)
        box.prop(settings, "unit")
        box.prop(settings, "material")
        note = described.status(settings)
        if note:
            box.label(text=note, icon="INFO")
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

        # Several patches joined at seams: the layout, then every patch built.
        box = layout.box()
        box.label(text="Several patches", icon="MESH_GRID")
        box.prop(settings, "layout_source", text="")
        if settings.layout_source == "AUTO":
            col = box.column(align=True)
            field(col, "max_patches", group="layout")
            field(col, "coverage_goal", group="layout", value=settings.automatic_options().get("coverage_goal", 0.0))
        elif settings.layout_source == "FILE":
            box.prop(settings, "layout_file", text="")
        elif settings.layout_source == "GROUPS":
            box.label(text="a vertex group of 4 vertices per patch", icon="GROUP_VERTEX")
        if STATE["call"] is None:
            box.operator("gridshell.layout")
            box.operator("gridshell.build_layout")
        for label, value, alert in layouts.summary(context.scene):
            split = box.split(factor=0.4)
            split.alert = alert
            split.label(text=label)
            split.label(text=str(value), icon="ERROR" if alert else "NONE")

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
