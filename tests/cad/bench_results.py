# SPDX-License-Identifier: GPL-3.0-or-later
"""Benchmark (issue 36): how long the Blender add-on and the FreeCAD workbench take to build their
result objects from a large design and deployment, without a daemon and without the solver.

    blender -b --factory-startup --python-exit-code 1 --python tests/cad/bench_results.py -- DESIGN_JSON RUN_DIR
    freecadcmd tests/cad/bench_results.py --pass DESIGN_JSON RUN_DIR     (or GRIDSHELL_BENCH_ARGS="...")

DESIGN_JSON: a design.json (e.g. of `gridshell design example:double-vault --members-u 100
--members-v 100 --lamella-width 0.1`); RUN_DIR: the output of `gridshell run` of the same design
(deployment.json, deployed.obj, deviation.ply and their *_without_notches twins). They are
wrapped as the daemon's DesignResult and SimulateResult (files base64, as over HTTP) and handed
to the plugin's show_design and show_deployment, the functions its operators call with a call's
result. Prints one line per step: seconds and the objects made.
"""

import base64
import json
import os
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))


def arguments():
    if "GRIDSHELL_BENCH_ARGS" in os.environ:
        return os.environ["GRIDSHELL_BENCH_ARGS"].split()
    if "--" in sys.argv:
        return sys.argv[sys.argv.index("--") + 1 :]
    if "--pass" in sys.argv:
        return sys.argv[sys.argv.index("--pass") + 1 :]
    return []


def results(design_path, run_dir):
    with open(design_path, "rb") as f:
        design_bytes = f.read()
    design = json.loads(design_bytes)
    # design.json holds the design's fields besides its options and report
    design_result = {
        "design": design,
        "report": design.get("report", {}),
        "views": [{"name": "design.json", "content": base64.b64encode(design_bytes).decode("ascii")}],
    }
    with open(os.path.join(run_dir, "deployment.json"), "rb") as f:
        deployment = json.load(f)
    views = []
    for name in ("deployment.json", "deployed.obj", "deviation.ply", "deployed_without_notches.obj",
                 "deviation_without_notches.ply"):
        path = os.path.join(run_dir, name)
        if os.path.exists(path):
            with open(path, "rb") as f:
                views.append({"name": name, "content": base64.b64encode(f.read()).decode("ascii")})
    return design_result, {"deployment": deployment, "views": views}


def timed(what, work):
    t0 = time.perf_counter()
    out = work()
    seconds = time.perf_counter() - t0
    print("bench_results: %s: %.2f s" % (what, seconds), flush=True)
    return out, seconds


def main():
    args = arguments()
    if len(args) < 2:
        print(__doc__)
        sys.exit(2)
    design_result, simulate_result = results(args[0], args[1])
    rods = simulate_result["deployment"]["rods"]
    print("bench_results: %d members, %d lamellas, %d rod vertices"
          % (len(design_result["design"]["members"]), len(rods), sum(len(r["centerline"]) for r in rods)), flush=True)
    try:
        import bpy  # noqa: F401
    except ImportError:
        bpy = None
    if bpy is not None:
        sys.path.insert(0, os.path.join(ROOT, "client", "blender"))
        from gridshell_blender import results as blender_results

        scene = bpy.context.scene
        timed("Blender show_design", lambda: blender_results.show_design(scene, design_result, "bench", "", 0.0))
        deployed, _ = timed("Blender show_deployment", lambda: blender_results.show_deployment(scene, simulate_result, 0.0))
        for obj in deployed.objects:
            print("bench_results: %s: %d vertices, %d faces" % (obj.name, len(obj.data.vertices), len(obj.data.polygons)))
        return
    sys.path.insert(0, os.path.join(ROOT, "client", "freecad"))
    import FreeCAD

    from gridshell_freecad import core

    doc = FreeCAD.newDocument("bench")
    timed("FreeCAD show_design", lambda: core.show_design(doc, design_result, "bench", "", 0.0))
    deployed, _ = timed("FreeCAD show_deployment", lambda: core.show_deployment(doc, simulate_result, 0.0))
    for obj in deployed.Group:
        print("bench_results: %s: %d points, %d facets" % (obj.Label, obj.Mesh.CountPoints, obj.Mesh.CountFacets))


main()
