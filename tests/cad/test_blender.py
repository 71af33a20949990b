# SPDX-License-Identifier: GPL-3.0-or-later
"""Tests of the Blender add-on (client/blender/gridshell_blender) in real Blender against a real
gridshelld on loopback (started and stopped here):

    blender -b --factory-startup --python-exit-code 1 --python tests/cad/test_blender.py

A dome (a primitive grid displaced, moved, rotated and scaled) with four selected corners and a
shared mesh imported with Blender's own OBJ importer go through design and simulation; the tests
check the objects made (member counts as in design.json, the world frame, the deviation colours,
the RMS on the collection as the daemon computes it), that the add-on, the CLI and curl get the
same design.json byte for byte from the same request, and the error reports. Against a daemon
with a site's material library (GRIDSHELL_MATERIALS): the material choices are the daemon's
description (its built-in materials and the site's), a run with the site's material selected
simulates with it, and the panel's initial values and choices are the described defaults.
Layouts of several patches (issue 35): knet1's automatic layout as one coloured object per patch,
its coverage as the daemon reports it; every patch built, one collection each, the whole's RMS
as the call answered it; a layout from vertex groups; the errors naming the field.
"""

import json
import math
import os
import subprocess
import sys
import tempfile
import unittest

import bmesh
import bpy

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(ROOT, "tests", "python"))
sys.path.insert(0, os.path.join(ROOT, "client", "blender"))

import gridshell_testing as T  # noqa: E402,N812

import gridshell_blender  # noqa: E402
from gridshell_blender import described, layouts, mesh_input, properties, results  # noqa: E402
from gridshell_blender.remote import gs  # noqa: E402
from gridshell_client.client import encode_request  # noqa: E402

RESOLUTION = 24  # distance maps: small and quick; the comparison with the CLI uses the same


def dome(name, n=14, size=10.0, height=2.5):
    """A grid primitive displaced into a dome, then moved, rotated and scaled (a world transform
    that the add-on must apply). Returns the object; its corner vertices are 0, n, last, last-n."""
    bpy.ops.mesh.primitive_grid_add(x_subdivisions=n, y_subdivisions=n, size=size)
    obj = bpy.context.active_object
    obj.name = name
    half = size / 2
    for v in obj.data.vertices:
        x, y = v.co.x / half, v.co.y / half
        v.co.z = height * (1 - 0.5 * (x * x + y * y))
    obj.location = (3.0, -2.0, 1.5)
    obj.rotation_euler = (0.3, -0.2, 0.9)
    obj.scale = (1.5, 1.5, 1.5)
    bpy.context.view_layer.update()
    return obj


def grid_corners(obj):
    """The grid's four corner vertices in boundary order (by position in the object's frame)."""
    vs = obj.data.vertices
    pick = lambda key: max(range(len(vs)), key=lambda i: key(vs[i].co))  # noqa: E731
    return [
        pick(lambda c: -c.x - c.y),
        pick(lambda c: c.x - c.y),
        pick(lambda c: c.x + c.y),
        pick(lambda c: -c.x + c.y),
    ]


def select(obj, vertices):
    """Selects exactly ``vertices`` of ``obj``, in this order (Blender's selection history)."""
    bpy.context.view_layer.objects.active = obj
    for other in bpy.context.view_layer.objects:
        other.select_set(other == obj)
    bm = bmesh.new()
    bm.from_mesh(obj.data)
    bm.verts.ensure_lookup_table()
    for v in bm.verts:
        v.select = False
    for e in bm.edges:
        e.select = False
    for f in bm.faces:
        f.select = False
    bm.select_history.clear()
    for i in vertices:
        bm.verts[i].select = True
        bm.select_history.add(bm.verts[i])
    bm.to_mesh(obj.data)
    bm.free()
    obj.data.update()


def world(obj, index):
    """A vertex in world coordinates, computed here in double precision."""
    m = obj.matrix_world
    co = obj.data.vertices[index].co
    return [
        sum(float(m[r][c]) * float(co[c]) for c in range(3)) + float(m[r][3]) for r in range(3)
    ]


def design_of_scene():
    return json.loads(results.design_json(bpy.context))


def member_objects(name=results.MEMBERS):
    return [o for o in bpy.data.collections[name].objects if o.type == "CURVE"]


class BlenderAddonTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.daemon = T.Daemon()
        gridshell_blender.register()
        cls.settings = bpy.context.scene.gridshell
        cls.settings.server = cls.daemon.url
        cls.tmp = tempfile.mkdtemp(prefix="gridshell-blender-")
        cls.client = gs.Client(cls.daemon.url)

    @classmethod
    def tearDownClass(cls):
        gridshell_blender.unregister()
        cls.daemon.stop()

    def setUp(self):
        s = self.settings
        s.server = self.daemon.url
        s.resolution = RESOLUTION
        s.notches = "on"
        s.material_name = ""  # the daemon's default
        s.unit = "SCENE"
        s.lamella_width = 0
        s.auto_anchors = False

    def test_dome_design_then_simulate(self):
        obj = dome("dome.obj")
        corners = grid_corners(obj)
        select(obj, corners)
        mesh, sent_corners, _ = mesh_input.request_mesh_for_scene(bpy.context)
        self.assertEqual(sent_corners, {"vertices": corners})

        self.assertEqual(bpy.ops.gridshell.design(), {"FINISHED"})
        design = design_of_scene()
        top = bpy.data.collections[results.COLLECTION]
        # One curve per member, on the surface and in the plane; anchors as empties.
        self.assertEqual(len(member_objects()), len(design["members"]))
        self.assertEqual(len(member_objects(results.PLANAR)), len(design["members"]))
        self.assertEqual(
            sorted(o.name for o in member_objects()),
            sorted("%s %d" % (m["family"], m["index"]) for m in design["members"]),
        )
        anchors = bpy.data.collections[results.ANCHORS].objects
        self.assertEqual(len(anchors), len(design["anchors"]))
        self.assertGreater(len(design["members"]), 8)
        self.assertEqual(top["members"], len(design["members"]))
        self.assertEqual(top["alpha_bar"], design["alpha_bar"])
        # The world frame: the patch's corners are the selected vertices, transformed.
        patch = design["patch"]
        for k, v in enumerate(corners):
            got = patch["vertices"][patch["corners"][k]]
            want = world(obj, v)
            for a, b in zip(got, want):
                self.assertAlmostEqual(a, b, delta=1e-9 * 20)
        # ... and a member curve's points are the design's surface points.
        member = design["members"][1]
        curve = bpy.data.objects["%s %d" % (member["family"], member["index"])]
        points = [tuple(p.co)[:3] for p in curve.data.splines[0].points]
        self.assertEqual(len(points), len(member["surface"]))
        for p, q in zip(points, member["surface"]):
            for a, b in zip(p, q):
                self.assertAlmostEqual(a, b, delta=1e-5)  # curve points are float32

        # The same request from curl and from the CLI gives the same design.json, byte for byte.
        ours = results.design_json(bpy.context).encode("utf-8")
        request = {"mesh": mesh, "corners": sent_corners, "options": self.settings.design_options(), "files": True}
        path = os.path.join(self.tmp, "request.json")
        with open(path, "wb") as f:
            f.write(encode_request(request))
        curl = subprocess.run(
            ["curl", "-sS", "--fail-with-body", "-X", "POST", "-H", "Content-Type: application/json",
             "--data-binary", "@" + path, self.daemon.url + "/v1/design"],
            capture_output=True, check=True,
        )
        self.assertEqual(gs.files_of(json.loads(curl.stdout))["design.json"], ours)
        obj_file = os.path.join(self.tmp, "dome.obj")
        T.write_obj(obj_file, mesh["positions"], mesh["indices"])
        out = os.path.join(self.tmp, "dome-cli")
        cli = T.cli("design", obj_file, "--corners", ",".join(map(str, corners)),
                    "--resolution", RESOLUTION, "--out", out, "--quiet")
        self.assertEqual(cli.returncode, 0, cli.stderr)
        with open(os.path.join(out, "design.json"), "rb") as f:
            self.assertEqual(f.read(), ours)

        # Simulate the design kept in the text: the deployed lamellas with their deviation.
        self.assertEqual(bpy.ops.gridshell.simulate(), {"FINISHED"})
        deployed = bpy.data.collections[results.DEPLOYED]
        lamellas = [o for o in deployed.objects if o.type == "MESH"]
        self.assertEqual(len(lamellas), 1)  # notches "on": one run
        lamella = lamellas[0]
        self.assertIn("deviation", lamella.data.color_attributes)
        # The daemon's own answer to the same simulation request.
        answer = self.client.simulate(
            ours, self.settings.simulation_options(bpy.context.scene), design_name=results.DESIGN_TEXT
        )
        deployment = answer["deployment"]
        self.assertEqual(top["rms_with_notches"], deployment["rms_with_notches"])
        self.assertNotIn("rms_without_notches", top)
        self.assertEqual(lamella["rms"], deployment["with_notches"]["rms"])
        # Four box corners per rod vertex, coloured by its deviation (blue 0 .. red at the max).
        deviation = [d for rod in deployment["rods"] for d in rod["deviation"] for _ in range(4)]
        self.assertEqual(len(lamella.data.vertices), len(deviation))
        values = lamella.data.attributes["deviation_distance"].data
        worst = max(range(len(deviation)), key=deviation.__getitem__)
        self.assertAlmostEqual(values[worst].value, deviation[worst], delta=1e-6 * max(deviation))
        colours = lamella.data.color_attributes["deviation"].data
        self.assertEqual(tuple(colours[worst].color), (1.0, 0.0, 0.0, 1.0))
        best = min(range(len(deviation)), key=deviation.__getitem__)
        self.assertGreater(colours[best].color[2], colours[best].color[0])
        self.assertEqual(lamella.material_slots[0].material.name, results.MATERIAL)
        # The lamellas lie in the world frame too: near the transformed dome's corner.
        c0 = world(obj, corners[0])
        nearest = min(
            math.dist(c0, tuple(v.co)) for v in lamella.data.vertices
        )
        self.assertLess(nearest, 0.05 * 15)

    def test_shared_mesh_imported_and_run(self):
        path = os.path.join(T.MESHES, "knet1.obj")
        self.assertTrue(os.path.exists(path), path)
        bpy.ops.object.select_all(action="DESELECT")
        bpy.ops.wm.obj_import(filepath=path)
        obj = bpy.context.selected_objects[0]
        bpy.context.view_layer.objects.active = obj
        select(obj, [])  # no corners selected: automatic
        mesh, corners, _ = mesh_input.request_mesh_for_scene(bpy.context)
        self.assertIsNone(corners)
        self.assertEqual(len(mesh["positions"]), 3 * 441)
        self.settings.notches = "both"
        self.assertEqual(bpy.ops.gridshell.run(), {"FINISHED"})
        design = design_of_scene()
        self.assertEqual(design["options"]["corners"], "auto")
        self.assertEqual(len(member_objects()), len(design["members"]))
        top = bpy.data.collections[results.COLLECTION]
        answer = self.client.run(
            mesh, None, self.settings.design_options(),
            self.settings.simulation_options(bpy.context.scene),
        )
        self.assertEqual(answer["design"]["design"], design)
        deployment = answer["simulation"]["deployment"]
        self.assertEqual(top["rms_with_notches"], deployment["rms_with_notches"])
        self.assertEqual(top["rms_without_notches"], deployment["rms_without_notches"])
        lamellas = [o for o in bpy.data.collections[results.DEPLOYED].objects]
        self.assertEqual(sorted(o["notches"] for o in lamellas), [False, True])

    def test_inner_anchors_found_by_the_simulation(self):
        """waves-bump held at its boundary snaps into a dome: "Find inner anchors" adds one."""
        loaded = self.client.load(gs.mesh_example("waves-bump"))
        p, f = loaded["mesh"]["positions"], loaded["mesh"]["indices"]
        data = bpy.data.meshes.new("waves-bump")
        data.from_pydata([p[k : k + 3] for k in range(0, len(p), 3)], [], [f[k : k + 3] for k in range(0, len(f), 3)])
        obj = bpy.data.objects.new("waves-bump", data)
        bpy.context.scene.collection.objects.link(obj)
        select(obj, loaded["example_corners"]["vertices"])
        s = self.settings
        s.resolution = 100
        s.auto_anchors = True
        self.assertEqual(s.simulation_options(bpy.context.scene)["interior_anchors"], "auto")
        self.assertEqual(bpy.ops.gridshell.run(), {"FINISHED"})
        top = bpy.data.collections[results.COLLECTION]
        answer = self.client.simulate(
            results.design_json(bpy.context), s.simulation_options(bpy.context.scene), design_name="design.json"
        )
        deployment = answer["deployment"]
        added = deployment["added_anchors"]
        self.assertGreaterEqual(len(added), 1, deployment["anchor_trial_rms"])
        self.assertEqual(top["rms_with_notches"], deployment["rms_with_notches"])
        self.assertEqual(top["added_anchors"], len(added))
        self.assertEqual(list(top["anchor_trial_rms"]), deployment["anchor_trial_rms"])
        empties = [o for o in bpy.data.collections[results.ANCHORS].objects if o.get("added")]
        self.assertEqual(sorted(o.name for o in empties), sorted("added anchor g%d h%d" % (a["g"], a["h"]) for a in added))
        for a in added:
            e = bpy.data.objects["added anchor g%d h%d" % (a["g"], a["h"])]
            self.assertLess(math.dist(tuple(e.location), a["position"]), 1e-4 * 100)
        self.assertIn(("Anchors", "%d, %d added by the simulation" % (len(design_of_scene()["anchors"]), len(added))),
                      results.summary(bpy.context.scene))
        # Simulating again without the search removes them.
        s.auto_anchors = False
        self.assertEqual(bpy.ops.gridshell.simulate(), {"FINISHED"})
        self.assertEqual([o for o in bpy.data.collections[results.ANCHORS].objects if o.get("added")], [])
        self.assertEqual(top["added_anchors"], 0)

    def test_errors_are_reports(self):
        grid = dome("flat.obj", n=8, height=0.0)
        vs = grid_corners(grid)
        # Three corners.
        select(grid, vs[:3])
        with self.assertRaisesRegex(RuntimeError, "select 4 corner vertices of flat.obj in order"):
            bpy.ops.gridshell.design()
        # A dart: the third corner inside the square, towards the first, is a reflex corner.
        n = 8
        inside = (n // 2 - 1) * (n + 1) + n // 2 - 1
        select(grid, [vs[0], vs[1], inside, vs[3]])
        with self.assertRaisesRegex(
            RuntimeError, r"infeasible design: selected corner 3 \(corners\[2\]\): .*criterion iv"
        ):
            bpy.ops.gridshell.design()
        # An option out of range names the panel's field.
        select(grid, vs)
        self.settings.lamella_width = 1e9
        with self.assertRaisesRegex(RuntimeError, r"invalid input: Lamella width \(options.lamella_width\)"):
            bpy.ops.gridshell.design()
        self.settings.lamella_width = 0
        # An invalid mesh: a vertex at NaN, named as Blender numbers it.
        grid.data.vertices[5].co.x = float("nan")
        with self.assertRaisesRegex(
            RuntimeError, r"invalid input: vertex 5 of flat.obj \(mesh.positions\[15\]\): NaN"
        ):
            bpy.ops.gridshell.design()
        # No daemon there.
        with T.refusing_port() as port:
            self.settings.server = "http://127.0.0.1:%d" % port
            with self.assertRaisesRegex(RuntimeError, "cannot reach the daemon at http://127.0.0.1"):
                bpy.ops.gridshell.design()
        self.settings.server = self.daemon.url
        # Not a mesh.
        bpy.ops.object.empty_add()
        with self.assertRaisesRegex(RuntimeError, "select a mesh object"):
            bpy.ops.gridshell.design()
        # The daemon kept serving throughout.
        self.assertEqual(self.client.health(), "SERVING")


class BlenderMaterialsTest(unittest.TestCase):
    """The material choices and the option defaults from the daemon's description."""

    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.mkdtemp(prefix="gridshell-blender-materials-")
        cls.daemon = T.Daemon(env=T.material_library(cls.tmp))
        gridshell_blender.register()
        cls.settings = bpy.context.scene.gridshell
        cls.client = gs.Client(cls.daemon.url)

    @classmethod
    def tearDownClass(cls):
        gridshell_blender.unregister()
        cls.daemon.stop()

    def setUp(self):
        s = self.settings
        s.server = self.daemon.url
        s.material_name = ""
        s.resolution = RESOLUTION
        s.notches = "on"
        s.unit = "SCENE"
        s.auto_anchors = False

    def choices(self):
        return [item[0] for item in described.material_items(self.settings)]

    def test_materials_from_the_description_and_a_run_with_the_sites(self):
        s, scene = self.settings, bpy.context.scene
        site = T.SITE_MATERIAL["name"]
        # Nothing read from this daemon yet: the daemon's default alone, and no material sent.
        gs.options.forget(self.daemon.url)
        self.assertEqual(self.choices(), [described.DEFAULT])
        self.assertEqual(s.material, described.DEFAULT)
        self.assertNotIn("material", s.simulation_options(scene))
        with self.assertRaises(TypeError):
            s.material = site  # not a choice before the description is read
        # Refresh reads the description: the built-in materials (as the CLI lists them), then
        # the site's.
        self.assertEqual(bpy.ops.gridshell.refresh_options(), {"FINISHED"})
        names = gs.options.cached(s.server).material_names()
        self.assertEqual(self.choices(), names)
        cli = T.cli("options", "--json")
        self.assertEqual(cli.returncode, 0, cli.stderr)
        built_in = [m["name"] for m in json.loads(cli.stdout)["materials"] if not m.get("site")]
        self.assertEqual(names, built_in + [site])
        self.assertEqual(s.material, built_in[0])  # none chosen: the default is shown
        self.assertNotIn("material", s.simulation_options(scene))
        for name in names:  # every item can be chosen
            s.material = name
            self.assertEqual((s.material, s.material_name), (name, name))
        labels = {item[0]: item[1] for item in described.material_items(s)}
        self.assertEqual(labels[site], "Test larch")
        s.material = site
        self.assertEqual(s.simulation_options(scene)["material"], site)

        # Design + Simulate with it: the deployment was simulated with the site's material.
        obj = dome("larch dome", n=10)
        select(obj, grid_corners(obj))
        self.assertEqual(bpy.ops.gridshell.run(), {"FINISHED"})
        top = bpy.data.collections[results.COLLECTION]
        self.assertEqual(top["material"], site)
        self.assertIn(("Material", site), results.summary(scene))
        answer = self.client.simulate(
            results.design_json(bpy.context), s.simulation_options(scene), design_name=results.DESIGN_TEXT
        )
        options = answer["deployment"]["options"]
        self.assertEqual(options["material"], site)
        self.assertEqual(options["young_modulus"], T.SITE_MATERIAL["young_modulus"])
        self.assertEqual(top["rms_with_notches"], answer["deployment"]["rms_with_notches"])

        # A daemon without the library: the chosen material stays (added to its list) and is
        # sent; the daemon refuses it, naming the panel's field.
        with T.Daemon() as plain:
            s.server = plain.url
            self.assertEqual(bpy.ops.gridshell.refresh_options(), {"FINISHED"})
            self.assertEqual(self.choices(), built_in + [site])
            self.assertEqual(s.material, site)
            with self.assertRaisesRegex(RuntimeError, r"invalid input: Material \(options.material\)"):
                bpy.ops.gridshell.simulate()
            s.material = built_in[0]
            self.assertEqual(self.choices(), built_in)
        # An unreachable daemon: Refresh reports it.
        with T.refusing_port() as port:
            s.server = "http://127.0.0.1:%d" % port
            with self.assertRaisesRegex(RuntimeError, "cannot reach the daemon"):
                bpy.ops.gridshell.refresh_options()
            # Nothing read: the daemon's default and the chosen material, still selected.
            self.assertEqual(self.choices(), [described.DEFAULT, built_in[0]])
            self.assertEqual(s.material, built_in[0])
            self.assertEqual(s.simulation_options(scene)["material"], built_in[0])

    def test_initial_values_and_choices_are_the_described_ones(self):
        description = gs.describe(self.client)
        rna = properties.GridshellSettings.bl_rna.properties
        for name in ("members_u", "members_v", "lamella_width", "lamella_thickness", "resolution",
                     "interior_anchors"):
            self.assertEqual(rna[name].default, description.default("design", name), name)
            # No copy of the described range: only the floor at 0 (0 = automatic).
            self.assertEqual(rna[name].hard_min, 0, name)
            maximum = description.option("design", name).get("maximum")  # none: unbounded
            if maximum is not None:
                self.assertGreater(rna[name].hard_max, maximum, name)
        self.assertEqual(rna["notches"].default, description.default("simulation", "notches"))
        self.assertEqual({i.identifier for i in rna["notches"].enum_items},
                         set(description.choices("simulation", "notches")))
        units = [i.identifier for i in rna["unit"].enum_items if i.identifier not in ("SCENE", "NONE")]
        self.assertEqual(units, description.length_units)
        # The design options the panel sends pass the description's check.
        for name, value in self.settings.design_options().items():
            if description.option("design", name) is not None:
                self.assertIsNone(description.check("design", name, value), name)


class BlenderLayoutTest(unittest.TestCase):
    """Several patches joined at seams: Layout and Build all patches."""

    @classmethod
    def setUpClass(cls):
        cls.daemon = T.Daemon()
        gridshell_blender.register()
        cls.settings = bpy.context.scene.gridshell
        cls.client = gs.Client(cls.daemon.url)
        cls.tmp = tempfile.mkdtemp(prefix="gridshell-blender-layout-")

    @classmethod
    def tearDownClass(cls):
        gridshell_blender.unregister()
        cls.daemon.stop()

    def setUp(self):
        s = self.settings
        s.server = self.daemon.url
        s.resolution = RESOLUTION
        s.notches = "on"
        s.material_name = ""
        s.unit = "SCENE"
        s.lamella_width = 0
        s.auto_anchors = False
        s.members_u = s.members_v = 0
        s.layout_source = "AUTO"
        s.max_patches = 36
        s.coverage_goal = 0.95

    def knet1(self):
        bpy.ops.object.select_all(action="DESELECT")
        bpy.ops.wm.obj_import(filepath=os.path.join(T.MESHES, "knet1.obj"))
        obj = bpy.context.selected_objects[0]
        bpy.context.view_layer.objects.active = obj
        return obj

    def test_automatic_layout_then_build_all_patches(self):
        self.knet1()
        mesh, _, _ = mesh_input.layout_target(bpy.context.active_object, bpy.context.evaluated_depsgraph_get())
        self.assertEqual(len(mesh["positions"]), 3 * 441)
        self.assertEqual(self.settings.automatic_options(), {"max_patches": 36, "coverage_goal": 0.95})
        self.assertEqual(bpy.ops.gridshell.layout(), {"FINISHED"})
        coll = bpy.data.collections[layouts.LAYOUT]
        # The daemon's own answer to the same request.
        report = self.client.layout(mesh, automatic=self.settings.automatic_options())["report"]
        patches = [o for o in coll.objects]
        self.assertEqual(len(patches), len(report["patches"]))
        self.assertEqual(coll["patches"], len(report["patches"]))
        self.assertEqual(len(report["patches"]), 20)  # knet1: 5 x 4 (docs/multi-patch.md)
        self.assertEqual(coll["coverage"], report["coverage"])
        self.assertAlmostEqual(coll["coverage"], 0.954, delta=0.001)
        self.assertEqual(coll["automatic_grid"], "5 x 4")
        self.assertEqual(sorted(o["patch"] for o in patches), sorted(p["name"] for p in report["patches"]))
        self.assertEqual(sorted(o.name for o in patches), sorted(p["name"] for p in report["patches"]))
        self.assertEqual(len({tuple(o.color) for o in patches}), len(patches))  # distinct colours
        for o in patches:
            self.assertEqual(o.type, "MESH")
            self.assertGreater(len(o.data.polygons), 0)
        self.assertAlmostEqual(coll["uncovered_area"], sum(u["area"] for u in report["uncovered"]), delta=1e-9)
        self.assertIn("outside the patches", coll["uncovered"])
        self.assertEqual(json.loads(bpy.data.texts[layouts.LAYOUT_TEXT].as_string()), report["layout"])

        # Every patch built, with the layout found (the text), small grids: one collection each.
        s = self.settings
        s.layout_source = "LAST"
        s.members_u = s.members_v = 3
        self.assertEqual(bpy.ops.gridshell.build_layout(), {"FINISHED"})
        parent = bpy.data.collections[layouts.PATCHES]
        deployment = json.loads(bpy.data.texts[layouts.DEPLOYMENT_TEXT].as_string())  # the call's
        built = [p["name"] for p in deployment["patches"]]
        self.assertGreater(len(built), 0)
        self.assertEqual(sorted(c.name for c in parent.children), sorted(layouts.PATCH_PREFIX + n for n in built))
        self.assertEqual(parent["patches_built"], len(built))
        self.assertEqual(parent["patches_built"] + parent["patches_failed"], 20)
        self.assertEqual(parent["rms_with_notches"], deployment["rms_with_notches"])
        self.assertEqual(parent["rms_with_notches_percent"], 100 * deployment["rms_with_notches"] / deployment["diagonal"])
        self.assertNotIn("rms_without_notches", parent)  # notches "on"
        self.assertEqual(parent["converged"], deployment["converged"])
        self.assertEqual(parent["max_seam_gap"], deployment["max_seam_gap"])
        self.assertGreater(parent["seam_bolts"], 0)
        # The whole was joined: its seams closed, the bolts' force and the patches alone kept.
        self.assertTrue(parent["seams_joined"])
        self.assertEqual(parent["max_bolt_force"], deployment["max_bolt_force"])
        self.assertEqual(parent["rms_before_joining"], deployment["rms_before_joining"])
        for child in parent.children:
            lamellas = [o for o in child.objects if o.type == "MESH"]
            self.assertEqual(len(lamellas), 1, child.name)
            self.assertIn("deviation", lamellas[0].data.color_attributes)
            name = child["patch"]
            numbers = next(p for p in deployment["patches"] if p["name"] == name)
            self.assertEqual(child["rms_with_notches"], numbers["rms_with_notches"])  # the patch alone
            # Drawn: the patch's lamellas in the joined whole, one deviation per box corner.
            self.assertEqual(lamellas[0]["rms"], numbers["joined_rms"])
            joined_rods = [r for r, p in zip(deployment["rods"], deployment["rod_patches"]) if p == name]
            self.assertEqual(len(lamellas[0].data.vertices), 4 * sum(len(r["deviation"]) for r in joined_rods))
        # The panel's rows.
        rows = {label: value for label, value, _ in layouts.summary(bpy.context.scene)}
        self.assertEqual(rows["Built"].split()[0], str(len(built)))

    def test_layout_from_vertex_groups(self):
        obj = dome("grouped dome", n=8)
        n = 8
        index = lambda i, j: j * (n + 1) + i  # noqa: E731 (the grid primitive's numbering)
        half = n // 2
        for name, (i, j) in (("A", (0, 0)), ("B", (half, 0)), ("C", (0, half)), ("D", (half, half))):
            group = obj.vertex_groups.new(name=name)
            group.add([index(i, j), index(i + half, j), index(i + half, j + half), index(i, j + half)], 1.0, "REPLACE")
        obj.vertex_groups.new(name="other").add([0, 1], 1.0, "REPLACE")  # not 4: left out
        select(obj, [])
        layout, ignored = mesh_input.vertex_group_layout(obj)
        self.assertEqual([p["name"] for p in layout["patches"]], ["A", "B", "C", "D"])
        self.assertEqual(len(layout["corners"]), 9)  # shared corners once
        self.assertEqual(ignored, ["other (2 vertices)"])
        self.settings.layout_source = "GROUPS"
        self.assertEqual(bpy.ops.gridshell.layout(), {"FINISHED"})
        coll = bpy.data.collections[layouts.LAYOUT]
        self.assertEqual(sorted(o.name for o in coll.objects), ["A", "B", "C", "D"])
        self.assertEqual(coll["failing_patches"], 0)
        self.assertEqual(coll["seams"], 4)  # the 2 x 2 layout's inner seams
        # The same layout written as a file, a layout report as the CLI writes it.
        path = os.path.join(self.tmp, "layout.json")
        with open(path, "w") as f:
            json.dump({"coverage": coll["coverage"], "layout": json.loads(bpy.data.texts[layouts.LAYOUT_TEXT].as_string())}, f)
        self.settings.layout_source = "FILE"
        self.settings.layout_file = path
        covered = coll["coverage"]
        self.assertEqual(bpy.ops.gridshell.layout(), {"FINISHED"})
        self.assertEqual(coll["coverage"], covered)
        self.assertEqual(sorted(o.name for o in coll.objects), ["A", "B", "C", "D"])

    def test_layout_errors_name_the_field(self):
        self.knet1()
        s = self.settings
        s.max_patches = 100
        with self.assertRaisesRegex(RuntimeError, r"invalid input: Patches at most \(automatic.max_patches\): .*100"):
            bpy.ops.gridshell.layout()
        with self.assertRaisesRegex(RuntimeError, r"invalid input: Patches at most \(automatic.max_patches\)"):
            bpy.ops.gridshell.build_layout()
        s.max_patches = 36
        # A layout file whose patch names a corner it does not have.
        path = os.path.join(self.tmp, "bad-layout.json")
        with open(path, "w") as f:
            json.dump({"corners": [{"vertex": 0}, {"vertex": 20}, {"vertex": 440}],
                       "patches": [{"corners": [0, 1, 2, 5]}]}, f)
        s.layout_source = "FILE"
        s.layout_file = path
        with self.assertRaisesRegex(RuntimeError, r"invalid input: Layout \(layout.patches\[0\].corners\[3\]\)"):
            bpy.ops.gridshell.layout()
        s.layout_file = os.path.join(self.tmp, "no-such-layout.json")
        with self.assertRaisesRegex(RuntimeError, "cannot read the layout file"):
            bpy.ops.gridshell.layout()
        with open(path, "w") as f:
            json.dump({"coverage": 1}, f)
        s.layout_file = path
        with self.assertRaisesRegex(RuntimeError, "holds no layout"):
            bpy.ops.gridshell.layout()
        s.layout_source = "GROUPS"
        with self.assertRaisesRegex(RuntimeError, "has no vertex group of 4 vertices"):
            bpy.ops.gridshell.layout()
        self.assertEqual(self.client.health(), "SERVING")

    def test_layout_options_are_the_described_ones(self):
        description = gs.describe(self.client)
        rna = properties.GridshellSettings.bl_rna.properties
        for name in ("max_patches", "coverage_goal"):
            option = description.option("layout", name)
            self.assertIsNotNone(option, name)
            self.assertAlmostEqual(rna[name].default, description.default("layout", name), delta=1e-7)
            self.assertEqual(rna[name].hard_min, 0, name)
            self.assertIsNone(description.check("layout", name, self.settings.automatic_options()[name]), name)
        self.assertIsNotNone(description.check("layout", "max_patches", 100))


def main():
    suite = unittest.defaultTestLoader.loadTestsFromTestCase(BlenderAddonTest)
    suite.addTests(unittest.defaultTestLoader.loadTestsFromTestCase(BlenderLayoutTest))
    suite.addTests(unittest.defaultTestLoader.loadTestsFromTestCase(BlenderMaterialsTest))
    result = unittest.TextTestRunner(verbosity=2, stream=sys.stdout).run(suite)
    failed = len(result.failures) + len(result.errors)
    print("blender: %d passed, %d failed" % (result.testsRun - failed, failed))
    if failed:
        raise SystemExit(1)


main()
