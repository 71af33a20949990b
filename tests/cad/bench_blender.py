# SPDX-License-Identifier: GPL-3.0-or-later
"""Benchmark: design + simulation of the double-vault example from the Blender add-on next to the
CLI for the same request, against one gridshelld (no patch cache, so every run computes all).

    blender -b --factory-startup --python-exit-code 1 --python tests/cad/bench_blender.py -- \\
        [--repeats N] [--json FILE]

The mesh is the example as the daemon loads it, made a Blender object (its vertices float32, as
Blender stores them), corners the example's, selected in order; the CLI gets the add-on's request
arrays as an OBJ with 17 digits and the same corners and options, so both send the same request
(checked: the same design.json, byte for byte). Runs alternate (CLI, add-on, add-on, CLI, ...) so
that both see the same machine load; the medians and their ratio are printed and, with --json,
written. The add-on's time is bpy.ops.gridshell.run() (request, call, results in the scene); the
CLI's is the process's wall time of `gridshell run --server` (request, Design and Simulate calls,
files written).
"""

import argparse
import json
import os
import resource
import statistics
import sys
import tempfile
import time

import bmesh
import bpy

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(ROOT, "tests", "python"))
sys.path.insert(0, os.path.join(ROOT, "client", "blender"))

import gridshell_testing as T  # noqa: E402,N812

import gridshell_blender  # noqa: E402
from gridshell_blender import mesh_input, results  # noqa: E402
from gridshell_blender.remote import gs  # noqa: E402


def arguments():
    argv = sys.argv[sys.argv.index("--") + 1 :] if "--" in sys.argv else []
    parser = argparse.ArgumentParser(prog="bench_blender.py")
    parser.add_argument("--repeats", type=int, default=7)
    parser.add_argument("--example", default="double-vault")
    parser.add_argument("--json", default="")
    return parser.parse_args(argv)


def main():
    args = arguments()
    tmp = tempfile.mkdtemp(prefix="gridshell-bench-")
    with T.Daemon("--cache-mib", "0") as daemon:
        gridshell_blender.register()
        settings = bpy.context.scene.gridshell
        settings.server = daemon.url
        settings.unit = "NONE"  # the CLI's default: no unit
        client = gs.Client(daemon.url)
        loaded = client.load(gs.mesh_example(args.example))
        p, f = loaded["mesh"]["positions"], loaded["mesh"]["indices"]
        mesh = bpy.data.meshes.new(args.example)
        mesh.from_pydata(
            [p[k : k + 3] for k in range(0, len(p), 3)], [], [f[k : k + 3] for k in range(0, len(f), 3)]
        )
        name = args.example + ".obj"
        obj = bpy.data.objects.new(name, mesh)
        bpy.context.scene.collection.objects.link(obj)
        bpy.context.view_layer.objects.active = obj
        corners = loaded["example_corners"]["vertices"]
        bm = bmesh.new()
        bm.from_mesh(mesh)
        bm.verts.ensure_lookup_table()
        for v in bm.verts:
            v.select = False
        for i in corners:
            bm.verts[i].select = True
            bm.select_history.add(bm.verts[i])
        bm.to_mesh(mesh)
        bm.free()
        request_mesh, request_corners, _ = mesh_input.request_mesh_for_scene(bpy.context)
        obj_file = os.path.join(tmp, name)
        T.write_obj(obj_file, request_mesh["positions"], request_mesh["indices"])
        cli_args = ["run", obj_file, "--corners", ",".join(map(str, corners)),
                    "--server", daemon.grpc, "--quiet"]

        def children_cpu():
            usage = resource.getrusage(resource.RUSAGE_CHILDREN)
            return usage.ru_utime + usage.ru_stime

        def cli_run(k):
            out = os.path.join(tmp, "cli-%d" % k)
            cpu, started = children_cpu(), time.monotonic()
            run = T.cli(*cli_args, "--out", out)
            seconds = time.monotonic() - started
            if run.returncode != 0:
                raise RuntimeError("gridshell run failed: %s" % run.stderr)
            return seconds, children_cpu() - cpu, out

        def addon_run():
            cpu, started = time.process_time(), time.monotonic()
            if bpy.ops.gridshell.run() != {"FINISHED"}:
                raise RuntimeError("gridshell.run did not finish")
            return time.monotonic() - started, time.process_time() - cpu

        def daemon_seconds(before, methods):
            """The daemon's time (queue + run) of the requests logged after ``before`` (with the
            Load the add-on's first design on a mesh makes for its patch key)."""
            calls = lambda: [e for e in daemon.requests()[before:] if e["method"] != "Load"]  # noqa: E731
            daemon.wait_for(lambda e: len(calls()) >= len(methods), 10)
            entries = daemon.requests()[before:]
            if sorted(e["method"] for e in calls()) != sorted(methods):
                raise RuntimeError("unexpected requests: %s" % entries)
            return sum(e["run_ms"] + e["queue_ms"] for e in entries) / 1000

        cli_times, addon_times, cli_cpu, addon_cpu, cli_daemon, addon_daemon = [], [], [], [], [], []
        for k in range(args.repeats):
            order = ("cli", "addon") if k % 2 == 0 else ("addon", "cli")
            for which in order:
                before = len(daemon.requests())
                if which == "cli":
                    seconds, cpu, out = cli_run(k)
                    cli_times.append(seconds)
                    cli_cpu.append(cpu)
                    cli_daemon.append(daemon_seconds(before, ["Design", "Simulate"]))
                else:
                    seconds, cpu = addon_run()
                    addon_times.append(seconds)
                    addon_cpu.append(cpu)
                    addon_daemon.append(daemon_seconds(before, ["Run"]))
            with open(os.path.join(out, "design.json"), "rb") as f_cli:
                same = f_cli.read() == results.design_json(bpy.context).encode("utf-8")
            if not same:
                raise RuntimeError("the CLI and the add-on sent different requests (design.json differs)")
            print("bench: run %d: cli %.3f s (daemon %.3f s), add-on %.3f s (daemon %.3f s)"
                  % (k + 1, cli_times[-1], cli_daemon[-1], addon_times[-1], addon_daemon[-1]), flush=True)
        top = bpy.data.collections[results.COLLECTION]
        summary = {
            "example": args.example,
            "vertices": len(p) // 3,
            "members": top["members"],
            "repeats": args.repeats,
            "cli_seconds": cli_times,
            "addon_seconds": addon_times,
            "cli_median": statistics.median(cli_times),
            "addon_median": statistics.median(addon_times),
            "ratio": statistics.median(addon_times) / statistics.median(cli_times),
            # The clients' own CPU time (the daemon's is the same for both): the CLI process's,
            # and Blender's during the operator (its thread in the call included).
            "cli_cpu_median": statistics.median(cli_cpu),
            "addon_cpu_median": statistics.median(addon_cpu),
            # Wall time outside the daemon's work (queue + run, from its log): the client's
            # own share, transport included.
            "cli_daemon_median": statistics.median(cli_daemon),
            "addon_daemon_median": statistics.median(addon_daemon),
            "cli_overhead_median": statistics.median([a - b for a, b in zip(cli_times, cli_daemon)]),
            "addon_overhead_median": statistics.median([a - b for a, b in zip(addon_times, addon_daemon)]),
            "rms_with_notches": top["rms_with_notches"],
            "blender": bpy.app.version_string,
        }
        print("bench: median cli %.3f s, add-on %.3f s, add-on / cli %.3f; client CPU cli %.3f s, add-on %.3f s;"
              " outside the daemon cli %.3f s, add-on %.3f s"
              % (summary["cli_median"], summary["addon_median"], summary["ratio"],
                 summary["cli_cpu_median"], summary["addon_cpu_median"],
                 summary["cli_overhead_median"], summary["addon_overhead_median"]), flush=True)
        if args.json:
            with open(args.json, "w") as f_json:
                json.dump(summary, f_json, indent=1)
        gridshell_blender.unregister()


main()
