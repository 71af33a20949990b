# SPDX-License-Identifier: GPL-3.0-or-later
"""The workbench without its GUI (importable in freecadcmd): the target of a request from a Mesh
object, calls to the daemon, and the results as document objects.

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
}


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


def show_deployment(doc, result, call_seconds):
    """The deployed lamellas of ``result`` (SimulateResult) into the group ``gridshell deployed``."""
    deployment = result["deployment"]
    views = gs.files_of(result)
    top = _group(doc, GROUP)
    deployed = _group(doc, DEPLOYED, top)
    _clear(doc, deployed)
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
        obj.Label = "gridshell lamellas" + ("" if notches else " without notches")
        obj.Mesh = mesh
        _set(obj, "Notches", "App::PropertyBool", notches)
        _set(obj, "Rms", "App::PropertyFloat", run.get("rms", 0.0))
        _set(obj, "MaxDeviation", "App::PropertyFloat", run.get("max_deviation", 0.0))
        # Deviation of every box corner, in the order of deployed.obj's vertices.
        _set(obj, "Deviation", "App::PropertyFloatList", deviation)
        _set(obj, "Positions", "App::PropertyVectorList", points, hidden=True)
        if mesh.CountFacets == len(facets):
            _set(obj, "FacetDeviation", "App::PropertyFloatList", facet_deviation)
        deployed.addObject(obj)
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


def error_message(error, settings, source=""):
    """Text for FreeCAD's report view or a message box."""
    if isinstance(error, InputError):
        return "gridshell: %s" % error
    return "\n".join(gs.plugin.error_text(error, settings.server, FIELD_LABELS, source))
