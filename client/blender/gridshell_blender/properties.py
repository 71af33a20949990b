# SPDX-License-Identifier: GPL-3.0-or-later
"""The add-on's settings, kept with the scene: ``bpy.context.scene.gridshell``.

The material choices are the daemon's (its description, described.py); the design options'
ranges are the daemon's too: the properties keep no copy of them (only a floor of 0 where 0
means automatic), the panel marks a value outside the described range red, and the daemon's
answer names the field (``options.resolution``) of a value it refuses. The initial values of the
properties are the API's defaults (the tests compare them with the description), and what the
panel shows is what is sent.
"""

import math
import os

import bpy
from bpy.props import BoolProperty, EnumProperty, FloatProperty, IntProperty, StringProperty

from . import described

DEFAULT_SERVER = "http://127.0.0.1:8080"

UNITS = [
    ("SCENE", "Scene", "The scene's unit system and scale (Scene > Units); none when it has none"),
    ("NONE", "None", "Unknown unit: energies and stresses are scaled, not physical"),
    ("mm", "mm", ""),
    ("cm", "cm", ""),
    ("m", "m", ""),
    ("in", "in", ""),
    ("ft", "ft", ""),
]

# Request fields -> the labels the panel shows (error reports name the field this way).
FIELD_LABELS = {
    "options.alpha": "Planar angle",
    "options.members_u": "Members u",
    "options.members_v": "Members v",
    "options.lamella_width": "Lamella width",
    "options.lamella_thickness": "Lamella thickness",
    "options.resolution": "Map resolution",
    "options.interior_anchors": "Inner anchors",
    "simulation.material": "Material",
    "options.material": "Material",
    "simulation.notches": "Notches",
    "options.notches": "Notches",
    "corners": "selected corner",
    # A layout of several patches (Layout, Build all patches).
    "automatic.max_patches": "Patches at most",
    "automatic.coverage_goal": "Coverage goal",
    "design.alpha": "Planar angle",
    "design.members_u": "Members u",
    "design.members_v": "Members v",
    "design.lamella_width": "Lamella width",
    "design.lamella_thickness": "Lamella thickness",
    "design.resolution": "Map resolution",
    "design.interior_anchors": "Inner anchors",
    "layout": "Layout",
}

LAYOUT_SOURCES = [
    ("AUTO", "Automatic", "The daemon computes the layout (a grid of patches on a disk-like surface, "
     "fewest patches that reach the coverage goal)"),
    ("FILE", "File", "A layout.json: a gridshell.v1.Layout, or a layout report as 'gridshell layout' "
     "writes it (its 'layout' is sent); vertex corners are indices of the mesh as sent"),
    ("GROUPS", "Vertex groups", "Every vertex group of the object holding exactly 4 vertices is one "
     "patch, named by the group, its corners ordered around their centre; vertices in several groups "
     "are shared corners"),
    ("LAST", "Last layout", "The layout the last Layout found (the text 'gridshell layout.json', "
     "editable)"),
]


def default_server():
    return os.environ.get("GRIDSHELL_SERVER", "").strip() or DEFAULT_SERVER


class GridshellSettings(bpy.types.PropertyGroup):
    server: StringProperty(
        name="Server",
        description="gridshelld's HTTP address (default: $GRIDSHELL_SERVER, else loopback)",
        default=default_server(),  # read when the add-on loads
    )
    token: StringProperty(
        name="Token", description="Bearer token of the daemon, if it has one", subtype="PASSWORD"
    )
    ca_file: StringProperty(
        name="CA file",
        description="PEM file of the CA to verify an https:// daemon against (default: system roots)",
        subtype="FILE_PATH",
    )
    timeout: FloatProperty(
        name="Timeout", description="Deadline of a call in seconds (0 = none)", default=0, min=0
    )
    alpha_mode: EnumProperty(
        name="Planar angle",
        description="The planar grid's corner angle ᾱ",
        items=[
            ("min", "Min", "The smallest feasible ᾱ (the paper's default)"),
            ("max", "Max", "The largest feasible ᾱ"),
            ("value", "Value", "This angle"),
        ],
        default="min",
    )
    alpha_value: FloatProperty(
        name="ᾱ", subtype="ANGLE", default=math.radians(70), min=0.01, max=math.pi - 0.01
    )
    members_u: IntProperty(name="Members u", description="Inner g-members (0 = automatic)", min=0)
    members_v: IntProperty(name="Members v", description="Inner h-members (0 = automatic)", min=0)
    lamella_width: FloatProperty(
        name="Lamella width",
        description="Width of the lamellas (0 = 1% of the longest patch side)",
        subtype="DISTANCE",
        min=0,
        precision=4,
    )
    lamella_thickness: FloatProperty(
        name="Lamella thickness",
        description="Thickness of the lamellas (0 = width / 10)",
        subtype="DISTANCE",
        min=0,
        precision=4,
    )
    resolution: IntProperty(
        name="Map resolution",
        description="Resolution R of the distance maps (0 = adaptive)",
        default=100,
        min=0,
    )
    interior_anchors: IntProperty(
        name="Inner anchors",
        description="Also pin up to N inner crossings at the target's bumps and dips",
        min=0,
    )
    auto_anchors: BoolProperty(
        name="Find inner anchors",
        description="Simulate with inner anchors added one by one where each lowers the deviation by "
        "5% or more (one more simulation per anchor tried); they appear as empties 'added anchor'",
        default=False,
    )
    unit: EnumProperty(name="Unit", description="Length unit of the model", items=UNITS, default="SCENE")
    # The chosen material by name ("" = none chosen: the daemon's default, not sent); the enum
    # below shows it among the daemon's materials.
    material_name: StringProperty(name="Material name", options={"HIDDEN"})
    material: EnumProperty(
        name="Material",
        description="Material of the lamellas: the daemon's presets and its site's own (Refresh "
        "reads them from the daemon)",
        items=described.material_items,
        get=described.get_material,
        set=described.set_material,
    )
    notches: EnumProperty(
        name="Notches",
        description="Simulate the grid with notched crossings, without, or both",
        items=[("both", "Both", ""), ("on", "On", ""), ("off", "Off", "")],
        default="both",
    )

    layout_source: EnumProperty(
        name="Layout", description="Where the patches of a layout come from", items=LAYOUT_SOURCES,
        default="AUTO",
    )
    layout_file: StringProperty(
        name="Layout file", description="layout.json: a gridshell.v1.Layout or a layout report",
        subtype="FILE_PATH",
    )
    # An automatic layout's options (AutoLayoutOptions; 0 = the daemon's default). Initial values:
    # the API's defaults; the ranges are the daemon's description's (red in the panel outside).
    max_patches: IntProperty(
        name="Patches at most", description="An automatic layout's patches at most (0 = default)",
        default=36, min=0,
    )
    coverage_goal: FloatProperty(
        name="Coverage goal",
        description="An automatic layout stops at this fraction of the area covered (0 = default)",
        default=0.95, min=0, precision=3,
    )

    def client(self):
        from .remote import gs

        return gs.Client(
            self.server,
            token=self.token or None,
            ca_file=bpy.path.abspath(self.ca_file) if self.ca_file else None,
            timeout=self.timeout or None,
        )

    def design_options(self):
        """DesignRequest.Options: only what differs from the API's defaults is sent."""
        options = {}
        if self.alpha_mode == "value":
            options["alpha"] = repr(float(self.alpha_value))
        elif self.alpha_mode == "max":
            options["alpha"] = "max"
        for name in ("members_u", "members_v", "lamella_width", "lamella_thickness", "interior_anchors"):
            value = getattr(self, name)
            if value:
                options[name] = value
        options["resolution"] = self.resolution
        return options

    def automatic_options(self):
        """AutoLayoutOptions: the options that are set (0: the daemon's default)."""
        options = {}
        if self.max_patches:
            options["max_patches"] = self.max_patches
        if self.coverage_goal:
            options["coverage_goal"] = float("%.6g" % self.coverage_goal)  # as typed, not float32
        return options

    def simulation_options(self, scene):
        """SimulationOptions: the material only when one was chosen (else the daemon's default)."""
        options = {"notches": self.notches}
        if self.material_name:
            options["material"] = self.material_name
        if self.auto_anchors:
            options["interior_anchors"] = "auto"
        if self.unit == "SCENE":
            units = scene.unit_settings
            if units.system != "NONE":
                options["unit_in_meters"] = float(units.scale_length)
        elif self.unit != "NONE":
            options["unit"] = self.unit
        return options


def register():
    bpy.utils.register_class(GridshellSettings)
    bpy.types.Scene.gridshell = bpy.props.PointerProperty(type=GridshellSettings)


def unregister():
    del bpy.types.Scene.gridshell
    bpy.utils.unregister_class(GridshellSettings)
