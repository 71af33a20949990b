# SPDX-License-Identifier: GPL-3.0-or-later
"""The FreeCAD workbench in FreeCAD's real GUI (a window under Xvfb), installed from
build/gridshell_freecad.zip into a temporary user folder as a user installs it, against a real
gridshelld: the workbench loads, a Design from the task panel with four picked points runs without
blocking FreeCAD (its event loop keeps running), shows progress and builds the result objects, its
spin boxes' ranges the daemon's; a Design + Simulate run with a site's material (the daemon runs
with a material library, GRIDSHELL_MATERIALS), chosen from the panel's material list, which is the
daemon's description; the panel's Cancel stops the daemon's work; Layout and Build all patches on
knet1 from their panels (one coloured Mesh per patch, one group per built patch). With
GRIDSHELL_SCREENSHOTS=DIR it also saves the docs' screenshots. Run by scripts/test-cad.sh:

    FREECAD_USER_HOME=TMP (with TMP/Mod/gridshell unzipped) QTWEBENGINE_DISABLE_SANDBOX=1 \\
        xvfb-run -a -s "-screen 0 1440x900x24" freecad tests/cad/test_freecad_gui.py

The script ends FreeCAD itself: exit code 0 when every check passed, 1 otherwise.
"""

import json
import os
import re
import shutil
import sys
import tempfile
import time
import traceback

import FreeCAD
import FreeCADGui
import Mesh
from FreeCAD import Vector
from PySide2 import QtCore, QtGui, QtWidgets

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(ROOT, "tests", "python"))

import gridshell_testing as T  # noqa: E402,N812

LIMIT = 600
SHOTS = os.environ.get("GRIDSHELL_SCREENSHOTS", "")
checks = []


def check(condition, what):
    checks.append((bool(condition), what))
    print("%s: %s" % ("ok" if condition else "FAILED", what), flush=True)


def screenshot(name):
    """The main window as the X server shows it (a widget grab would miss the 3D view's GL)."""
    if not SHOTS:
        return
    os.makedirs(SHOTS, exist_ok=True)
    window = FreeCADGui.getMainWindow()
    screen = QtGui.QGuiApplication.primaryScreen()
    corner = window.mapToGlobal(QtCore.QPoint(0, 0))
    image = screen.grabWindow(0, corner.x(), corner.y(), window.width(), window.height())
    image.save(os.path.join(SHOTS, name))
    print("screenshot %s" % name, flush=True)


class Ticks:
    """An independent 20 ms timer on FreeCAD's event loop: its ticks during a call show that
    nothing blocked the loop."""

    def __init__(self):
        self.times = []
        self.timer = QtCore.QTimer()
        self.timer.setInterval(20)
        self.timer.timeout.connect(lambda: self.times.append(time.monotonic()))
        self.timer.start()


def dome(doc, n=16, size=100.0, height=25.0, name="dome"):
    """A dome as a Mesh object (mm), and its four corner points."""
    positions = []
    for j in range(n + 1):
        for i in range(n + 1):
            u, v = 2 * i / n - 1, 2 * j / n - 1
            positions.append(Vector(size * u / 2, size * v / 2, height * (1 - 0.5 * (u * u + v * v))))
    triangles = []
    for j in range(n):
        for i in range(n):
            a = j * (n + 1) + i
            for t in ((a, a + 1, a + n + 2), (a, a + n + 2, a + n + 1)):
                triangles += [positions[k] for k in t]
    obj = doc.addObject("Mesh::Feature", name)
    obj.Mesh = Mesh.Mesh(triangles)
    doc.recompute()
    corners = [positions[0], positions[n], positions[-1], positions[n * (n + 1)]]
    return obj, corners


def wait_for_call(panel, limit):
    """Yields while the panel's call runs; returns the number of event loop turns it took."""
    turns, started = 0, time.monotonic()
    while panel.call is not None and time.monotonic() - started < limit:
        turns += 1
        yield 0.05
    return turns


def steps(daemon):
    import gridshell_freecad
    from gridshell_freecad import gui
    from gridshell_freecad.remote import gs

    home = os.environ.get("FREECAD_USER_HOME", "")
    check("GridshellWorkbench" in FreeCADGui.listWorkbenches(), "the workbench is listed")
    check(home and gridshell_freecad.__file__.startswith(os.path.join(home, "Mod")),
          "loaded from the installed zip: %s" % gridshell_freecad.__file__)
    check(os.path.dirname(gs.__file__) == os.path.join(os.path.dirname(gridshell_freecad.__file__), "gridshell_client"),
          "with the client it carries: %s" % gs.__file__)
    FreeCADGui.activateWorkbench("GridshellWorkbench")
    window = FreeCADGui.getMainWindow()
    combo = window.findChild(QtWidgets.QDockWidget, "Combo View")
    if combo is not None:
        window.resizeDocks([combo], [430], QtCore.Qt.Horizontal)
    doc = FreeCAD.newDocument("gridshell")
    obj, corners = dome(doc)
    view = FreeCADGui.ActiveDocument.ActiveView
    view.viewIsometric()
    view.fitAll()
    yield 0.5
    p = FreeCAD.ParamGet(gui.core.PARAMETERS)
    p.SetString("server", daemon.url)
    p.SetInt("resolution", 400)  # a call long enough (about 1 s on a quiet machine) to watch
    p.SetString("notches", "on")

    # Four picked points on the mesh (a facet each, the point in global coordinates).
    FreeCADGui.Selection.clearSelection()
    for k, c in enumerate(corners):
        FreeCADGui.Selection.addSelection(doc.Name, obj.Name, "Facet%d" % k, c.x, c.y, c.z)
    FreeCADGui.runCommand("Gridshell_Design")
    yield 0.5
    panel = gui.TaskPanel.current
    check(panel is not None and panel.points is not None and len(panel.points) == 4,
          "the panel took the 4 picked points as corners")
    started = time.monotonic()
    while panel.description is None and time.monotonic() - started < 30:
        yield 0.05
    description = panel.description
    spans = {name: (box.minimum(), box.maximum()) for name, box in panel.fields.items()}
    check(description is not None
          and all(spans[name][1] == description.option("design", name).get("maximum", gui.core.UNBOUNDED)
                  for name in spans),
          "the spin boxes' ranges are the daemon's: %s" % spans)
    ticks = Ticks()
    started = time.monotonic()
    panel.accept()  # the OK button
    check(panel.call is not None, "the call runs in the background")
    shot = False
    shown = []  # the panel's status lines, as the event loop drew them during the call
    while panel.call is not None and time.monotonic() - started < 300:  # a bound, not a speed
        if not shown or shown[-1] != panel.status.text():
            shown.append(panel.status.text())
        if not shot and panel.status.text().startswith("distance maps") and panel.progress.value() > 300:
            screenshot("freecad-progress.png")
            shot = True
        yield 0.05
    ended = time.monotonic()
    during = len([t for t in ticks.times if started <= t <= ended])
    # A call blocking the GUI would let no timer tick and no progress line through until it
    # ended (accept() would return with the call over): the loop ran while the call did if the
    # independent timer ticked and the panel drew the call's progress meanwhile.
    progress = [line for line in shown if re.match(r".*? \d+%", line)]
    check(during >= 1 and progress,
          "FreeCAD's event loop kept running: %d timer ticks and %d progress lines (%s) during the call"
          % (during, len(progress), "; ".join(progress[:3])))
    top = doc.getObject("gridshell")
    check(top is not None and top.Members > 8, "the design's objects are in the document")
    members = doc.getObject("gridshell_members")
    check(members is not None and len(members.Group) == top.Members, "one wire per member")
    yield 0.5

    # Design + Simulate from the Run panel.
    FreeCADGui.Selection.clearSelection()
    FreeCADGui.Selection.addSelection(doc.Name, obj.Name)
    FreeCADGui.runCommand("Gridshell_Run")
    yield 0.5
    panel = gui.TaskPanel.current
    # The material list is the daemon's description: its built-in materials (as the CLI lists
    # them), then the site's; choose the site's.
    site = T.SITE_MATERIAL["name"]
    started = time.monotonic()
    while panel.description is None and time.monotonic() - started < 30:
        yield 0.05
    listed = [panel.material.itemData(k) for k in range(panel.material.count())]
    cli = T.cli("options", "--json")
    built_in = [m["name"] for m in json.loads(cli.stdout)["materials"] if not m.get("site")] if cli.returncode == 0 else []
    check(built_in and listed == built_in + [site], "the panel's materials are the daemon's: %s" % ", ".join(listed))
    panel.material.setCurrentIndex(panel.material.findData(site))
    check(panel.material.currentText() == "Test larch (site)", "chose %s" % panel.material.currentText())
    panel.accept()
    started = time.monotonic()
    while panel.call is not None and time.monotonic() - started < 300:
        yield 0.1
    check(top.Material == site, "simulated with the site's material: %s" % top.Material)
    deployed = doc.getObject("gridshell_deployed")
    check(deployed is not None and len(deployed.Group) == 1, "the deployed lamellas are in the document")
    check("RmsWithNotches" in top.PropertiesList and top.RmsWithNotches > 0, "RMS on the group")
    obj.ViewObject.Visibility = False
    doc.getObject("gridshell_patch").ViewObject.Visibility = False
    view.viewIsometric()
    view.fitAll()
    FreeCADGui.Selection.clearSelection()
    FreeCADGui.Selection.addSelection(doc.Name, top.Name)
    yield 1.0
    screenshot("freecad-result.png")

    # Cancel while the design runs: the daemon stops the work. A finer dome at the finest maps,
    # whose design takes several seconds, so that Cancel reaches it while it runs.
    fine, _ = dome(doc, n=48, name="fine_dome")
    FreeCADGui.Selection.clearSelection()
    FreeCADGui.Selection.addSelection(doc.Name, fine.Name)
    p.SetInt("resolution", 1000)
    since = len(daemon.log)
    FreeCADGui.runCommand("Gridshell_Design")
    yield 0.5
    panel = gui.TaskPanel.current
    panel.accept()
    started = time.monotonic()
    while "%" not in panel.status.text() and time.monotonic() - started < 120:
        yield 0.05
    panel.reject()  # the Cancel button
    pressed = time.monotonic()
    while panel.call is not None and time.monotonic() - pressed < 60:
        yield 0.05
    check(panel.call is None, "the call ended %.2f s after Cancel" % (time.monotonic() - pressed))
    check("cancelled" in panel.status.text(), "the panel says: %s" % panel.status.text())
    cancelled = daemon.wait_for(
        lambda e: e.get("method") == "Design" and e.get("status") == "CANCELLED", 30, since=since
    )
    check(cancelled is not None, "the daemon cancelled the work")
    FreeCADGui.Control.closeDialog()
    yield 0.5

    # Several patches: Layout, then Build all patches, from their panels, on knet1.
    knet1 = doc.addObject("Mesh::Feature", "knet1")
    knet1.Mesh = Mesh.read(os.path.join(T.MESHES, "knet1.obj"))
    doc.recompute()
    FreeCADGui.Selection.clearSelection()
    FreeCADGui.Selection.addSelection(doc.Name, knet1.Name)
    p.SetInt("resolution", 24)
    p.SetString("layout", "auto")
    FreeCADGui.runCommand("Gridshell_Layout")
    yield 0.5
    panel = gui.TaskPanel.current
    check(panel is not None and panel.mode == "layout", "the Layout panel opened")
    started = time.monotonic()
    while panel.description is None and time.monotonic() - started < 30:
        yield 0.05
    box = panel.layout_fields["max_patches"]
    option = panel.description.option("layout", "max_patches") if panel.description else None
    check(option is not None and box.maximum() == option["maximum"],
          "Patches at most takes the daemon's range: %d to %d" % (box.minimum(), box.maximum()))
    panel.accept()
    started = time.monotonic()
    while panel.call is not None and time.monotonic() - started < 120:
        yield 0.05
    group = doc.getObject("gridshell_layout")
    patches = [o for o in group.Group if o.TypeId == "Mesh::Feature"] if group is not None else []
    check(group is not None and len(patches) == group.Patches == 20,
          "one Mesh per patch: %d" % len(patches))
    colours = {tuple(o.ViewObject.ShapeColor[:3]) for o in patches}
    check(len(colours) == len(patches), "each patch in its own colour (%d colours)" % len(colours))
    check(group is not None and abs(group.Coverage - 0.954) < 0.001, "coverage %.4f" % (group.Coverage if group else 0))
    p.SetInt("members_u", 3)
    p.SetInt("members_v", 3)
    p.SetString("layout", "last")
    FreeCADGui.Selection.clearSelection()
    FreeCADGui.Selection.addSelection(doc.Name, knet1.Name)
    FreeCADGui.runCommand("Gridshell_BuildLayout")
    yield 0.5
    panel = gui.TaskPanel.current
    check(panel is not None and panel.mode == "build" and panel.layout_source.currentData() == "last",
          "the Build all patches panel opened, with the last layout")
    panel.accept()
    started = time.monotonic()
    while panel.call is not None and time.monotonic() - started < 300:
        yield 0.1
    parent = doc.getObject("gridshell_patches")
    groups = [o for o in parent.Group if o.TypeId == "App::DocumentObjectGroup"] if parent is not None else []
    check(parent is not None and len(groups) == parent.PatchesBuilt > 0,
          "one group per built patch: %d" % len(groups))
    check(parent is not None and parent.RmsWithNotches == json.loads(parent.DeploymentJson)["rms_with_notches"],
          "the whole's RMS on the group")
    p.SetInt("members_u", 0)
    p.SetInt("members_v", 0)
    p.SetString("layout", "auto")


def main():
    library = tempfile.mkdtemp(prefix="gridshell-freecad-gui-")
    daemon = T.Daemon(env=T.material_library(library))
    runner = steps(daemon)
    deadline = time.monotonic() + LIMIT
    timer = QtCore.QTimer()
    timer.setSingleShot(True)

    def finish(ok):
        daemon.stop()
        shutil.rmtree(library, ignore_errors=True)
        failed = sum(1 for passed, _ in checks if not passed) + (0 if ok else 1)
        print("freecad gui: %d passed, %d failed" % (len(checks) - failed + (0 if ok else 1), failed), flush=True)
        os._exit(0 if failed == 0 else 1)

    def tick():
        try:
            if time.monotonic() > deadline:
                print("FAILED: took longer than %d s" % LIMIT, flush=True)
                finish(False)
            wait = next(runner)
            timer.start(int(1000 * wait))
        except StopIteration:
            finish(True)
        except Exception:
            traceback.print_exc()
            finish(False)

    timer.timeout.connect(tick)
    timer.start(2000)
    main.timer = timer  # kept alive


main()
