# SPDX-License-Identifier: GPL-3.0-or-later
"""Tests of the daemon's description of its options and materials as the Python client sees it
(``Client.options()``, ``gridshell_client.options``), against a real gridshelld on loopback:

- every group is described, every option's default passes the option's own range, the materials
  are the simulation's ``material`` choices, the CLI prints the same description;
- the description agrees with the daemon: the defaults sent explicitly give the same results as
  leaving them out, a value just outside each described range is refused by the daemon with the
  option's field, and the patch routing key's defaults are the described ones;
- a site's material library (GRIDSHELL_MATERIALS) is listed after the built-in materials and a run
  with it selected uses it; the mesh formats come from the description, not from a list of the
  client's.

    python3 -m unittest discover -s tests/python -t tests/python -v
"""

import json
import shutil
import tempfile
import time
import unittest

import gridshell_testing as T  # noqa: N812 (puts client/python on sys.path)

import gridshell_client as gs
from gridshell_client import options as described, routing

HYPAR = gs.mesh_example("hypar")
QUICK = {"resolution": 16}


def explicit_defaults(description, group):
    """Every option of ``group`` with a default, set to it; not those whose use depends on
    another option (a ``note``: e.g. anchor_goal applies to interior_anchors auto only)."""
    out = {}
    for option in description.group(group):
        value = description.default(group, option["name"])
        if value is not None and not option.get("note"):
            out[option["name"]] = value
    return out


def outside(option):
    """Values just outside the option's range (not 0 where 0 is allowed)."""
    integer = option["type"] == "integer"
    low, high = option.get("minimum"), option.get("maximum")
    values = []
    if high is not None:
        if option.get("exclusive_maximum"):
            values.append(high)
        else:
            values.append(high + 1 if integer or high <= 0 else 2 * high)
    if low is not None:
        if option.get("exclusive_minimum"):
            value = low
        else:
            value = low - 1 if integer or low <= 0 else low / 2
        if not (value == 0 and option.get("zero_allowed")):
            values.append(value)
    return [int(v) if integer else v for v in values]


class DescriptionTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.daemon = T.Daemon()
        cls.client = gs.Client(cls.daemon.url)
        cls.result = cls.client.options()
        cls.description = gs.Description(cls.result)

    @classmethod
    def tearDownClass(cls):
        cls.daemon.stop()

    def test_every_group_and_each_default_within_its_range(self):
        d = self.description
        self.assertEqual(d.groups(), list(described.GROUPS))
        seen = set()
        for option in d.options:
            group, name = option["group"], option["name"]
            where = "%s.%s" % (group, name)
            self.assertNotIn((group, name), seen, where)
            seen.add((group, name))
            self.assertIn(option["type"], described.TYPES, where)
            self.assertTrue(option.get("label"), where)
            self.assertTrue(option.get("help"), where)
            self.assertIs(d.option(group, name), option)
            if option["type"] == "choice":
                self.assertTrue(option.get("choices"), where)
            low, high = option.get("minimum"), option.get("maximum")
            if low is not None and high is not None:
                self.assertLess(low, high, where)
            if option.get("zero_allowed"):
                self.assertIsNone(d.check(group, name, 0), where)
            if option.get("output"):
                continue  # results only: a request ignores it
            default = d.default(group, name)
            if option["type"] in ("number", "integer", "boolean", "numbers", "choice"):
                self.assertIsNotNone(default, where)
            if default is not None:
                self.assertIsNone(d.check(group, name, default), "%s default %r" % (where, default))
            if option["type"] == "numbers" and option.get("count"):
                self.assertEqual(len(default), option["count"], where)
        self.assertIsNone(d.option("design", "no_such_option"))
        with self.assertRaises(KeyError):
            d.default("design", "no_such_option")
        # The groups the requests have: the options a design takes include the patch's.
        for name in ("geodesic_method", "eta_max", "auto_corner_angles"):
            self.assertIsNotNone(d.option("patch", name), name)
            self.assertEqual(d.option("patch", name)["default_value"],
                             d.option("design", name)["default_value"], name)

    def test_materials_are_the_material_choices(self):
        d = self.description
        names = d.material_names()
        self.assertGreaterEqual(len(names), 2)
        self.assertEqual(len(set(names)), len(names))
        self.assertEqual(d.default_material, names[0])
        self.assertEqual(d.default("simulation", "material"), d.default_material)
        choices = d.choices("simulation", "material")
        for name in names:
            self.assertIn(name, choices)
            m = d.material(name)
            self.assertTrue(m.get("label"), name)
            self.assertGreater(m["young_modulus"], 0, name)
            self.assertGreater(m["shear_modulus"], 0, name)
            for field in ("young_modulus", "shear_modulus", "bending_strength", "shear_strength"):
                if m.get(field):
                    self.assertIsNone(d.check("simulation", field, m[field]), (name, field))
        self.assertIsNone(d.material("no-such-material"))
        self.assertEqual(d.mesh_formats, self.result["mesh_formats"])
        self.assertIn("obj", d.mesh_formats)
        self.assertTrue(d.length_units)

    def test_the_cli_prints_the_same_description(self):
        run = T.cli("options", "--json")
        self.assertEqual(run.returncode, 0, run.stderr)
        self.assertEqual(json.loads(run.stdout), self.result)

    def test_explicit_defaults_change_nothing(self):
        d = self.description
        patch = explicit_defaults(d, "patch")
        self.assertIn("eta_max", patch)
        self.assertEqual(
            self.client.patch(HYPAR, options=patch)["patch"], self.client.patch(HYPAR)["patch"]
        )
        design = explicit_defaults(d, "design")
        self.assertEqual(design["resolution"], d.default("design", "resolution"))
        self.assertEqual(
            self.client.design(HYPAR, options=design)["design"], self.client.design(HYPAR)["design"]
        )
        made = self.client.design(HYPAR, options=QUICK)["design"]
        simulation = explicit_defaults(d, "simulation")
        self.assertEqual(simulation["material"], d.default_material)
        a = self.client.simulate(made, options=simulation)["deployment"]
        b = self.client.simulate(made)["deployment"]
        for key in ("options", "rods", "rms_with_notches", "rms_without_notches"):
            self.assertEqual(a[key], b[key], key)

    def test_the_daemon_refuses_what_the_ranges_exclude(self):
        d = self.description
        made = self.client.design(HYPAR, options=QUICK)["design"]
        tried = 0
        for group in ("patch", "design", "simulation"):
            for option in d.group(group):
                if option["type"] not in ("number", "integer"):
                    continue
                name = option["name"]
                for value in outside(option):
                    where = "%s.%s = %r" % (group, name, value)
                    self.assertIsNotNone(d.check(group, name, value), where)
                    with self.assertRaises(gs.InvalidInput, msg=where) as caught:
                        if group == "patch":
                            self.client.patch(HYPAR, options={name: value})
                        elif group == "design":
                            self.client.design(HYPAR, options=dict(QUICK, **{name: value}))
                        else:
                            self.client.simulate(made, options={name: value})
                    self.assertEqual(caught.exception.field, "options." + name, where)
                    tried += 1
        self.assertGreater(tried, 20)

    def test_the_routing_key_defaults_are_the_described_ones(self):
        d = self.description
        self.assertEqual(routing.DEFAULT_RESOLUTION, d.default("design", "resolution"))
        self.assertEqual(routing.DEFAULT_ETA_MAX, d.default("design", "eta_max"))
        self.assertEqual(routing.DEFAULT_METHOD, d.default("design", "geodesic_method"))
        self.assertEqual(set(routing.METHODS), set(d.choices("design", "geodesic_method")))
        self.assertEqual(routing.SMOOTHING_ITERATIONS, d.default("patch", "max_smoothing_iterations"))
        # The key is None (no key sent) exactly where the description refuses the resolution.
        digest = routing.MeshDigest([0, 0, 0, 1, 0, 0, 0, 1, 0], [0, 1, 2])
        for value in (0, 1, 7, 8, 16, 1000, 1001):
            refused = d.check("design", "resolution", value) is not None
            self.assertEqual(digest.key(None, {"resolution": value}) is None, refused, value)

    def test_described_once_per_daemon(self):
        described.forget()
        self.assertIsNone(described.cached(self.daemon.url))
        before = len(self.daemon.requests("Options"))
        first = gs.describe(self.client)
        again = gs.describe(gs.Client(self.daemon.url + "/"))
        self.assertIs(first, again)
        self.assertIs(described.cached(self.daemon.url), first)
        self.assertEqual(first.raw, self.result)
        self.assertIsNone(described.cached("http://127.0.0.1:1"))
        self.assertIsNone(described.cached("not an address:x"))
        fresh = gs.describe(self.client, refresh=True)
        self.assertIsNot(fresh, first)
        self.assertIs(described.cached(self.daemon.url), fresh)
        # Two calls in all: the first describe and the refresh (the log line follows the answer).
        deadline = time.monotonic() + 10
        while len(self.daemon.requests("Options")) < before + 2 and time.monotonic() < deadline:
            time.sleep(0.05)
        time.sleep(0.2)
        self.assertEqual(len(self.daemon.requests("Options")), before + 2)
        described.forget(self.daemon.url)
        self.assertIsNone(described.cached(self.daemon.url))

    def test_mesh_format_left_to_the_daemon(self):
        self.assertFalse(hasattr(gs, "MESH_FORMATS"))  # no list of the client's own
        mesh = gs.mesh_file(b"v 0 0 0\n")  # bytes without a name: no format
        self.assertNotIn("format", mesh)
        for bad in (mesh, gs.mesh_file(b"v 0 0 0\n", format="3ds")):
            with self.assertRaises(gs.InvalidInput) as caught:
                self.client.load(bad)
            self.assertEqual(caught.exception.field, "mesh.format")
            for name in self.description.mesh_formats:
                self.assertIn(name, caught.exception.message)
        for name in self.description.mesh_formats:
            self.assertEqual(gs.mesh_file(b"", name="part." + name)["format"], name)


class SiteMaterialTest(unittest.TestCase):
    """A daemon started with a site's material library (GRIDSHELL_MATERIALS)."""

    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.mkdtemp(prefix="gridshell-materials-")
        cls.daemon = T.Daemon(env=T.material_library(cls.tmp))
        cls.client = gs.Client(cls.daemon.url)

    @classmethod
    def tearDownClass(cls):
        cls.daemon.stop()
        shutil.rmtree(cls.tmp, ignore_errors=True)

    def test_listed_after_the_built_in_materials(self):
        d = gs.describe(self.client, refresh=True)
        names = d.material_names()
        self.assertEqual(names[-1], T.SITE_MATERIAL["name"])
        # The built-in ones first, as the CLI lists them without the library.
        run = T.cli("options", "--json")
        self.assertEqual(run.returncode, 0, run.stderr)
        built_in = [m["name"] for m in json.loads(run.stdout)["materials"] if not m.get("site")]
        self.assertEqual(names[: len(built_in)], built_in)
        self.assertEqual(d.default_material, built_in[0])
        site = d.material(T.SITE_MATERIAL["name"])
        self.assertTrue(site["site"])
        for field, value in T.SITE_MATERIAL.items():
            self.assertEqual(site[field], value, field)
        self.assertIn(T.SITE_MATERIAL["name"], d.choices("simulation", "material"))
        self.assertIsNone(d.check("simulation", "material", T.SITE_MATERIAL["name"]))

    def test_a_run_with_it_uses_it(self):
        name = T.SITE_MATERIAL["name"]
        run = self.client.run(
            gs.mesh_example("double-vault"), None, QUICK, {"material": name, "notches": "on"}
        )
        options = run["simulation"]["deployment"]["options"]
        self.assertEqual(options["material"], name)
        self.assertEqual(options["young_modulus"], T.SITE_MATERIAL["young_modulus"])
        self.assertEqual(options["shear_modulus"], T.SITE_MATERIAL["shear_modulus"])
        self.assertEqual(options["bending_strength"], T.SITE_MATERIAL["bending_strength"])
        self.assertEqual(options["shear_strength"], T.SITE_MATERIAL["shear_strength"])
        # A daemon without the library does not know it: the field names the option.
        with T.Daemon() as plain:
            with self.assertRaises(gs.InvalidInput) as caught:
                gs.Client(plain.url).run(
                    gs.mesh_example("double-vault"), None, QUICK, {"material": name}
                )
        self.assertEqual(caught.exception.field, "simulation.material")


if __name__ == "__main__":
    unittest.main()
