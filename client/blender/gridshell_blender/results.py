# SPDX-License-Identifier: GPL-3.0-or-later
"""Results into the scene, in world coordinates (the frame the request's mesh was sent in).

Collection ``gridshell``: the target patch (mesh), the surface members as curves (collection
``gridshell members``, one object per member), the anchors as empties (``gridshell anchors``),
the deployed lamellas as a mesh with a ``deviation`` colour attribute and a material that shows
it; RMS values, ᾱ and times as custom properties of the collection. Collection ``gridshell
planar`` beside it: the flat layout as curves, placed next to the model. design.json itself is
kept as the text ``gridshell design.json`` (what Simulate sends).
"""

import bpy

from .remote import gs

COLLECTION = "gridshell"
MEMBERS = "gridshell members"
ANCHORS = "gridshell anchors"
PLANAR = "gridshell planar"
DEPLOYED = "gridshell deployed"
DESIGN_TEXT = "gridshell design.json"
MATERIAL = "gridshell deviation"


def collection(scene, name, parent=None):
    """The collection ``name``, linked under ``parent`` (default: the scene's), made if needed."""
    parent = parent or scene.collection
    coll = bpy.data.collections.get(name)
    if coll is None:
        coll = bpy.data.collections.new(name)
    if coll.name not in parent.children:
        parent.children.link(coll)
    return coll


def clear(coll):
    """Removes the collection's own objects and their data."""
    for obj in list(coll.objects):
        data = obj.data
        bpy.data.objects.remove(obj, do_unlink=True)
        if data is not None and data.users == 0:
            if isinstance(data, bpy.types.Mesh):
                bpy.data.meshes.remove(data)
            elif isinstance(data, bpy.types.Curve):
                bpy.data.curves.remove(data)


def new_mesh(name, positions, polygons):
    """A mesh from flat positions and polygons (lists of vertex indices)."""
    mesh = bpy.data.meshes.new(name)
    mesh.vertices.add(len(positions) // 3)
    mesh.vertices.foreach_set("co", positions)
    loops = [v for polygon in polygons for v in polygon]
    starts, start = [], 0
    for polygon in polygons:
        starts.append(start)
        start += len(polygon)
    mesh.loops.add(len(loops))
    mesh.loops.foreach_set("vertex_index", loops)
    mesh.polygons.add(len(polygons))
    mesh.polygons.foreach_set("loop_start", starts)
    mesh.polygons.foreach_set("loop_total", [len(p) for p in polygons])
    mesh.update(calc_edges=True)
    return mesh


def new_curve(name, points, coll, dimensions="3D"):
    """A poly curve object through ``points`` ((x, y, z) each)."""
    curve = bpy.data.curves.new(name, "CURVE")
    curve.dimensions = dimensions
    spline = curve.splines.new("POLY")
    spline.points.add(len(points) - 1)
    spline.points.foreach_set("co", [c for p in points for c in (p[0], p[1], p[2], 1.0)])
    obj = bpy.data.objects.new(name, curve)
    coll.objects.link(obj)
    return obj


def _extent(vertices):
    lo = [min(v[k] for v in vertices) for k in range(3)]
    hi = [max(v[k] for v in vertices) for k in range(3)]
    return lo, hi


def show_design(scene, result, source, server, call_seconds):
    """Replaces the design part of the ``gridshell`` collections with ``result`` (DesignResult
    with files)."""
    design = result["design"]
    report = result.get("report", {})
    files = gs.files_of(result)
    top = collection(scene, COLLECTION)
    clear(top)
    members = collection(scene, MEMBERS, top)
    anchors = collection(scene, ANCHORS, top)
    planar = collection(scene, PLANAR)
    for coll in (members, anchors, planar):
        clear(coll)
    deployed = bpy.data.collections.get(DEPLOYED)
    if deployed is not None:
        clear(deployed)  # a deployment of an earlier design

    patch = design["patch"]
    vertices = patch["vertices"]
    positions = [c for v in vertices for c in v]
    patch_obj = bpy.data.objects.new(
        "gridshell patch", new_mesh("gridshell patch", positions, patch["faces"])
    )
    patch_obj.display_type = "WIRE"
    top.objects.link(patch_obj)

    for member in design["members"]:
        obj = new_curve("%s %d" % (member["family"], member["index"]), member["surface"], members)
        obj["family"] = member["family"]
        obj["index"] = member["index"]
        obj["boundary"] = member.get("boundary", False)
        obj["length"] = member.get("length", 0.0)

    lo, hi = _extent(vertices)
    size = max(hi[k] - lo[k] for k in range(3)) or 1.0
    for anchor in design.get("anchors", []):
        empty = bpy.data.objects.new("anchor g%d h%d" % (anchor["g"], anchor["h"]), None)
        empty.empty_display_type = "PLAIN_AXES"
        empty.empty_display_size = 0.03 * size
        empty.location = anchor["position"]
        empty["g"], empty["h"] = anchor["g"], anchor["h"]
        empty["corner"] = anchor.get("corner", False)
        empty["side"] = anchor.get("side", 0)
        anchors.objects.link(empty)

    # The flat layout beside the model: its lower left at the model's lower right, a gap between.
    flat = [p for m in design["members"] for p in m["planar"]]
    fx0 = min(p[0] for p in flat)
    fy0 = min(p[1] for p in flat)
    offset = (hi[0] + 0.1 * size - fx0, lo[1] - fy0, lo[2])
    for member in design["members"]:
        points = [(p[0] + offset[0], p[1] + offset[1], offset[2]) for p in member["planar"]]
        obj = new_curve("planar %s %d" % (member["family"], member["index"]), points, planar)
        obj["family"] = member["family"]
        obj["index"] = member["index"]
    planar["offset"] = offset

    top["source"] = source
    top["server"] = server
    top["alpha"] = design["alpha"]
    top["alpha_bar"] = design["alpha_bar"]
    top["alpha_bar_min"], top["alpha_bar_max"] = design["alpha_bar_range"]
    top["members"] = len(design["members"])
    top["crossings"] = len(design.get("crossings", []))
    top["anchors"] = len(design.get("anchors", []))
    top["design_seconds"] = report.get("seconds", 0.0)
    top["design_call_seconds"] = call_seconds
    for key in list(top.keys()):
        if key.startswith(("rms_", "simulate_", "seconds_")) or key in ("converged", "material"):
            del top[key]

    text = bpy.data.texts.get(DESIGN_TEXT) or bpy.data.texts.new(DESIGN_TEXT)
    text.clear()
    text.write(files["design.json"].decode("utf-8"))
    return top


def design_json(context):
    """The design to simulate: the text ``gridshell design.json`` (made by Design, or any
    design.json opened into it)."""
    text = bpy.data.texts.get(DESIGN_TEXT)
    return None if text is None else text.as_string()


def deviation_material():
    material = bpy.data.materials.get(MATERIAL)
    if material is not None:
        return material
    material = bpy.data.materials.new(MATERIAL)
    material.use_nodes = True
    nodes = material.node_tree.nodes
    bsdf = nodes.get("Principled BSDF")
    attribute = nodes.new("ShaderNodeAttribute")
    attribute.attribute_name = "deviation"
    attribute.location = (-300, 200)
    material.node_tree.links.new(attribute.outputs["Color"], bsdf.inputs["Base Color"])
    return material


def lamella_objects(result, coll, prefix="gridshell lamellas", scale=None):
    """The deployed lamellas of ``result`` (SimulateResult with its views) as meshes in ``coll``
    (one per run: ``prefix``, ``prefix without notches``, hidden when both ran), coloured by
    their deviation from the target: blue 0 to red at ``scale`` (default: the run's largest)."""
    deployment = result["deployment"]
    views = gs.files_of(result)
    runs = [r for r in (True, False) if ("deployed%s.obj" % ("" if r else "_without_notches")) in views]
    made = []
    for notches in runs:
        positions, polygons, deviation = gs.plugin.deployed_mesh(result, views, notches)
        run = deployment["with_notches" if notches else "without_notches"]
        name = prefix + ("" if notches else " without notches")
        mesh = new_mesh(name, positions, polygons)
        top_deviation = scale if scale is not None else (max(deviation) if deviation else 0.0)
        colours = mesh.color_attributes.new("deviation", "FLOAT_COLOR", "POINT")
        rgba = []
        for d in deviation:
            rgba += gs.plugin.deviation_colour(d, top_deviation) + (1.0,)
        colours.data.foreach_set("color", rgba)
        mesh.color_attributes.active_color = colours  # what Solid shading's "Attribute" shows
        values = mesh.attributes.new("deviation_distance", "FLOAT", "POINT")
        values.data.foreach_set("value", deviation)
        mesh.materials.append(deviation_material())
        obj = bpy.data.objects.new(name, mesh)
        obj["rms"] = run.get("rms", 0.0)
        obj["max_deviation"] = run.get("max_deviation", 0.0)
        obj["notches"] = notches
        coll.objects.link(obj)
        if not notches and len(runs) > 1:
            obj.hide_set(True)
            obj.hide_render = True
        made.append(obj)
    return made


def show_deployment(scene, result, call_seconds):
    """The deployed lamellas of ``result`` (SimulateResult) into ``gridshell deployed``."""
    deployment = result["deployment"]
    top = collection(scene, COLLECTION)
    deployed = collection(scene, DEPLOYED, top)
    clear(deployed)
    lamella_objects(result, deployed)
    for key in ("rms_with_notches", "rms_without_notches", "seconds_with_notches", "seconds_without_notches"):
        if key in deployment:
            top[key] = deployment[key]
        elif key in top:
            del top[key]
    top["converged"] = bool(deployment.get("converged", False))
    top["simulate_call_seconds"] = call_seconds
    top["material"] = deployment.get("options", {}).get("material", "")  # the one simulated
    # Inner anchors the simulation added (interior_anchors "auto"): empties beside the design's.
    anchors = collection(scene, ANCHORS, top)
    for obj in [o for o in anchors.objects if o.get("added", False)]:
        bpy.data.objects.remove(obj, do_unlink=True)
    added = deployment.get("added_anchors", [])
    size = max((o.empty_display_size for o in anchors.objects), default=1.0)  # the design's anchors
    for anchor in added:
        empty = bpy.data.objects.new("added anchor g%d h%d" % (anchor["g"], anchor["h"]), None)
        empty.empty_display_type = "CUBE"
        empty.empty_display_size = 1.5 * size
        empty.location = anchor["position"]
        empty["g"], empty["h"] = anchor["g"], anchor["h"]
        empty["side"] = anchor.get("side", -1)
        empty["added"] = True
        anchors.objects.link(empty)
    top["added_anchors"] = len(added)
    if "anchor_trial_rms" in deployment:
        top["anchor_trial_rms"] = list(deployment["anchor_trial_rms"])
    elif "anchor_trial_rms" in top:
        del top["anchor_trial_rms"]
    return deployed


def summary(scene):
    """(label, value) rows of the last results, for the panel."""
    top = bpy.data.collections.get(COLLECTION)
    if top is None or "alpha" not in top:
        return []
    deg = 57.29577951308232
    rows = [
        ("Source", top.get("source", "")),
        ("α, ᾱ", "%.2f°, %.2f°" % (top["alpha"] * deg, top["alpha_bar"] * deg)),
        ("Feasible ᾱ", "%.2f° to %.2f°" % (top["alpha_bar_min"] * deg, top["alpha_bar_max"] * deg)),
        ("Members", "%d, %d crossings" % (top["members"], top["crossings"])),
        ("Anchors", "%d" % top["anchors"]
         + (", %d added by the simulation" % top["added_anchors"] if top.get("added_anchors") else "")),
        ("Design", "%.1f s, call %.1f s" % (top["design_seconds"], top["design_call_seconds"])),
    ]
    if "rms_without_notches" in top:
        rows.append(("RMS1", "%.4g" % top["rms_without_notches"]))  # without notches
    if "rms_with_notches" in top:
        rows.append(("RMS2", "%.4g" % top["rms_with_notches"]))  # with notches (paper's RMS2)
    if top.get("material"):
        rows.append(("Material", top["material"]))
    if "simulate_call_seconds" in top:
        seconds = [top[k] for k in ("seconds_without_notches", "seconds_with_notches") if k in top]
        rows.append(("Simulation", "%.1f s, call %.1f s" % (sum(seconds), top["simulate_call_seconds"])))
    return rows
