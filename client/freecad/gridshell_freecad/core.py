# SPDX-License-Identifier: GPL-3.0-or-later
"""The workbench without its GUI (importable in freecadcmd): the target of a request from a Mesh
object, calls to the daemon, and the results as document objects; also layouts of several
patches joined at seams (``layout``, ``build_layout``: groups ``gridshell layout`` and
``gridshell patches``, docs/freecad.md).

    import FreeCAD, gridshell_freecad.core as core
    settings = core.Settings(server="http://127.0.0.1:8080", resolution=40)
    group = core.design(doc, doc.getObject("Mesh"), settings)        # corners automatic
    core.simulate(doc, settings)                                     # the design in the group

Results go into the group ``gridshell``: the target patch (Mesh), surface members as Part wires
(group ``gridshell members``), anchors as Part vertices (``gridshell anchors``), the deployed
lamellas as a Mesh with the deviation of every vertex (``gridshell deployed``); beside it the
group ``gridshell planar`` with the flat layout as Part wires, placed next to the model. RMS
values, ᾱ and times are properties of the group ``gridshell`` (section "Gridshell"), and
design.json is kept in its hidden property ``DesignJson`` (what Simulate sends).
"""

import colorsys
import json
import os
import time

import FreeCAD
import Mesh
import Part
from FreeCAD import Vector

from .remote import gs

GROUP = "gridshell"
MEMBERS = "gridshell members"
ANCHORS = "gridshell anchors"
PLANAR = "gridshell planar"
DEPLOYED = "gridshell deployed"
PARAMETERS = "User parameter:BaseApp/Preferences/Mod/Gridshell"

# Request fields -> the labels of the task panel (error messages name the field this way).
FIELD_LABELS = {
    "options.alpha": "Planar angle",
    "options.members_u": "Members u",
    "options.members_v": "Members v",
    "options.lamella_width": "Lamella width",
    "options.lamella_thickness": "Lamella thickness",
    "options.resolution": "Map resolution",
    "options.interior_anchors": "Inner anchors",
    "options.material": "Material",
    "simulation.material": "Material",
    "options.notches": "Notches",
    "simulation.notches": "Notches",
    "corners": "picked corner",
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

# Where a layout's patches come from (Settings.layout).
LAYOUT_SOURCES = (
    ("auto", "Automatic"),
    ("file", "Layout file"),
    ("last", "Last layout (group 'gridshell layout')"),
)


class InputError(Exception):
    """The document does not give a target (no Mesh object, a wrong number of corners)."""


class Settings:
    """Server and options of a request; the initial values are the API's defaults (the tests
    compare them with the daemon's description), and what is set is sent. ``material`` "" is
    none chosen: the request names none and the daemon takes its default (the first of its
    description). FreeCAD's length unit is the millimetre, so the simulation's unit is mm
    (energies in joules, stresses in pascals)."""

    FIELDS = {
        "server": "",
        "token": "",
        "ca_file": "",
        "timeout": 0.0,
        "alpha": "min",  # "min" | "max" | degrees as a number
        "members_u": 0,
        "members_v": 0,
        "lamella_width": 0.0,
        "lamella_thickness": 0.0,
        "resolution": 100,
        "interior_anchors": 0,
        "unit": "mm",
        "material": "",  # a name of the daemon's materials; "" = its default
        "notches": "both",
        "auto_anchors": False,  # simulate with interior_anchors "auto"
        "layout": "auto",  # "auto" | "file" | "last": where a layout's patches come from
        "layout_file": "",  # layout.json: a gridshell.v1.Layout or a layout report
        "max_patches": 36,  # an automatic layout's options (0 = the daemon's default)
        "coverage_goal": 0.95,
    }

    def __init__(self, **values):
        for name, default in self.FIELDS.items():
            setattr(self, name, values.pop(name, default))
        if values:
            raise TypeError("unknown settings: %s" % ", ".join(sorted(values)))
        if not self.server:
            self.server = os.environ.get("GRIDSHELL_SERVER", "").strip() or "http://127.0.0.1:8080"

    @classmethod
    def load(cls):
        """The settings saved in FreeCAD's parameters (Preferences/Mod/Gridshell)."""
        p = FreeCAD.ParamGet(PARAMETERS)
        values = {}
        for name, default in cls.FIELDS.items():
            if isinstance(default, str):
                values[name] = p.GetString(name, default)
            elif isinstance(default, bool):
                values[name] = p.GetBool(name, default)
            elif isinstance(default, int):
                values[name] = p.GetInt(name, default)
            else:
                values[name] = p.GetFloat(name, default)
        return cls(**values)

    def save(self):
        p = FreeCAD.ParamGet(PARAMETERS)
        for name, default in self.FIELDS.items():
            value = getattr(self, name)
            if isinstance(default, str):
                p.SetString(name, str(value))
            elif isinstance(default, bool):
                p.SetBool(name, bool(value))
            elif isinstance(default, int):
                p.SetInt(name, int(value))
            else:
                p.SetFloat(name, float(value))

    def client(self):
        return gs.Client(
            self.server,
            token=self.token or None,
            ca_file=self.ca_file or None,
            timeout=self.timeout or None,
        )

    def design_options(self):
        options = {}
        alpha = str(self.alpha).strip()
        if alpha in ("max",):
            options["alpha"] = "max"
        elif alpha not in ("", "min"):
            options["alpha"] = alpha if alpha.endswith("deg") else alpha + "deg"
        for name in ("members_u", "members_v", "lamella_width", "lamella_thickness", "interior_anchors"):
            if getattr(self, name):
                options[name] = getattr(self, name)
        options["resolution"] = self.resolution
        return options

    def automatic_options(self):
        """AutoLayoutOptions: the options that are set (0: the daemon's default)."""
        options = {}
        if self.max_patches:
            options["max_patches"] = int(self.max_patches)
        if self.coverage_goal:
            options["coverage_goal"] = float(self.coverage_goal)
        return options

    def simulation_options(self):
        options = {"notches": self.notches}
        if self.material:
            options["material"] = self.material
        if self.auto_anchors:
            options["interior_anchors"] = "auto"
        if self.unit:
            options["unit"] = self.unit
        return options


def describe(settings, refresh=False, timeout=10.0):
    """The daemon's description of its options and materials (``gridshell_client.Description``),
    read once per daemon address for the FreeCAD session (``refresh``: read again); a call with
    no retries, so that an unreachable daemon answers at once."""
    client = settings.client()
    client.retries = 0
    return gs.describe(client, refresh=refresh, timeout=timeout)


def cached_description(settings):
    """The description ``describe`` read for the settings' daemon, or None (no call)."""
    return gs.options.cached(settings.server)


def material_choices(description, chosen=""):
    """(name, label) of the materials to offer: the daemon's (its default first, then its
    site's own), or, without a description, its default alone (name "": none sent); a chosen
    name the description lacks is kept at the end (sent as it is: the daemon checks it)."""
    if description is not None and description.materials:
        rows = []
        for m in description.materials:
            label = m.get("label") or m.get("name", "")
            label = label[:1].upper() + label[1:]
            rows.append((m.get("name", ""), label + (" (site)" if m.get("site") else "")))
    else:
        rows = [("", "Default (the daemon's)")]
    if chosen and chosen not in [name for name, _ in rows]:
        rows.append((chosen, "%s (not in the daemon's list)" % chosen))
    return rows


# A spin box's maximum for an option the description bounds only from below (a Qt spin box needs
# one): the largest int32, which is also the API's largest integer.
UNBOUNDED = 2**31 - 1


def spin_range(description, group, name):
    """(low, high) for a spin box of a numeric option from the daemon's description: 0 where 0 is
    allowed (automatic), else its minimum, up to its maximum (UNBOUNDED where the description sets
    none); None when the description has no minimum (the box keeps its own, and the daemon checks
    the value)."""
    option = None if description is None else description.option(group, name)
    if option is None or option.get("type") not in ("number", "integer"):
        return None
    low, high = option.get("minimum"), option.get("maximum")
    if low is None:
        return None
    if high is None:
        high = UNBOUNDED
    if option.get("zero_allowed"):
        low = min(low, 0)
    if option.get("type") == "integer":
        return int(-(-low // 1)), int(high // 1)
    return float(low), float(high)


def _vector(v):
    return Vector(float(v[0]), float(v[1]), float(v[2]))


def target(obj, corners=None):
    """(mesh message, corners message or None) of a Mesh object in global coordinates.

    ``corners``: None (automatic), 4 points (global x, y, z; snapped to the surface by the
    daemon) or 4 vertex indices of the object's mesh.
    """
    if obj is None or not hasattr(obj, "Mesh") or not isinstance(obj.Mesh, Mesh.Mesh):
        raise InputError(
            "select a Mesh object as the target surface%s"
            % ("" if obj is None else " (%s is a %s)" % (obj.Label, obj.TypeId))
        )
    points, facets = obj.Mesh.Topology  # the object's own Placement applied
    if not facets:
        raise InputError("%s has no faces" % obj.Label)
    outer = obj.getGlobalPlacement().multiply(obj.Placement.inverse())  # App::Part containers
    if not outer.isIdentity():
        points = [outer.multVec(p) for p in points]
    positions = [c for p in points for c in (p.x, p.y, p.z)]
    indices = [i for f in facets for i in f]
    request_corners = None
    if corners is not None:
        corners = list(corners)
        if len(corners) != 4:
            raise InputError("pick 4 corner points on %s (or none for automatic corners); %d are picked"
                             % (obj.Label, len(corners)))
        if all(isinstance(c, int) for c in corners):
            request_corners = {"vertices": corners}
        else:
            request_corners = {"points": [float(x) for c in corners for x in (c[0], c[1], c[2])]}
    return gs.mesh_arrays(positions, indices, name=obj.Label), request_corners


def _group(doc, name, parent=None):
    group = doc.getObject(name.replace(" ", "_"))
    if group is None:
        group = doc.addObject("App::DocumentObjectGroup", name.replace(" ", "_"))
        group.Label = name
    if parent is not None and group not in parent.Group:
        parent.addObject(group)
    return group


def _clear(doc, group):
    for obj in list(group.Group):
        if obj.TypeId == "App::DocumentObjectGroup":
            _clear(doc, obj)
            continue
        doc.removeObject(obj.Name)


def _set(obj, name, kind, value, section="Gridshell", hidden=False):
    if name not in obj.PropertiesList:
        obj.addProperty(kind, name, section)
        if hidden:
            obj.setEditorMode(name, 2)
    setattr(obj, name, value)


def _feature(doc, group, label, shape):
    feature = doc.addObject("Part::Feature", "gridshell_part")
    feature.Label = label
    feature.Shape = shape
    group.addObject(feature)
    return feature


def show_design(doc, result, source, server, call_seconds):
    """Replaces the design objects of the gridshell groups with ``result`` (DesignResult with
    files); returns the group ``gridshell``."""
    design = result["design"]
    report = result.get("report", {})
    files = gs.files_of(result)
    top = _group(doc, GROUP)
    members = _group(doc, MEMBERS, top)
    anchors = _group(doc, ANCHORS, top)
    deployed = _group(doc, DEPLOYED, top)
    planar = _group(doc, PLANAR)
    for group in (members, anchors, deployed, planar):
        _clear(doc, group)
    for obj in list(top.Group):
        if obj.TypeId != "App::DocumentObjectGroup":
            doc.removeObject(obj.Name)

    patch = design["patch"]
    triangles = [[patch["vertices"][i] for i in face] for face in patch["faces"]]
    patch_obj = doc.addObject("Mesh::Feature", "gridshell_patch")
    patch_obj.Label = "gridshell patch"
    patch_obj.Mesh = Mesh.Mesh([_vector(p) for t in triangles for p in t])
    top.addObject(patch_obj)

    for member in design["members"]:
        wire = Part.makePolygon([_vector(p) for p in member["surface"]])
        f = _feature(doc, members, "%s %d" % (member["family"], member["index"]), wire)
        _set(f, "Family", "App::PropertyString", member["family"])
        _set(f, "Index", "App::PropertyInteger", member["index"])
        _set(f, "Boundary", "App::PropertyBool", bool(member.get("boundary", False)))
        _set(f, "Length", "App::PropertyFloat", member.get("length", 0.0))

    for anchor in design.get("anchors", []):
        f = _feature(doc, anchors, "anchor g%d h%d" % (anchor["g"], anchor["h"]),
                     Part.Vertex(_vector(anchor["position"])))
        _set(f, "Corner", "App::PropertyBool", bool(anchor.get("corner", False)))
        _set(f, "Side", "App::PropertyInteger", anchor.get("side", 0))

    # The flat layout beside the model: its lower left at the model's lower right, a gap between.
    xs = [v[0] for v in patch["vertices"]]
    ys = [v[1] for v in patch["vertices"]]
    zs = [v[2] for v in patch["vertices"]]
    size = max(max(xs) - min(xs), max(ys) - min(ys), max(zs) - min(zs)) or 1.0
    flat = [p for m in design["members"] for p in m["planar"]]
    offset = (max(xs) + 0.1 * size - min(p[0] for p in flat), min(ys) - min(p[1] for p in flat), min(zs))
    for member in design["members"]:
        wire = Part.makePolygon([Vector(p[0] + offset[0], p[1] + offset[1], offset[2]) for p in member["planar"]])
        f = _feature(doc, planar, "planar %s %d" % (member["family"], member["index"]), wire)
        _set(f, "Family", "App::PropertyString", member["family"])
        _set(f, "Index", "App::PropertyInteger", member["index"])

    _set(top, "Source", "App::PropertyString", source)
    _set(top, "Server", "App::PropertyString", server)
    _set(top, "Alpha", "App::PropertyAngle", design["alpha"] * 57.29577951308232)
    _set(top, "AlphaBar", "App::PropertyAngle", design["alpha_bar"] * 57.29577951308232)
    _set(top, "AlphaBarRadians", "App::PropertyFloat", design["alpha_bar"])
    _set(top, "AlphaBarMin", "App::PropertyAngle", design["alpha_bar_range"][0] * 57.29577951308232)
    _set(top, "AlphaBarMax", "App::PropertyAngle", design["alpha_bar_range"][1] * 57.29577951308232)
    _set(top, "Members", "App::PropertyInteger", len(design["members"]))
    _set(top, "Crossings", "App::PropertyInteger", len(design.get("crossings", [])))
    _set(top, "Anchors", "App::PropertyInteger", len(design.get("anchors", [])))
    _set(top, "DesignSeconds", "App::PropertyFloat", report.get("seconds", 0.0))
    _set(top, "DesignCallSeconds", "App::PropertyFloat", call_seconds)
    _set(top, "DesignJson", "App::PropertyString", files["design.json"].decode("utf-8"), hidden=True)
    for name in ("RmsWithNotches", "RmsWithoutNotches", "SimulateCallSeconds", "Material"):
        if name in top.PropertiesList:
            top.removeProperty(name)
    doc.recompute()
    return top


def _lamella_objects(doc, result, group, prefix="gridshell lamellas", scale=None):
    """The deployed lamellas of ``result`` (SimulateResult with its views) as Mesh objects in
    ``group``, one per run (``prefix``, ``prefix without notches``), with the deviation of every
    box vertex and facet (``scale``: the largest deviation of the colour map, kept as
    ``DeviationScale``; default the run's own largest)."""
    deployment = result["deployment"]
    views = gs.files_of(result)
    made = []
    for notches in (True, False):
        if ("deployed%s.obj" % ("" if notches else "_without_notches")) not in views:
            continue
        positions, polygons, deviation = gs.plugin.deployed_mesh(result, views, notches)
        points = [Vector(positions[k], positions[k + 1], positions[k + 2]) for k in range(0, len(positions), 3)]
        facets = []
        for polygon in polygons:  # quads and end caps -> triangles (fans)
            for k in range(1, len(polygon) - 1):
                facets.append((polygon[0], polygon[k], polygon[k + 1]))
        mesh = Mesh.Mesh([points[i] for f in facets for i in f])
        # A facet's deviation: the largest of its corners' (for colouring by deviation).
        facet_deviation = [max(deviation[i] for i in f) for f in facets]
        run = deployment["with_notches" if notches else "without_notches"]
        obj = doc.addObject("Mesh::Feature", "gridshell_lamellas")
        obj.Label = prefix + ("" if notches else " without notches")
        obj.Mesh = mesh
        _set(obj, "Notches", "App::PropertyBool", notches)
        _set(obj, "Rms", "App::PropertyFloat", run.get("rms", 0.0))
        _set(obj, "MaxDeviation", "App::PropertyFloat", run.get("max_deviation", 0.0))
        # Deviation of every box corner, in the order of deployed.obj's vertices.
        _set(obj, "Deviation", "App::PropertyFloatList", deviation)
        _set(obj, "Positions", "App::PropertyVectorList", points, hidden=True)
        if mesh.CountFacets == len(facets):
            _set(obj, "FacetDeviation", "App::PropertyFloatList", facet_deviation)
        if scale is not None:
            _set(obj, "DeviationScale", "App::PropertyFloat", scale)
        group.addObject(obj)
        made.append(obj)
    return made


def show_deployment(doc, result, call_seconds):
    """The deployed lamellas of ``result`` (SimulateResult) into the group ``gridshell deployed``."""
    deployment = result["deployment"]
    top = _group(doc, GROUP)
    deployed = _group(doc, DEPLOYED, top)
    _clear(doc, deployed)
    _lamella_objects(doc, result, deployed)
    for key, name in (("rms_with_notches", "RmsWithNotches"), ("rms_without_notches", "RmsWithoutNotches")):
        if key in deployment:
            _set(top, name, "App::PropertyFloat", deployment[key])
        elif name in top.PropertiesList:
            top.removeProperty(name)
    _set(top, "Converged", "App::PropertyBool", bool(deployment.get("converged", False)))
    _set(top, "SimulateCallSeconds", "App::PropertyFloat", call_seconds)
    # The material the simulation used (a name of the daemon's materials, or "custom").
    _set(top, "Material", "App::PropertyString", deployment.get("options", {}).get("material", ""))
    # Inner anchors the simulation added (interior_anchors "auto"): vertices beside the design's.
    anchors = _group(doc, ANCHORS, top)
    for obj in list(anchors.Group):
        if "Added" in obj.PropertiesList and obj.Added:
            doc.removeObject(obj.Name)
    added = deployment.get("added_anchors", [])
    for anchor in added:
        f = _feature(doc, anchors, "added anchor g%d h%d" % (anchor["g"], anchor["h"]),
                     Part.Vertex(_vector(anchor["position"])))
        _set(f, "Corner", "App::PropertyBool", False)
        _set(f, "Side", "App::PropertyInteger", anchor.get("side", -1))
        _set(f, "Added", "App::PropertyBool", True)
    _set(top, "AddedAnchors", "App::PropertyInteger", len(added))
    _set(top, "AnchorTrialRms", "App::PropertyFloatList", list(deployment.get("anchor_trial_rms", [])))
    doc.recompute()
    return deployed


# ---- several patches joined at seams (issue 35, docs/multi-patch.md) -------------------------

LAYOUT = "gridshell layout"
PATCHES = "gridshell patches"
PATCH_PREFIX = "gridshell "  # a built patch's group: "gridshell P1"


def layout_of(data, where):
    """The ``gridshell.v1.Layout`` in ``data`` (gridshell_client.plugin.layout_of), InputError
    when it holds none."""
    try:
        return gs.plugin.layout_of(data, where)
    except ValueError as e:
        raise InputError(str(e)) from None


def read_layout_file(path):
    """The layout of a layout.json file (gridshell_client.plugin.read_layout_file)."""
    try:
        return gs.plugin.read_layout_file(path)
    except ValueError as e:
        raise InputError(str(e)) from None


def last_layout(doc):
    """The layout the last Layout found (the hidden property ``LayoutJson`` of ``gridshell layout``)."""
    group = doc.getObject(LAYOUT.replace(" ", "_"))
    text = getattr(group, "LayoutJson", "") if group is not None else ""
    if not text:
        raise InputError("no layout yet: run Layout first (group '%s')" % LAYOUT)
    return layout_of(json.loads(text), "the group '%s'" % LAYOUT)


def layout_inputs(doc, settings):
    """(layout, automatic, how) of the settings: a layout dict or None, the automatic options or
    None, and words for the report."""
    if settings.layout == "auto":
        return None, settings.automatic_options(), "automatic"
    if settings.layout == "file":
        return read_layout_file(settings.layout_file), None, "file %s" % settings.layout_file
    if settings.layout == "last":
        return last_layout(doc), None, "last layout"
    raise InputError("unknown layout source %r: expected one of %s"
                     % (settings.layout, ", ".join(k for k, _ in LAYOUT_SOURCES)))


def patch_colour(k):
    """A distinct colour for the k-th patch (0-based): hues a golden angle apart."""
    r, g, b = colorsys.hsv_to_rgb((0.61803398875 * k) % 1.0, 0.55, 0.95)
    return (r, g, b)


FAILED_COLOUR = (0.35, 0.35, 0.35)


def _remove_tree(doc, group):
    """Removes ``group``'s objects and its sub-groups with theirs."""
    for obj in list(group.Group):
        if obj.TypeId == "App::DocumentObjectGroup":
            _remove_tree(doc, obj)
        doc.removeObject(obj.Name)


def _percent(x):
    return "%.1f %%" % (100 * x)


def _patches(count):
    return "%d patch%s" % (count, "" if count == 1 else "es")


def _say(lines):
    for level, text in lines:
        if level == "WARNING":
            FreeCAD.Console.PrintWarning(text + "\n")
        else:
            FreeCAD.Console.PrintMessage(text + "\n")


def show_layout(doc, result, source, server, call_seconds, how="", report_view=True):
    """The patches of ``result`` (LayoutResult) into the group ``gridshell layout``: one Mesh
    per patch, labelled by the patch, in its own colour (``Colour``; the GUI shows it); the
    coverage and what is not covered as properties of the group, and in the report view.
    Returns the group."""
    report = result.get("report", {})
    summaries = report.get("patches", [])
    meshes = result.get("patches", [])
    top = _group(doc, GROUP)
    group = _group(doc, LAYOUT, top)
    _remove_tree(doc, group)
    for k, summary in enumerate(summaries):
        name = summary.get("name") or "P%d" % (k + 1)
        mesh = meshes[k] if k < len(meshes) else {}
        positions, indices = mesh.get("positions", []), mesh.get("indices", [])
        ok = bool(summary.get("ok", False))
        obj = doc.addObject("Mesh::Feature", "gridshell_layout_patch")
        obj.Label = name
        if positions and indices:
            points = [Vector(positions[3 * i], positions[3 * i + 1], positions[3 * i + 2]) for i in indices]
            obj.Mesh = Mesh.Mesh(points)
        colour = patch_colour(k) if ok else FAILED_COLOUR
        _set(obj, "Patch", "App::PropertyString", name)
        _set(obj, "Ok", "App::PropertyBool", ok)
        _set(obj, "Problem", "App::PropertyString", summary.get("problem", ""))
        _set(obj, "ProblemField", "App::PropertyString", summary.get("problem_field", ""))
        _set(obj, "Area", "App::PropertyFloat", summary.get("area", 0.0))
        _set(obj, "Eta", "App::PropertyFloat", summary.get("eta", 0.0))
        _set(obj, "CornerAngles", "App::PropertyFloatList", list(summary.get("corner_angles", [])))
        _set(obj, "SideLengths", "App::PropertyFloatList", list(summary.get("side_lengths", [])))
        _set(obj, "Colour", "App::PropertyColor", colour)
        if getattr(obj, "ViewObject", None) is not None:
            obj.ViewObject.ShapeColor = colour
        group.addObject(obj)

    seams = [x for x in report.get("seams", []) if len(x.get("patches", [])) == 2]
    uncovered = report.get("uncovered", [])
    failing = [x for x in summaries if not x.get("ok", False)]
    automatic = report.get("automatic")
    _set(group, "Source", "App::PropertyString", source)
    _set(group, "Server", "App::PropertyString", server)
    _set(group, "Layout", "App::PropertyString", how)
    _set(group, "Coverage", "App::PropertyFloat", report.get("coverage", 0.0))
    _set(group, "InputArea", "App::PropertyFloat", report.get("input_area", 0.0))
    _set(group, "CoveredArea", "App::PropertyFloat", report.get("covered_area", 0.0))
    _set(group, "UncoveredArea", "App::PropertyFloat", sum(u.get("area", 0.0) for u in uncovered))
    _set(group, "Uncovered", "App::PropertyStringList", [
        "%s: %.6g (%s)" % (u.get("where", ""), u.get("area", 0.0), u.get("reason", "")) for u in uncovered])
    _set(group, "Patches", "App::PropertyInteger", len(summaries))
    _set(group, "FailingPatches", "App::PropertyStringList", [
        "%s: %s" % (x.get("name", ""), x.get("problem", "")) for x in failing])
    _set(group, "Seams", "App::PropertyInteger", len(seams))
    _set(group, "MaxSeamMismatch", "App::PropertyFloat", max((x.get("mismatch", 0.0) for x in seams), default=0.0))
    _set(group, "AutomaticGrid", "App::PropertyString", gs.plugin.automatic_grid(automatic) if automatic else "")
    _set(group, "AutomaticSurface", "App::PropertyString", automatic.get("surface", "disk") if automatic else "")
    _set(group, "AutomaticCut", "App::PropertyString", automatic.get("cut", "") if automatic else "")
    _set(group, "LayoutCallSeconds", "App::PropertyFloat", call_seconds)
    _set(group, "LayoutJson", "App::PropertyString", json.dumps(report.get("layout", {})), hidden=True)
    doc.recompute()

    grid = " (%s)" % group.AutomaticGrid if automatic else ""
    lines = [("INFO", "gridshell: layout of %s: %s%s, %s of the area covered (%.6g of %.6g)" % (
        source, _patches(len(summaries)), grid, _percent(group.Coverage), group.CoveredArea, group.InputArea))]
    if group.AutomaticCut:
        lines.append(("INFO", "gridshell: surface: %s" % group.AutomaticCut))
    for u in uncovered:
        lines.append(("INFO", "gridshell: not covered: %s, area %.6g: %s" % (
            u.get("where", ""), u.get("area", 0.0), u.get("reason", ""))))
    for x in failing:
        lines.append(("WARNING", "gridshell: patch %s fails: %s%s" % (
            x.get("name", ""), x.get("problem", ""),
            " (%s)" % x["problem_field"] if x.get("problem_field") else "")))
    if report_view:
        _say(lines)
    return group


def _largest_deviation(run):
    deployment = run.get("deployment", {})
    values = [d for key in ("rods", "rods_without_notches") for rod in deployment.get(key, [])
              for d in rod.get("deviation", [])]
    return max(values, default=0.0)


def show_build(doc, result, source, server, call_seconds, how=""):
    """The patches of ``result`` (LayoutRunResult) built: the layout into ``gridshell layout``,
    each built patch's deployed lamellas into the group ``gridshell P1`` ... in ``gridshell
    patches``, the whole's numbers as properties of ``gridshell patches`` (and in the report
    view, with a warning for a patch not built and for a run that did not converge). Returns the
    group ``gridshell patches``."""
    show_layout(doc, result.get("layout", {}), source, server, call_seconds, how, report_view=False)
    report = result.get("layout", {}).get("report", {})
    summaries = report.get("patches", [])
    runs = result.get("patches", [])
    deployment = result.get("deployment", {})
    design = result.get("design", {})
    top = _group(doc, GROUP)
    parent = _group(doc, PATCHES, top)
    _remove_tree(doc, parent)
    per_patch = {p.get("name"): p for p in deployment.get("patches", [])}
    # The whole joined at its seams, drawn per patch (each patch as it deployed alone when the
    # seams were not joined), on one colour scale as the whole's deviation.ply: blue 0, red at
    # the largest.
    joined = gs.plugin.joined_patch_results(result)
    drawn = list(joined.values()) or [r["simulation"] for r in runs if r.get("simulation")]
    scale = max((_largest_deviation(r) for r in drawn), default=0.0)
    built, failed = [], []
    for k, summary in enumerate(summaries):
        name = summary.get("name") or "P%d" % (k + 1)
        run = runs[k] if k < len(runs) else {}
        if not run.get("simulation"):
            failed.append("%s: %s%s" % (name, summary.get("problem", "") or "not built",
                                        " (%s)" % summary["problem_field"] if summary.get("problem_field") else ""))
            continue
        group = _group(doc, PATCH_PREFIX + name, parent)
        _lamella_objects(doc, joined.get(name) or run["simulation"], group, prefix="%s lamellas" % name,
                         scale=scale)
        numbers = per_patch.get(name, {})
        _set(group, "Patch", "App::PropertyString", name)
        for key, prop in (("rms_with_notches", "RmsWithNotches"), ("rms_without_notches", "RmsWithoutNotches"),
                          ("max_normal_stress", "MaxNormalStress")):
            if key in numbers:
                _set(group, prop, "App::PropertyFloat", numbers[key])
        _set(group, "GridVertices", "App::PropertyInteger", numbers.get("grid_vertices", 0))
        _set(group, "Converged", "App::PropertyBool", bool(numbers.get("converged", False)))
        patch_design = run.get("design", {}).get("design", {})
        if patch_design:
            _set(group, "AlphaBarRadians", "App::PropertyFloat", patch_design.get("alpha_bar", 0.0))
            _set(group, "Members", "App::PropertyInteger", len(patch_design.get("members", [])))
        built.append(name)

    diagonal = deployment.get("diagonal", 0.0)
    for key, prop in (("rms_with_notches", "RmsWithNotches"), ("rms_without_notches", "RmsWithoutNotches")):
        for name in (prop, prop + "Percent"):
            if name in parent.PropertiesList:
                parent.removeProperty(name)
        if key in deployment:
            _set(parent, prop, "App::PropertyFloat", deployment[key])
            if diagonal > 0:  # % of the diagonal of the input's bounding box
                _set(parent, prop + "Percent", "App::PropertyFloat", 100 * deployment[key] / diagonal)
    _set(parent, "Diagonal", "App::PropertyFloat", diagonal)
    _set(parent, "Converged", "App::PropertyBool", bool(deployment.get("converged", False)))
    _set(parent, "SeamBolts", "App::PropertyInteger", design.get("seam_bolts", 0))
    _set(parent, "MaxSeamGap", "App::PropertyFloat", deployment.get("max_seam_gap", 0.0))
    _set(parent, "MaxSeamGapPercent", "App::PropertyFloat",
         100 * deployment.get("max_seam_gap", 0.0) / diagonal if diagonal > 0 else 0.0)
    _set(parent, "SeamsJoined", "App::PropertyBool", bool(deployment.get("seams_joined", False)))
    _set(parent, "MaxBoltForce", "App::PropertyFloat", deployment.get("max_bolt_force", 0.0))
    _set(parent, "ForceUnit", "App::PropertyString", deployment.get("force_unit", ""))
    _set(parent, "RmsBeforeJoining", "App::PropertyFloat", deployment.get("rms_before_joining", 0.0))
    _set(parent, "GridVertices", "App::PropertyInteger", deployment.get("grid_vertices", 0))
    _set(parent, "MaxNormalStress", "App::PropertyFloat", deployment.get("max_normal_stress", 0.0))
    _set(parent, "PatchesBuilt", "App::PropertyInteger", len(built))
    _set(parent, "FailedPatches", "App::PropertyStringList", failed)
    _set(parent, "Coverage", "App::PropertyFloat", report.get("coverage", 0.0))
    _set(parent, "Material", "App::PropertyString", deployment.get("options", {}).get("material", ""))
    _set(parent, "Source", "App::PropertyString", source)
    _set(parent, "Server", "App::PropertyString", server)
    _set(parent, "BuildCallSeconds", "App::PropertyFloat", call_seconds)
    _set(parent, "DeploymentJson", "App::PropertyString", json.dumps(deployment), hidden=True)
    doc.recompute()

    rms = ", ".join(
        "%s %.4g (%.3f %% of the diagonal)" % (what, deployment[key], 100 * deployment[key] / diagonal if diagonal else 0)
        for what, key in (("RMS2", "rms_with_notches"), ("RMS1", "rms_without_notches")) if key in deployment
    )
    lines = [("INFO", "gridshell: layout of %s: %s, %s of the area covered" % (
        source, _patches(len(summaries)), _percent(report.get("coverage", 0.0))))]
    lines.append(("INFO", "gridshell: built %d of %d patches of %s; whole %s; %d seam bolts; largest seam gap "
                  "%s %.4g (%.3f %% of the diagonal)%s" % (
                      len(built), len(summaries), source, rms or "no RMS", parent.SeamBolts,
                      "after joining" if deployment.get("seams_joined") else "before joining (not joined)",
                      parent.MaxSeamGap, parent.MaxSeamGapPercent, gs.plugin.joining_note(deployment))))
    for line in failed:
        lines.append(("WARNING", "gridshell: patch %s" % line))
    if not parent.Converged:
        late = [p.get("name", "") for p in deployment.get("patches", []) if not p.get("converged", False)]
        lines.append(("WARNING", "gridshell: NOT CONVERGED: the simulation of %s did not reach "
                      "equilibrium; the deviations are not those of the deployed shell" % (
                          "patches " + ", ".join(late) if late else "the whole")))
    _say(lines)
    return parent


def layout_target(obj):
    """The mesh message of a Mesh object for a layout (the layout says where the corners are)."""
    mesh, _ = target(obj)
    return mesh


def prepare_layout(doc, obj, settings):
    """(work(progress, cancel), finish(result, seconds)) of a layout of ``obj``."""
    mesh = layout_target(obj)
    layout, automatic, how = layout_inputs(doc, settings)
    client = settings.client()

    def work(progress=None, cancel=None):
        return client.layout(mesh, layout=layout, automatic=automatic, progress=progress, cancel=cancel)

    def finish(result, seconds):
        return show_layout(doc, result, mesh["name"], client.server, seconds, how)

    return work, finish


def prepare_build(doc, obj, settings):
    """(work, finish) of every patch of the layout designed and simulated."""
    mesh = layout_target(obj)
    layout, automatic, how = layout_inputs(doc, settings)
    client = settings.client()
    design_options = settings.design_options()
    simulation = settings.simulation_options()

    def work(progress=None, cancel=None):
        return client.run_layout(mesh, layout=layout, automatic=automatic, design_options=design_options,
                                 simulation=simulation, progress=progress, cancel=cancel)

    def finish(result, seconds):
        return show_build(doc, result, mesh["name"], client.server, seconds, how)

    return work, finish


def design_json(doc):
    top = doc.getObject(GROUP)
    if top is None or "DesignJson" not in top.PropertiesList or not top.DesignJson:
        return None
    return top.DesignJson


def _call(work, progress, cancel):
    started = time.monotonic()
    result = work(progress, cancel)
    return result, time.monotonic() - started


def prepare_design(doc, obj, settings, corners=None):
    """(work(progress, cancel), finish(result, seconds)) of a design of ``obj``."""
    mesh, request_corners = target(obj, corners)
    client = settings.client()
    options = settings.design_options()

    def work(progress=None, cancel=None):
        return client.design(mesh, request_corners, options, files=True, progress=progress, cancel=cancel)

    def finish(result, seconds):
        return show_design(doc, result, mesh["name"], client.server, seconds)

    return work, finish


def prepare_simulate(doc, settings):
    design = design_json(doc)
    if not design:
        raise InputError("no design yet: run Design first")
    client = settings.client()
    options = settings.simulation_options()

    def work(progress=None, cancel=None):
        return client.simulate(design, options, design_name="design.json", progress=progress, cancel=cancel)

    def finish(result, seconds):
        return show_deployment(doc, result, seconds)

    return work, finish


def prepare_run(doc, obj, settings, corners=None):
    mesh, request_corners = target(obj, corners)
    client = settings.client()
    design_options = settings.design_options()
    simulation = settings.simulation_options()

    def work(progress=None, cancel=None):
        return client.run(mesh, request_corners, design_options, simulation, files=True,
                          progress=progress, cancel=cancel)

    def finish(result, seconds):
        show_design(doc, result["design"], mesh["name"], client.server, seconds)
        show_deployment(doc, result["simulation"], seconds)
        return doc.getObject(GROUP)

    return work, finish


def _blocking(prepared, progress, cancel):
    work, finish = prepared
    result, seconds = _call(work, progress, cancel)
    return finish(result, seconds)


def design(doc, obj, settings, corners=None, progress=None, cancel=None):
    """Designs ``obj``'s gridshell (blocking); returns the group ``gridshell``."""
    return _blocking(prepare_design(doc, obj, settings, corners), progress, cancel)


def simulate(doc, settings, progress=None, cancel=None):
    """Simulates the design kept in the group ``gridshell`` (blocking); returns ``gridshell deployed``."""
    return _blocking(prepare_simulate(doc, settings), progress, cancel)


def run(doc, obj, settings, corners=None, progress=None, cancel=None):
    """Design and simulation in one call (blocking); returns the group ``gridshell``."""
    return _blocking(prepare_run(doc, obj, settings, corners), progress, cancel)


def layout(doc, obj, settings, progress=None, cancel=None):
    """A layout of several patches on ``obj`` (blocking; ``settings.layout``: "auto", "file",
    "last"); returns the group ``gridshell layout``."""
    return _blocking(prepare_layout(doc, obj, settings), progress, cancel)


def build_layout(doc, obj, settings, progress=None, cancel=None):
    """Every patch of the layout designed and simulated in one call (blocking); returns the
    group ``gridshell patches``."""
    return _blocking(prepare_build(doc, obj, settings), progress, cancel)


def error_message(error, settings, source=""):
    """Text for FreeCAD's report view or a message box."""
    if isinstance(error, InputError):
        return "gridshell: %s" % error
    return "\n".join(gs.plugin.error_text(error, settings.server, FIELD_LABELS, source))
