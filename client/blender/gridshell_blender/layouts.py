# SPDX-License-Identifier: GPL-3.0-or-later
"""Layouts of several four-sided patches joined at seams (issue 35, docs/multi-patch.md): the
layout to send (automatic, a layout.json file, the object's vertex groups, or the last layout
found), and the results of ``Layout`` and ``RunLayout`` in the scene, in world coordinates.

Collection ``gridshell layout`` (in ``gridshell``): one object per patch, named by the patch
(``P1``, ``P2``, ...), each in its own colour; coverage, areas and what is not covered as custom
properties of the collection. The layout used is kept as the text ``gridshell layout.json`` (a
``gridshell.v1.Layout``: what *Last layout* sends). Collection ``gridshell patches`` (in
``gridshell``): one collection per built patch, ``gridshell P1`` ..., with its deployed lamellas
as the single-patch run builds them, and the whole's numbers (RMS with notches and in % of the
diagonal, converged, seam bolts, the largest seam gap) as custom properties;
the whole's deployment.json is the text ``gridshell layout deployment.json``.
"""

import colorsys
import json

import bpy

from . import results
from .mesh_input import InputError
from .remote import gs

LAYOUT = "gridshell layout"
PATCHES = "gridshell patches"
LAYOUT_TEXT = "gridshell layout.json"
DEPLOYMENT_TEXT = "gridshell layout deployment.json"
PATCH_PREFIX = "gridshell "  # a built patch's collection: "gridshell P1"


def layout_of(data, where):
    """The ``gridshell.v1.Layout`` in ``data`` (gridshell_client.plugin.layout_of), InputError
    when it holds none."""
    try:
        return gs.plugin.layout_of(data, where)
    except ValueError as e:
        raise InputError(str(e)) from None


def read_layout_file(path):
    """The layout of a layout.json file (gridshell_client.plugin.read_layout_file); the path may
    be Blender-relative (//)."""
    try:
        return gs.plugin.read_layout_file(bpy.path.abspath(path) if path else path)
    except ValueError as e:
        raise InputError(str(e)) from None


def last_layout():
    """The layout the last Layout found (the text ``gridshell layout.json``)."""
    text = bpy.data.texts.get(LAYOUT_TEXT)
    if text is None or not text.as_string().strip():
        raise InputError("no layout yet: run Layout first (text '%s')" % LAYOUT_TEXT)
    try:
        data = json.loads(text.as_string())
    except ValueError as e:
        raise InputError("the text '%s' is not JSON: %s" % (LAYOUT_TEXT, e)) from None
    return layout_of(data, "the text '%s'" % LAYOUT_TEXT)


def colour(k):
    """A distinct colour for the k-th patch (0-based): hues a golden angle apart."""
    r, g, b = colorsys.hsv_to_rgb((0.61803398875 * k) % 1.0, 0.55, 0.95)
    return (r, g, b, 1.0)


FAILED_COLOUR = (0.35, 0.35, 0.35, 1.0)


def _patch_material(k, ok):
    name = "gridshell patch colour %d" % (k + 1) if ok else "gridshell patch failed"
    material = bpy.data.materials.get(name) or bpy.data.materials.new(name)
    material.diffuse_color = colour(k) if ok else FAILED_COLOUR  # Solid shading, Material colour
    return material


def remove_tree(coll):
    """Removes ``coll``'s child collections (with their objects) and its own objects."""
    for child in list(coll.children):
        remove_tree(child)
        bpy.data.collections.remove(child)
    results.clear(coll)


def _percent(x):
    return "%.1f %%" % (100 * x)


def _patches(count):
    return "%d patch%s" % (count, "" if count == 1 else "es")


def show_layout(scene, result, source, server, call_seconds, how=""):
    """The patches of ``result`` (LayoutResult) into ``gridshell layout``; returns the report's
    lines as (level, text)."""
    report = result.get("report", {})
    summaries = report.get("patches", [])
    meshes = result.get("patches", [])
    top = results.collection(scene, results.COLLECTION)
    coll = results.collection(scene, LAYOUT, top)
    remove_tree(coll)
    objects = []
    for k, summary in enumerate(summaries):
        name = summary.get("name") or "P%d" % (k + 1)
        mesh = meshes[k] if k < len(meshes) else {}
        positions, indices = mesh.get("positions", []), mesh.get("indices", [])
        ok = bool(summary.get("ok", False))
        if positions and indices:
            data = results.new_mesh(name, positions, [indices[i : i + 3] for i in range(0, len(indices), 3)])
            data.materials.append(_patch_material(k, ok))
            obj = bpy.data.objects.new(name, data)
        else:  # not cut: an empty stands for it, with its problem
            obj = bpy.data.objects.new(name, None)
        obj.color = colour(k) if ok else FAILED_COLOUR  # Solid shading, Object colour
        obj["patch"] = name
        obj["ok"] = ok
        obj["problem"] = summary.get("problem", "")
        obj["problem_field"] = summary.get("problem_field", "")
        obj["area"] = summary.get("area", 0.0)
        obj["eta"] = summary.get("eta", 0.0)
        obj["vertices"] = summary.get("vertices", 0)
        if summary.get("corner_angles"):
            obj["corner_angles"] = list(summary["corner_angles"])
        if summary.get("side_lengths"):
            obj["side_lengths"] = list(summary["side_lengths"])
        coll.objects.link(obj)
        objects.append(obj)

    seams = [s for s in report.get("seams", []) if len(s.get("patches", [])) == 2]
    uncovered = report.get("uncovered", [])
    failing = [s for s in summaries if not s.get("ok", False)]
    for key in list(coll.keys()):
        del coll[key]
    coll["source"] = source
    coll["server"] = server
    coll["layout"] = how
    coll["coverage"] = report.get("coverage", 0.0)
    coll["input_area"] = report.get("input_area", 0.0)
    coll["covered_area"] = report.get("covered_area", 0.0)
    coll["uncovered_area"] = sum(u.get("area", 0.0) for u in uncovered)
    coll["uncovered"] = "\n".join(
        "%s: %.6g (%s)" % (u.get("where", ""), u.get("area", 0.0), u.get("reason", "")) for u in uncovered
    )
    coll["patches"] = len(summaries)
    coll["failing_patches"] = len(failing)
    coll["seams"] = len(seams)
    coll["max_seam_mismatch"] = max((s.get("mismatch", 0.0) for s in seams), default=0.0)
    automatic = report.get("automatic")
    if automatic:
        coll["automatic_grid"] = gs.plugin.automatic_grid(automatic)
        coll["automatic_surface"] = automatic.get("surface", "disk")
        coll["automatic_cut"] = automatic.get("cut", "")
        coll["automatic_trials"] = len(automatic.get("trials", []))
    coll["layout_call_seconds"] = call_seconds

    text = bpy.data.texts.get(LAYOUT_TEXT) or bpy.data.texts.new(LAYOUT_TEXT)
    text.clear()
    text.write(json.dumps(report.get("layout", {}), indent=1) + "\n")

    grid = " (%s)" % coll["automatic_grid"] if automatic else ""
    lines = [("INFO", "gridshell: layout of %s: %s%s, %s of the area covered (%.6g of %.6g)" % (
        source, _patches(len(summaries)), grid, _percent(coll["coverage"]), coll["covered_area"], coll["input_area"]))]
    if automatic and automatic.get("cut"):
        lines.append(("INFO", "gridshell: surface: %s" % automatic["cut"]))
    for u in uncovered:
        lines.append(("INFO", "gridshell: not covered: %s, area %.6g: %s" % (
            u.get("where", ""), u.get("area", 0.0), u.get("reason", ""))))
    for s in failing:
        lines.append(("WARNING", "gridshell: patch %s fails: %s%s" % (
            s.get("name", ""), s.get("problem", ""),
            " (%s)" % s["problem_field"] if s.get("problem_field") else "")))
    return lines


def _largest_deviation(run):
    deployment = run.get("deployment", {})
    values = [d for key in ("rods", "rods_without_notches") for rod in deployment.get(key, [])
              for d in rod.get("deviation", [])]
    return max(values, default=0.0)


def show_build(scene, result, source, server, call_seconds, how=""):
    """The patches of ``result`` (LayoutRunResult) built: the layout into ``gridshell layout``,
    each built patch's deployed lamellas into ``gridshell P1`` ... under ``gridshell patches``,
    the whole's numbers on ``gridshell patches``. Returns the report's lines (level, text)."""
    lines = show_layout(scene, result.get("layout", {}), source, server, call_seconds, how)
    report = result.get("layout", {}).get("report", {})
    summaries = report.get("patches", [])
    runs = result.get("patches", [])
    deployment = result.get("deployment", {})
    design = result.get("design", {})
    top = results.collection(scene, results.COLLECTION)
    parent = results.collection(scene, PATCHES, top)
    remove_tree(parent)
    for key in list(parent.keys()):
        del parent[key]
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
        coll = results.collection(scene, PATCH_PREFIX + name, parent)
        results.lamella_objects(joined.get(name) or run["simulation"], coll, prefix="%s lamellas" % name,
                                scale=scale)
        coll["patch"] = name
        numbers = per_patch.get(name, {})
        for key in ("rms_with_notches", "rms_without_notches", "grid_vertices", "max_normal_stress"):
            if key in numbers:
                coll[key] = numbers[key]
        coll["converged"] = bool(numbers.get("converged", False))
        patch_design = run.get("design", {}).get("design", {})
        if patch_design:
            coll["alpha_bar"] = patch_design.get("alpha_bar", 0.0)
            coll["members"] = len(patch_design.get("members", []))
        built.append(name)

    diagonal = deployment.get("diagonal", 0.0)
    for key in ("rms_with_notches", "rms_without_notches"):
        if key in deployment:
            parent[key] = deployment[key]
            if diagonal > 0:
                parent[key + "_percent"] = 100 * deployment[key] / diagonal  # of the diagonal
    parent["diagonal"] = diagonal
    parent["converged"] = bool(deployment.get("converged", False))
    parent["seam_bolts"] = design.get("seam_bolts", 0)
    parent["max_seam_gap"] = deployment.get("max_seam_gap", 0.0)
    if diagonal > 0:
        parent["max_seam_gap_percent"] = 100 * deployment.get("max_seam_gap", 0.0) / diagonal
    parent["seams_joined"] = bool(deployment.get("seams_joined", False))
    parent["max_bolt_force"] = deployment.get("max_bolt_force", 0.0)
    parent["force_unit"] = deployment.get("force_unit", "")
    if "rms_before_joining" in deployment:
        parent["rms_before_joining"] = deployment["rms_before_joining"]
    parent["grid_vertices"] = deployment.get("grid_vertices", 0)
    parent["max_normal_stress"] = deployment.get("max_normal_stress", 0.0)
    parent["patches_built"] = len(built)
    parent["patches_failed"] = len(failed)
    parent["failed"] = "\n".join(failed)
    parent["coverage"] = report.get("coverage", 0.0)
    parent["material"] = deployment.get("options", {}).get("material", "")
    parent["source"] = source
    parent["server"] = server
    parent["build_call_seconds"] = call_seconds
    text = bpy.data.texts.get(DEPLOYMENT_TEXT) or bpy.data.texts.new(DEPLOYMENT_TEXT)
    text.clear()
    text.write(json.dumps(deployment, indent=1) + "\n")

    lines = [line for line in lines if line[0] != "WARNING"]  # failing patches: said below
    rms = ", ".join(
        "%s %.4g (%.3f %% of the diagonal)" % (what, deployment[key], 100 * deployment[key] / diagonal if diagonal else 0)
        for what, key in (("RMS2", "rms_with_notches"), ("RMS1", "rms_without_notches")) if key in deployment
    )
    lines.append(("INFO", "gridshell: built %d of %d patches of %s; whole %s; %d seam bolts; largest seam gap "
                  "%s %.4g (%.3f %% of the diagonal)%s" % (
                      len(built), len(summaries), source, rms or "no RMS", parent["seam_bolts"],
                      "after joining" if deployment.get("seams_joined") else "before joining (not joined)",
                      parent["max_seam_gap"], parent.get("max_seam_gap_percent", 0.0), gs.plugin.joining_note(deployment))))
    for line in failed:
        lines.append(("WARNING", "gridshell: patch %s" % line))
    if not parent["converged"]:
        late = [p.get("name", "") for p in deployment.get("patches", []) if not p.get("converged", False)]
        lines.append(("WARNING", "gridshell: NOT CONVERGED: the simulation of %s did not reach "
                      "equilibrium; the deviations are not those of the deployed shell" % (
                          "patches " + ", ".join(late) if late else "the whole")))
    return lines


def summary(scene):
    """(label, value, alert) rows of the last layout and build, for the panel."""
    rows = []
    coll = bpy.data.collections.get(LAYOUT)
    if coll is not None and "coverage" in coll:
        rows.append(("Layout", "%s%s" % (_patches(coll["patches"]), ", %d failing" % coll["failing_patches"]
                                                 if coll.get("failing_patches") else ""), bool(coll.get("failing_patches"))))
        rows.append(("Covered", _percent(coll["coverage"]), False))
    parent = bpy.data.collections.get(PATCHES)
    if parent is not None and "patches_built" in parent:
        rows.append(("Built", "%s%s" % (_patches(parent["patches_built"]), ", %d failed" % parent["patches_failed"]
                                                if parent.get("patches_failed") else ""), bool(parent.get("patches_failed"))))
        if "rms_with_notches" in parent:
            rows.append(("Whole RMS2", "%.4g (%.3f %%)" % (parent["rms_with_notches"],
                                                          parent.get("rms_with_notches_percent", 0.0)), False))
        elif "rms_without_notches" in parent:
            rows.append(("Whole RMS1", "%.4g (%.3f %%)" % (parent["rms_without_notches"],
                                                          parent.get("rms_without_notches_percent", 0.0)), False))
        rows.append(("Converged", "yes" if parent["converged"] else "NO", not parent["converged"]))
        rows.append(("Seams", "%d bolts, gap %.3g" % (parent["seam_bolts"], parent["max_seam_gap"]), False))
    return rows
