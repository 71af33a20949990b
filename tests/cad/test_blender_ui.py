# SPDX-License-Identifier: GPL-3.0-or-later
"""The Blender add-on in Blender's real UI (a window under Xvfb) against a real gridshelld: the
operators started as a button starts them (INVOKE) run without blocking Blender (its timers keep
running while the daemon computes), report progress, the panel reads the daemon's materials on
its first draw, build the results when the answer is in,
and Esc (a real key event) cancels the daemon's work. With GRIDSHELL_SCREENSHOTS=DIR it also saves
the docs' screenshots of the window there.

    xvfb-run -a -s "-screen 0 1440x900x24" blender --factory-startup --enable-event-simulate \\
        --python tests/cad/test_blender_ui.py

Blender's UI loop runs the steps below from a timer; the script ends Blender itself, with exit
code 0 when every check passed and 1 otherwise (or when it takes longer than LIMIT seconds).
"""

import os
import sys
import time
import traceback

import bmesh
import bpy

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(ROOT, "tests", "python"))
sys.path.insert(0, os.path.join(ROOT, "client", "blender"))

import gridshell_testing as T  # noqa: E402,N812

import gridshell_blender  # noqa: E402
from gridshell_blender import described, panel, results  # noqa: E402
from gridshell_blender.operators import STATE  # noqa: E402
from gridshell_blender.remote import gs  # noqa: E402

LIMIT = 600  # seconds for the whole script
SHOTS = os.environ.get("GRIDSHELL_SCREENSHOTS", "")
checks = []


def check(condition, what):
    checks.append((bool(condition), what))
    print("%s: %s" % ("ok" if condition else "FAILED", what))
    sys.stdout.flush()


def view3d():
    window = bpy.context.window_manager.windows[0]
    for area in window.screen.areas:
        if area.type == "VIEW_3D":
            region = [r for r in area.regions if r.type == "WINDOW"][0]
            return window, area, region
    raise RuntimeError("no 3D viewport")


def invoke(operator):
    window, area, region = view3d()
    with bpy.context.temp_override(window=window, area=area, region=region):
        return operator("INVOKE_DEFAULT")


def screenshot(name):
    if not SHOTS:
        return
    os.makedirs(SHOTS, exist_ok=True)
    window, area, region = view3d()
    with bpy.context.temp_override(window=window):
        bpy.ops.screen.screenshot(filepath=os.path.join(SHOTS, name))
    print("screenshot %s" % name)


def add_dome(name, n, size=10.0, height=2.5):
    """The dome of test_blender.py as the active object, n x n quads, its corners selected."""
    bpy.ops.mesh.primitive_grid_add(x_subdivisions=n, y_subdivisions=n, size=size)
    obj = bpy.context.active_object
    obj.name = name
    for v in obj.data.vertices:
        x, y = v.co.x / (size / 2), v.co.y / (size / 2)
        v.co.z = height * (1 - 0.5 * (x * x + y * y))
    vs = obj.data.vertices
    pick = lambda key: max(range(len(vs)), key=lambda i: key(vs[i].co))  # noqa: E731
    corners = [pick(lambda c: -c.x - c.y), pick(lambda c: c.x - c.y), pick(lambda c: c.x + c.y),
               pick(lambda c: -c.x + c.y)]
    bm = bmesh.new()
    bm.from_mesh(obj.data)
    bm.verts.ensure_lookup_table()
    for seq in (bm.verts, bm.edges, bm.faces):
        for e in seq:
            e.select = False
    for i in corners:
        bm.verts[i].select = True
        bm.select_history.add(bm.verts[i])
    bm.to_mesh(obj.data)
    bm.free()
    obj.data.update()
    return obj


def prepare_scene():
    """The dome of test_blender.py, corners selected, the sidebar open on the gridshell tab."""
    for obj in list(bpy.data.objects):
        bpy.data.objects.remove(obj, do_unlink=True)
    obj = add_dome("dome", 16)
    window, area, region = view3d()
    space = area.spaces.active
    space.show_region_ui = True
    space.shading.type = "SOLID"
    space.shading.color_type = "VERTEX"  # the active colour attribute
    with bpy.context.temp_override(window=window, area=area, region=region):
        bpy.ops.view3d.view_axis(type="FRONT")
        bpy.ops.view3d.view_orbit(angle=0.9, type="ORBITUP")
        bpy.ops.view3d.view_orbit(angle=0.5, type="ORBITLEFT")
        bpy.ops.view3d.view_all()
    settings = bpy.context.scene.gridshell
    settings.resolution = 400  # slow enough (about 1 s) for the progress to be seen
    settings.notches = "on"
    return obj


def steps(daemon):
    """The test as a generator: each yield gives Blender's UI loop a turn (seconds to wait)."""
    window = bpy.context.window_manager.windows[0]
    window.event_simulate(type="ESC", value="PRESS")  # the splash screen
    window.event_simulate(type="ESC", value="RELEASE")
    yield 0.5
    gridshell_blender.register()
    bpy.context.scene.gridshell.server = daemon.url
    prepare_scene()
    yield 0.5
    # The sidebar's gridshell tab: Blender 3.4 has no API to choose a tab, so click down the
    # tab strip at the sidebar's right edge (as a user does) until the panel draws.
    window, area, region = view3d()
    sidebar = [r for r in area.regions if r.type == "UI"][0]
    x = sidebar.x + sidebar.width - 8
    for k in range(60):
        y = sidebar.y + sidebar.height - 12 - 10 * k
        if y < sidebar.y or panel.DRAWS[0] > 0:
            break
        window.event_simulate(type="MOUSEMOVE", value="NOTHING", x=x, y=y)
        window.event_simulate(type="LEFTMOUSE", value="PRESS", x=x, y=y)
        window.event_simulate(type="LEFTMOUSE", value="RELEASE", x=x, y=y)
        yield 0.25
    window.event_simulate(type="MOUSEMOVE", value="NOTHING", x=region.x + 20, y=region.y + 20)
    check(panel.DRAWS[0] > 0, "the sidebar shows the gridshell panel")
    # Its first draw with the daemon's address read the daemon's description in the background
    # (the loop kept turning): the material list is the daemon's.
    started = time.monotonic()
    while gs.options.cached(daemon.url) is None and time.monotonic() - started < 30:
        yield 0.1
    description = gs.options.cached(daemon.url)
    names = [item[0] for item in described.material_items(bpy.context.scene.gridshell)]
    check(description is not None and names == description.material_names(),
          "the panel read the daemon's materials: %s" % ", ".join(names))
    check(described.status(bpy.context.scene.gridshell) is None, "no note about the materials")

    # Design from the UI while the daemon's only worker is busy with another client's long job:
    # the add-on's call waits in the daemon's queue until this test ends that job, which it does
    # only after Blender's loop has turned several times with the call pending. A blocking call
    # would stop the loop, the job would never end and the check would fail at its time limit.
    blocker = gs.plugin.BackgroundCall(
        lambda progress, cancel: gs.Client(daemon.url).design(
            gs.mesh_example("double-vault"), options={"resolution": 1000}, progress=progress, cancel=cancel
        )
    )
    started = time.monotonic()
    while blocker.progress is None and time.monotonic() - started < 60:
        yield 0.05
    check(invoke(bpy.ops.gridshell.design) == {"RUNNING_MODAL"}, "Design started as a modal operator")
    call = STATE["call"]
    turns = 0
    while turns < 5 and not call.done and time.monotonic() - started < 120:
        yield 0.05
        turns += 1
    check(turns == 5 and not call.done, "Blender's loop turned %d times while the call waited" % turns)
    blocker.cancel()
    texts, shot = set(), False
    while STATE["call"] is not None and time.monotonic() - started < 300:
        texts.add(STATE["text"])
        if not shot and "%" in STATE["text"] and " 0%" not in STATE["text"] and " 100%" not in STATE["text"]:
            screenshot("blender-progress.png")
            shot = True
        yield 0.05
    check(STATE["call"] is None, "Design finished")
    check(any("%" in t for t in texts), "progress shown: %s" % sorted(texts)[:3])
    top = bpy.data.collections.get(results.COLLECTION)
    check(top is not None and top.get("members", 0) > 8, "the design's objects are in the scene")
    yield 0.5

    # Simulate from the UI.
    check(invoke(bpy.ops.gridshell.simulate) == {"RUNNING_MODAL"}, "Simulate started as a modal operator")
    started = time.monotonic()
    while STATE["call"] is not None and time.monotonic() - started < 300:
        yield 0.1
    deployed = bpy.data.collections.get(results.DEPLOYED)
    check(deployed is not None and len(deployed.objects) == 1, "the deployed lamellas are in the scene")
    check("rms_with_notches" in top, "RMS on the collection")
    # The view a user would make: the deployed lamellas coloured by their deviation, the
    # members, and the flat layout beside them.
    dome = bpy.data.objects["dome"]
    dome.display_type = "WIRE"
    bpy.data.objects["gridshell patch"].hide_set(True)
    dome.select_set(False)
    shown = [o for name in (results.DEPLOYED, results.PLANAR) for o in bpy.data.collections[name].objects]
    points = [o.matrix_world @ v.co for o in shown if o.type == "MESH" for v in o.data.vertices]
    points += [o.matrix_world @ p.co.to_3d() for o in shown if o.type == "CURVE" for p in o.data.splines[0].points]
    lo = [min(p[k] for p in points) for k in range(3)]
    hi = [max(p[k] for p in points) for k in range(3)]
    window, area, region = view3d()
    view = area.spaces.active.region_3d
    view.view_location = [(a + b) / 2 for a, b in zip(lo, hi)]
    view.view_distance = 1.5 * max(b - a for a, b in zip(lo, hi))
    yield 1.0
    screenshot("blender-result.png")
    dome.display_type = "TEXTURED"
    dome.select_set(True)

    # Esc cancels a running call; the daemon stops the work; earlier results stay. A finer dome
    # at the finest maps: its design takes several seconds (7 s here), so the key reaches it
    # while it runs even when the software-rendered window delays the event by half a second.
    members_before = top["members"]
    add_dome("fine dome", 48)
    bpy.context.scene.gridshell.resolution = 1000
    since = len(daemon.log)
    check(invoke(bpy.ops.gridshell.design) == {"RUNNING_MODAL"}, "a slow Design started")
    started = time.monotonic()
    while not STATE["text"].startswith("distance maps") and time.monotonic() - started < 120:
        yield 0.05
    window.event_simulate(type="ESC", value="PRESS")
    window.event_simulate(type="ESC", value="RELEASE")
    pressed = time.monotonic()
    while STATE["call"] is not None and time.monotonic() - pressed < 60:
        yield 0.05
    check(STATE["call"] is None, "the call ended %.2f s after Esc" % (time.monotonic() - pressed))
    cancelled = daemon.wait_for(
        lambda e: e.get("method") == "Design" and e.get("status") == "CANCELLED", 30, since=since
    )
    check(cancelled is not None, "the daemon cancelled the work (%s)" % (cancelled or {}).get("message"))
    check(top.get("members") == members_before, "the earlier results are kept")


def main():
    daemon = T.Daemon("--workers", "1")  # one job at a time: see the first Design below
    runner = steps(daemon)
    deadline = time.monotonic() + LIMIT

    def finish(ok):
        daemon.stop()
        failed = sum(1 for passed, _ in checks if not passed) + (0 if ok else 1)
        print("blender ui: %d passed, %d failed" % (len(checks) - failed + (0 if ok else 1), failed))
        sys.stdout.flush()
        os._exit(0 if failed == 0 else 1)

    def tick():
        try:
            if time.monotonic() > deadline:
                print("FAILED: took longer than %d s" % LIMIT)
                finish(False)
            return next(runner)
        except StopIteration:
            finish(True)
        except Exception:
            traceback.print_exc()
            finish(False)
        return None

    bpy.app.timers.register(tick, first_interval=1.0)


main()
