# SPDX-License-Identifier: GPL-3.0-or-later
"""Tests of the FreeCAD workbench's non-GUI part (client/freecad/gridshell_freecad/core.py) in real
FreeCAD against a real gridshelld on loopback (started and stopped here):

    freecadcmd tests/cad/test_freecad.py

(freecadcmd exits 0 after an uncaught exception, so this script exits 1 itself on a failure.)
A dome Mesh object with a Placement, corners as vertices and as picked points, and a shared mesh
read by FreeCAD's own Mesh module go through design and simulation; the tests check the document
objects (member wires as in design.json, the global frame, the deployed lamellas and their
deviation, RMS as the daemon computes it), design.json byte for byte as the CLI writes it, progress
and cancellation, and the error messages. Against a daemon with a site's material library
(GRIDSHELL_MATERIALS): the material choices are the daemon's description (built-in and the
site's), a run with the site's material simulates with it, and the settings' initial values and
the spin boxes' ranges are the described ones. Layouts of several patches (issue 35): knet1's
automatic layout as one Mesh per patch, its coverage as the daemon reports it; every patch built,
one group each, the whole's RMS as the call answered it; a layout file; errors naming the field.
"""

import json
import os
import sys
import tempfile
import threading
import time
import traceback
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(ROOT, "tests", "python"))
sys.path.insert(0, os.path.join(ROOT, "client", "freecad"))

import FreeCAD  # noqa: E402
import Mesh  # noqa: E402
import Part  # noqa: E402
from FreeCAD import Placement, Rotation, Vector  # noqa: E402

import gridshell_testing as T  # noqa: E402,N812

from gridshell_freecad import core  # noqa: E402
from gridshell_freecad.remote import gs  # noqa: E402

RESOLUTION = 24


def dome_arrays(n=12, size=10.0, height=2.5):
    positions, indices = [], []
    for j in range(n + 1):
        for i in range(n + 1):
            x, y = size * (i / n - 0.5), size * (j / n - 0.5)
            u, v = 2 * i / n - 1, 2 * j / n - 1
            positions += [x, y, height * (1 - 0.5 * (u * u + v * v))]
    for j in range(n):
        for i in range(n):
            a = j * (n + 1) + i
            indices += [a, a + 1, a + n + 2, a, a + n + 2, a + n + 1]
    return positions, indices, [0, n, (n + 1) * (n + 1) - 1, n * (n + 1)]


def mesh_feature(doc, name, positions, indices, placement=None):
    points = [Vector(*positions[3 * i : 3 * i + 3]) for i in indices]
    obj = doc.addObject("Mesh::Feature", name)
    obj.Label = name
    obj.Mesh = Mesh.Mesh(points)
    if placement is not None:
        obj.Placement = placement
    doc.recompute()
    return obj


def members_of(doc, group):
    return [o for o in doc.getObject(group.replace(" ", "_")).Group if o.TypeId == "Part::Feature"]


class FreeCADWorkbenchTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.daemon = T.Daemon()
        cls.client = gs.Client(cls.daemon.url)
        cls.tmp = tempfile.mkdtemp(prefix="gridshell-freecad-")

    @classmethod
    def tearDownClass(cls):
        cls.daemon.stop()

    def setUp(self):
        self.doc = FreeCAD.newDocument("gridshell_test")
        self.settings = core.Settings(server=self.daemon.url, resolution=RESOLUTION, notches="on")

    def tearDown(self):
        FreeCAD.closeDocument(self.doc.Name)

    def test_dome_design_then_simulate(self):
        positions, indices, corners = dome_arrays()
        placement = Placement(Vector(3, -2, 1.5), Rotation(Vector(0.3, -0.2, 0.9), 40))
        obj = mesh_feature(self.doc, "dome.obj", positions, indices, placement)
        # FreeCAD keeps the points in first-use order: corners by index into its own points.
        points, _ = obj.Mesh.Topology
        want = [placement.multVec(Vector(*positions[3 * c : 3 * c + 3])) for c in corners]
        index = [min(range(len(points)), key=lambda k: (points[k] - w).Length) for w in want]
        stages = []
        top = core.design(self.doc, obj, self.settings, corners=index, progress=lambda p: stages.append(p.stage))
        self.assertIn("distance maps", stages)
        design = json.loads(top.DesignJson)
        self.assertEqual(len(members_of(self.doc, core.MEMBERS)), len(design["members"]))
        self.assertEqual(len(members_of(self.doc, core.PLANAR)), len(design["members"]))
        self.assertEqual(len(members_of(self.doc, core.ANCHORS)), len(design["anchors"]))
        self.assertEqual(top.Members, len(design["members"]))
        self.assertEqual(top.AlphaBarRadians, design["alpha_bar"])
        # Member wires run through the design's surface points; the patch corners are the
        # object's corner vertices with its Placement applied.
        member = design["members"][2]
        wire = [o for o in members_of(self.doc, core.MEMBERS)
                if o.Family == member["family"] and o.Index == member["index"]][0]
        self.assertEqual(len(wire.Shape.Vertexes), len(member["surface"]))
        for vertex, p in zip(wire.Shape.Vertexes, member["surface"]):
            self.assertLess((vertex.Point - Vector(*p)).Length, 1e-9 * 20)
        patch = design["patch"]
        for k in range(4):
            got = Vector(*patch["vertices"][patch["corners"][k]])
            self.assertLess((got - want[k]).Length, 1e-5)  # FreeCAD stores float32 points
        # The CLI on the same arrays (written with 17 digits) writes the same design.json.
        mesh, _ = core.target(obj, index)
        path = os.path.join(self.tmp, "dome.obj")
        T.write_obj(path, mesh["positions"], mesh["indices"])
        out = os.path.join(self.tmp, "dome-cli")
        cli = T.cli("design", path, "--corners", ",".join(map(str, index)), "--resolution", RESOLUTION,
                    "--out", out, "--quiet")
        self.assertEqual(cli.returncode, 0, cli.stderr)
        with open(os.path.join(out, "design.json"), "rb") as f:
            self.assertEqual(f.read(), top.DesignJson.encode("utf-8"))

        deployed = core.simulate(self.doc, self.settings)
        answer = self.client.simulate(top.DesignJson, self.settings.simulation_options(), design_name="design.json")
        deployment = answer["deployment"]
        self.assertEqual(top.RmsWithNotches, deployment["rms_with_notches"])
        self.assertNotIn("RmsWithoutNotches", top.PropertiesList)
        lamellas = [o for o in deployed.Group if o.TypeId == "Mesh::Feature"]
        self.assertEqual(len(lamellas), 1)
        lamella = lamellas[0]
        deviation = [d for rod in deployment["rods"] for d in rod["deviation"] for _ in range(4)]
        self.assertEqual(len(lamella.Deviation), len(deviation))
        for a, b in zip(lamella.Deviation, deviation):
            self.assertAlmostEqual(a, b, delta=1e-12 + 1e-12 * abs(b))
        self.assertEqual(lamella.Rms, deployment["with_notches"]["rms"])
        self.assertGreater(lamella.Mesh.CountFacets, 0)
        self.assertEqual(answer["deployment"]["options"]["unit"], "mm")

    def test_picked_points_and_cancel(self):
        positions, indices, corners = dome_arrays(n=10)
        obj = mesh_feature(self.doc, "dome", positions, indices)
        # Picked a little off the surface, along the normal of the corner's faces: the daemon
        # snaps each point to the closest surface point, the corner vertex itself.
        exact = [Vector(*positions[3 * c : 3 * c + 3]) for c in corners]
        picked = []
        for c, p in zip(corners, exact):
            normal = Vector()
            for k in range(0, len(indices), 3):
                if c in indices[k : k + 3]:
                    a, b, d = (Vector(*positions[3 * i : 3 * i + 3]) for i in indices[k : k + 3])
                    normal += (b - a).cross(d - a).normalize()
            picked.append(p + normal.normalize() * 0.05)
        top = core.design(self.doc, obj, self.settings, corners=picked)
        design = json.loads(top.DesignJson)
        patch = design["patch"]
        for k in range(4):
            got = Vector(*patch["vertices"][patch["corners"][k]])
            self.assertLess((got - exact[k]).Length, 1e-6)
        self.assertIn(";", design["options"]["corners"])  # recorded as points
        # Cancel from another thread while the design runs.
        cancel = gs.Cancel()
        seen = threading.Event()
        outcome = {}
        slow = core.Settings(server=self.daemon.url, resolution=1000)

        def work():
            try:
                core.design(self.doc, obj, slow, progress=lambda p: seen.set(), cancel=cancel)
                outcome["done"] = True
            except gs.GridshellError as e:
                outcome["error"] = e

        since = len(self.daemon.log)
        thread = threading.Thread(target=work)
        thread.start()
        self.assertTrue(seen.wait(60))
        cancel.cancel()
        thread.join(30)
        self.assertIsInstance(outcome.get("error"), gs.Cancelled, outcome)
        self.assertIsNotNone(
            self.daemon.wait_for(
                lambda e: e.get("method") == "Design" and e.get("status") == "CANCELLED", 30, since=since
            )
        )
        # The earlier results are still there.
        self.assertEqual(json.loads(top.DesignJson), design)

    def test_shared_mesh_read_by_freecad_and_run(self):
        path = os.path.join(T.MESHES, "knet1.obj")
        self.assertTrue(os.path.exists(path), path)
        obj = self.doc.addObject("Mesh::Feature", "knet1")
        obj.Mesh = Mesh.read(path)
        self.doc.recompute()
        self.settings.notches = "both"
        top = core.run(self.doc, obj, self.settings)
        design = json.loads(top.DesignJson)
        self.assertEqual(design["options"]["corners"], "auto")
        self.assertEqual(len(members_of(self.doc, core.MEMBERS)), len(design["members"]))
        mesh, _ = core.target(obj)
        answer = self.client.run(mesh, None, self.settings.design_options(), self.settings.simulation_options())
        self.assertEqual(answer["design"]["design"], design)
        deployment = answer["simulation"]["deployment"]
        self.assertEqual(top.RmsWithNotches, deployment["rms_with_notches"])
        self.assertEqual(top.RmsWithoutNotches, deployment["rms_without_notches"])
        deployed = self.doc.getObject(core.DEPLOYED.replace(" ", "_"))
        self.assertEqual(sorted(o.Notches for o in deployed.Group), [False, True])

    def test_inner_anchors_found_by_the_simulation(self):
        """waves-bump held at its boundary snaps into a dome: "Find inner anchors" adds one."""
        loaded = self.client.load(gs.mesh_example("waves-bump"))
        positions, indices = loaded["mesh"]["positions"], loaded["mesh"]["indices"]
        obj = mesh_feature(self.doc, "waves_bump", positions, indices)
        picked = [Vector(*positions[3 * v : 3 * v + 3]) for v in loaded["example_corners"]["vertices"]]
        self.settings.resolution = 100
        self.settings.auto_anchors = True
        self.assertEqual(self.settings.simulation_options()["interior_anchors"], "auto")
        top = core.run(self.doc, obj, self.settings, corners=picked)
        answer = self.client.simulate(top.DesignJson, self.settings.simulation_options(), design_name="design.json")
        deployment = answer["deployment"]
        added = deployment["added_anchors"]
        self.assertGreaterEqual(len(added), 1, deployment["anchor_trial_rms"])
        self.assertEqual(top.RmsWithNotches, deployment["rms_with_notches"])
        self.assertEqual(top.AddedAnchors, len(added))
        self.assertEqual(list(top.AnchorTrialRms), deployment["anchor_trial_rms"])
        vertices = [o for o in members_of(self.doc, core.ANCHORS) if "Added" in o.PropertiesList and o.Added]
        self.assertEqual(sorted(o.Label for o in vertices), sorted("added anchor g%d h%d" % (a["g"], a["h"]) for a in added))
        for o in vertices:
            a = next(a for a in added if o.Label == "added anchor g%d h%d" % (a["g"], a["h"]))
            self.assertLess((o.Shape.Vertexes[0].Point - Vector(*a["position"])).Length, 1e-9 * 100)
        # The setting is kept with the others (FreeCAD's parameters), as a bool.
        self.settings.save()
        self.assertIs(core.Settings.load().auto_anchors, True)
        self.settings.auto_anchors = False
        self.settings.save()
        # Simulating again without the search removes them.
        core.simulate(self.doc, self.settings)
        self.assertEqual([o for o in members_of(self.doc, core.ANCHORS) if "Added" in o.PropertiesList and o.Added], [])
        self.assertEqual(top.AddedAnchors, 0)

    def test_errors(self):
        positions, indices, corners = dome_arrays(n=8, height=0.0)
        obj = mesh_feature(self.doc, "flat", positions, indices)
        box = self.doc.addObject("Part::Box", "Box")
        self.doc.recompute()
        with self.assertRaises(core.InputError) as caught:
            core.design(self.doc, box, self.settings)
        self.assertIn("select a Mesh object", core.error_message(caught.exception, self.settings))
        with self.assertRaises(core.InputError) as caught:
            core.design(self.doc, obj, self.settings, corners=[Vector(0, 0, 0)] * 3)
        self.assertIn("pick 4 corner points on flat", str(caught.exception))
        with self.assertRaises(core.InputError):
            core.simulate(self.doc, self.settings)  # no design yet
        # A dart: a reflex corner, infeasible.
        dart = [Vector(-5, -5, 0), Vector(5, -5, 0), Vector(0, -1, 0), Vector(-5, 5, 0)]
        with self.assertRaises(gs.Infeasible) as caught:
            core.design(self.doc, obj, self.settings, corners=dart)
        text = core.error_message(caught.exception, self.settings, "flat")
        self.assertRegex(text, "^gridshell: infeasible design: .*criterion iv")
        # An option out of range names the panel's field.
        wide = core.Settings(server=self.daemon.url, resolution=RESOLUTION, lamella_width=1e9)
        with self.assertRaises(gs.InvalidInput) as caught:
            core.design(self.doc, obj, wide)
        self.assertIn("Lamella width (options.lamella_width)", core.error_message(caught.exception, wide))
        with T.refusing_port() as port:
            away = core.Settings(server="http://127.0.0.1:%d" % port)
            with self.assertRaises(gs.Unavailable) as caught:
                core.design(self.doc, obj, away)
        self.assertIn("cannot reach the daemon at http://127.0.0.1", core.error_message(caught.exception, away))
        self.assertEqual(self.client.health(), "SERVING")


class FreeCADMaterialsTest(unittest.TestCase):
    """The material choices and the option ranges from the daemon's description."""

    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.mkdtemp(prefix="gridshell-freecad-materials-")
        cls.daemon = T.Daemon(env=T.material_library(cls.tmp))
        cls.client = gs.Client(cls.daemon.url)

    @classmethod
    def tearDownClass(cls):
        cls.daemon.stop()

    def setUp(self):
        self.doc = FreeCAD.newDocument("gridshell_materials")
        self.settings = core.Settings(server=self.daemon.url, resolution=RESOLUTION, notches="on")

    def tearDown(self):
        FreeCAD.closeDocument(self.doc.Name)

    def test_materials_from_the_description_and_a_run_with_the_sites(self):
        site = T.SITE_MATERIAL["name"]
        gs.options.forget(self.daemon.url)
        self.assertIsNone(core.cached_description(self.settings))
        # Before the description is read: the daemon's default alone (nothing sent), and a
        # chosen material kept.
        self.assertEqual([name for name, _ in core.material_choices(None)], [""])
        self.assertEqual([name for name, _ in core.material_choices(None, site)], ["", site])
        self.assertNotIn("material", self.settings.simulation_options())
        description = core.describe(self.settings)
        self.assertIs(core.cached_description(self.settings), description)
        choices = core.material_choices(description)
        cli = T.cli("options", "--json")
        self.assertEqual(cli.returncode, 0, cli.stderr)
        built_in = [m["name"] for m in json.loads(cli.stdout)["materials"] if not m.get("site")]
        self.assertEqual([name for name, _ in choices], built_in + [site])
        self.assertEqual(dict(choices)[site], "Test larch (site)")
        self.assertEqual(description.default_material, built_in[0])

        # Design + Simulate with the site's material: the deployment used it.
        positions, indices, corners = dome_arrays(n=8)
        obj = mesh_feature(self.doc, "larch_dome", positions, indices)
        self.settings.material = site
        self.assertEqual(self.settings.simulation_options()["material"], site)
        top = core.run(self.doc, obj, self.settings)
        self.assertEqual(top.Material, site)
        answer = self.client.simulate(top.DesignJson, self.settings.simulation_options(), design_name="design.json")
        options = answer["deployment"]["options"]
        self.assertEqual(options["material"], site)
        self.assertEqual(options["shear_modulus"], T.SITE_MATERIAL["shear_modulus"])
        self.assertEqual(top.RmsWithNotches, answer["deployment"]["rms_with_notches"])
        # None chosen: the daemon's default (the description's first).
        self.settings.material = ""
        core.simulate(self.doc, self.settings)
        self.assertEqual(top.Material, description.default_material)

    def test_initial_values_and_ranges_are_the_described_ones(self):
        description = core.describe(self.settings)
        fields = core.Settings.FIELDS
        for name in ("members_u", "members_v", "lamella_width", "lamella_thickness", "resolution",
                     "interior_anchors"):
            self.assertEqual(fields[name], description.default("design", name), name)
            option = description.option("design", name)
            low, high = core.spin_range(description, "design", name)
            self.assertEqual(high, option.get("maximum", core.UNBOUNDED), name)
            self.assertEqual(low, 0, name)  # 0 is allowed (automatic) or the minimum
            self.assertIsNone(description.check("design", name, fields[name]), name)
        self.assertEqual(fields["notches"], description.default("simulation", "notches"))
        self.assertEqual(fields["alpha"], description.default("design", "alpha"))
        self.assertIn(fields["unit"], description.length_units)
        self.assertIsNone(core.spin_range(description, "design", "alpha"))  # text: no range
        self.assertIsNone(core.spin_range(description, "design", "no_such_option"))
        self.assertIsNone(core.spin_range(None, "design", "resolution"))
        # What the settings send passes the description's check.
        for name, value in core.Settings(server=self.daemon.url).design_options().items():
            self.assertIsNone(description.check("design", name, value), name)


class FreeCADLayoutTest(unittest.TestCase):
    """Several patches joined at seams: Layout and Build all patches."""

    @classmethod
    def setUpClass(cls):
        cls.daemon = T.Daemon()
        cls.client = gs.Client(cls.daemon.url)
        cls.tmp = tempfile.mkdtemp(prefix="gridshell-freecad-layout-")

    @classmethod
    def tearDownClass(cls):
        cls.daemon.stop()

    def setUp(self):
        self.doc = FreeCAD.newDocument("gridshell_layout")
        self.settings = core.Settings(server=self.daemon.url, resolution=RESOLUTION, notches="on")
        self.knet1 = self.doc.addObject("Mesh::Feature", "knet1")
        self.knet1.Mesh = Mesh.read(os.path.join(T.MESHES, "knet1.obj"))
        self.doc.recompute()

    def tearDown(self):
        FreeCAD.closeDocument(self.doc.Name)

    def test_automatic_layout_then_build_all_patches(self):
        self.assertEqual(self.settings.automatic_options(), {"max_patches": 36, "coverage_goal": 0.95})
        group = core.layout(self.doc, self.knet1, self.settings)
        mesh = core.layout_target(self.knet1)
        self.assertEqual(len(mesh["positions"]), 3 * 441)
        report = self.client.layout(mesh, automatic=self.settings.automatic_options())["report"]
        patches = [o for o in group.Group if o.TypeId == "Mesh::Feature"]
        self.assertEqual(len(patches), len(report["patches"]))
        self.assertEqual(group.Patches, len(report["patches"]))
        self.assertEqual(len(report["patches"]), 20)  # knet1: 5 x 4 (docs/multi-patch.md)
        self.assertEqual(group.Coverage, report["coverage"])
        self.assertAlmostEqual(group.Coverage, 0.954, delta=0.001)
        self.assertEqual(group.AutomaticGrid, "5 x 4")
        self.assertEqual(sorted(o.Label for o in patches), sorted(p["name"] for p in report["patches"]))
        self.assertEqual(len({tuple(o.Colour) for o in patches}), len(patches))  # distinct colours
        for o in patches:
            self.assertGreater(o.Mesh.CountFacets, 0)
        self.assertAlmostEqual(group.UncoveredArea, sum(u["area"] for u in report["uncovered"]), delta=1e-9)
        self.assertTrue(any(u.startswith("outside the patches") for u in group.Uncovered))
        self.assertEqual(json.loads(group.LayoutJson), report["layout"])

        # Every patch built with the layout found, small grids: one group per built patch.
        s = self.settings
        s.layout = "last"
        s.members_u = s.members_v = 3
        parent = core.build_layout(self.doc, self.knet1, s)
        deployment = json.loads(parent.DeploymentJson)  # the call's own answer
        built = [p["name"] for p in deployment["patches"]]
        self.assertGreater(len(built), 0)
        groups = [o for o in parent.Group if o.TypeId == "App::DocumentObjectGroup"]
        self.assertEqual(sorted(g.Label for g in groups), sorted(core.PATCH_PREFIX + n for n in built))
        self.assertEqual(parent.PatchesBuilt, len(built))
        self.assertEqual(parent.PatchesBuilt + len(parent.FailedPatches), 20)
        self.assertEqual(parent.RmsWithNotches, deployment["rms_with_notches"])
        self.assertEqual(parent.RmsWithNotchesPercent, 100 * deployment["rms_with_notches"] / deployment["diagonal"])
        self.assertNotIn("RmsWithoutNotches", parent.PropertiesList)  # notches "on"
        self.assertEqual(parent.Converged, deployment["converged"])
        self.assertEqual(parent.MaxSeamGap, deployment["max_seam_gap"])
        self.assertGreater(parent.SeamBolts, 0)
        # The whole was joined: its seams closed, the bolts' force and the patches alone kept.
        self.assertTrue(parent.SeamsJoined)
        self.assertEqual(parent.MaxBoltForce, deployment["max_bolt_force"])
        self.assertEqual(parent.RmsBeforeJoining, deployment["rms_before_joining"])
        for g in groups:
            lamellas = [o for o in g.Group if o.TypeId == "Mesh::Feature"]
            self.assertEqual(len(lamellas), 1, g.Label)
            self.assertGreater(len(lamellas[0].Deviation), 0)
            numbers = next(p for p in deployment["patches"] if p["name"] == g.Patch)
            self.assertEqual(g.RmsWithNotches, numbers["rms_with_notches"])  # the patch alone
            # Drawn: the patch's lamellas in the joined whole, one deviation per box corner.
            self.assertEqual(lamellas[0].Rms, numbers["joined_rms"])
            joined_rods = [r for r, p in zip(deployment["rods"], deployment["rod_patches"]) if p == g.Patch]
            self.assertEqual(len(lamellas[0].Deviation), 4 * sum(len(r["deviation"]) for r in joined_rods))
        # Building again replaces the groups.
        core.build_layout(self.doc, self.knet1, s)
        self.assertEqual(len([o for o in parent.Group if o.TypeId == "App::DocumentObjectGroup"]), len(built))

    def test_layout_file(self):
        """A layout report as the CLI writes it (layout.json): its 'layout' is sent."""
        path = os.path.join(self.tmp, "layout.json")
        # knet1.obj is a 21 x 21 grid: its four corner vertices, as points (FreeCAD numbers the
        # vertices its own way; the daemon snaps the points onto the surface).
        with open(os.path.join(T.MESHES, "knet1.obj")) as f:
            vertices = [[float(x) for x in line.split()[1:4]] for line in f if line.startswith("v ")]
        n = 20
        corners = [vertices[c] for c in (0, n, (n + 1) * (n + 1) - 1, n * (n + 1))]
        with open(path, "w") as f:
            json.dump({"coverage": 0, "layout": {
                "corners": [{"point": c} for c in corners],
                "patches": [{"name": "whole", "corners": [0, 1, 2, 3]}]}}, f)
        mesh = core.layout_target(self.knet1)
        self.settings.layout = "file"
        self.settings.layout_file = path
        group = core.layout(self.doc, self.knet1, self.settings)
        answer = self.client.layout(mesh, layout=core.read_layout_file(path))["report"]
        self.assertEqual([o.Label for o in group.Group], ["whole"])
        self.assertEqual(group.Coverage, answer["coverage"])
        self.assertTrue(group.Group[0].Ok, group.Group[0].Problem)
        self.assertAlmostEqual(group.Coverage, 0.486, delta=0.001)  # one patch (docs/multi-patch.md)

    def test_layout_errors_name_the_field(self):
        s = self.settings
        s.max_patches = 100
        for call in (core.layout, core.build_layout):
            with self.assertRaises(gs.InvalidInput) as caught:
                call(self.doc, self.knet1, s)
            self.assertRegex(core.error_message(caught.exception, s),
                             r"invalid input: Patches at most \(automatic.max_patches\): .*100")
        s.max_patches = 36
        path = os.path.join(self.tmp, "bad-layout.json")
        with open(path, "w") as f:
            json.dump({"corners": [{"vertex": 0}, {"vertex": 20}, {"vertex": 440}],
                       "patches": [{"corners": [0, 1, 2, 5]}]}, f)
        s.layout, s.layout_file = "file", path
        with self.assertRaises(gs.InvalidInput) as caught:
            core.layout(self.doc, self.knet1, s)
        self.assertIn("invalid input: Layout (layout.patches[0].corners[3])", core.error_message(caught.exception, s))
        s.layout_file = os.path.join(self.tmp, "missing.json")
        with self.assertRaises(core.InputError) as caught:
            core.layout(self.doc, self.knet1, s)
        self.assertIn("cannot read the layout file", core.error_message(caught.exception, s))
        s.layout = "last"
        with self.assertRaises(core.InputError) as caught:
            core.build_layout(self.doc, self.knet1, s)
        self.assertIn("no layout yet", str(caught.exception))
        self.assertEqual(self.client.health(), "SERVING")

    def test_layout_options_are_the_described_ones(self):
        description = core.describe(self.settings)
        for name in ("max_patches", "coverage_goal"):
            option = description.option("layout", name)
            self.assertIsNotNone(option, name)
            self.assertEqual(core.Settings.FIELDS[name], description.default("layout", name), name)
            self.assertEqual(core.spin_range(description, "layout", name), (0 if name == "max_patches" else 0.0,
                                                                           option["maximum"]), name)
            self.assertIsNone(description.check("layout", name, self.settings.automatic_options()[name]), name)


def main():
    try:
        suite = unittest.defaultTestLoader.loadTestsFromTestCase(FreeCADWorkbenchTest)
        suite.addTests(unittest.defaultTestLoader.loadTestsFromTestCase(FreeCADLayoutTest))
        suite.addTests(unittest.defaultTestLoader.loadTestsFromTestCase(FreeCADMaterialsTest))
        result = unittest.TextTestRunner(verbosity=2, stream=sys.stdout).run(suite)
        failed = len(result.failures) + len(result.errors)
        print("freecad: %d passed, %d failed" % (result.testsRun - failed, failed))
    except BaseException:
        traceback.print_exc()
        failed = 1
    sys.stdout.flush()
    os._exit(1 if failed else 0)  # freecadcmd would exit 0 after an exception


started = time.monotonic()
main()
