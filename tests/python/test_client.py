# SPDX-License-Identifier: GPL-3.0-or-later
"""Tests of the Python client (client/python/gridshell_client) against a real gridshelld on
loopback, started and stopped here: results, progress, files byte for byte as the CLI writes them,
errors with code/field/message, cancellation, deadlines, retries, token and TLS with a custom CA.

    python3 -m unittest discover -s tests/python -v
"""

import json
import os
import shutil
import subprocess
import tempfile
import threading
import time
import unittest

import gridshell_testing as T  # noqa: N812 (puts client/python on sys.path)

import gridshell_client as gs
from gridshell_client.client import encode_request

# A small, quick design: the hypar example at distance map resolution 16.
QUICK = {"resolution": 16}
# Long enough to cancel or to pass a deadline (seconds): double-vault at the finest maps.
SLOW = {"resolution": 1000}
# A plane's corners as a dart: a reflex corner, so the design is infeasible (paper 4.1 (iv)).
DART = [(-40, -30, 0), (40, -30, 0), (0, -10, 0), (-40, 30, 0)]


def square_grid(n=6, size=10.0, bump=1.0):
    """An (n+1) x (n+1) grid of a gentle dome as packed arrays, corners at its four corners."""
    positions, indices = [], []
    for j in range(n + 1):
        for i in range(n + 1):
            x, y = size * i / n, size * j / n
            u, v = 2 * i / n - 1, 2 * j / n - 1
            positions += [x, y, bump * (1 - 0.5 * (u * u + v * v))]
    for j in range(n):
        for i in range(n):
            a = j * (n + 1) + i
            b, c, d = a + 1, a + n + 2, a + n + 1
            indices += [a, b, c, a, c, d]
    corners = [0, n, (n + 1) * (n + 1) - 1, n * (n + 1)]
    return positions, indices, corners


class ClientTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        # No patch cache: every design computes its distance maps (and reports their progress).
        cls.daemon = T.Daemon("--cache-mib", "0")
        cls.client = gs.Client(cls.daemon.url)
        cls.tmp = tempfile.mkdtemp(prefix="gridshell-python-")

    @classmethod
    def tearDownClass(cls):
        cls.daemon.stop()
        shutil.rmtree(cls.tmp, ignore_errors=True)

    def test_health_and_examples(self):
        self.assertEqual(self.client.health(), "SERVING")
        names = [e["name"] for e in self.client.examples()["examples"]]
        self.assertIn("double-vault", names)
        self.assertIn("hypar", names)

    def test_design_streams_progress_and_returns_the_cli_bytes(self):
        # What `gridshell design example:hypar` sends: the example by name, its suggested corners.
        hypar = [e for e in self.client.examples()["examples"] if e["name"] == "hypar"][0]
        mesh = dict(gs.mesh_example("hypar"), name="example:hypar")
        corners = {"vertices": hypar["corners"], "label": "example"}
        events = []
        result = self.client.design(mesh, corners, options=QUICK, files=True, progress=events.append)
        self.assertTrue(events, "no progress event")
        for event in events:
            self.assertIsInstance(event, gs.Progress)
            self.assertTrue(event.stage)
            self.assertGreaterEqual(event.fraction, 0.0)
            self.assertLessEqual(event.fraction, 1.0)
        stages = {e.stage for e in events}
        self.assertIn("distance maps", stages)
        files = gs.files_of(result)
        self.assertEqual(
            set(files), {"planar.svg", "spatial.obj", "maps.svg", "design.json", "report.json"}
        )
        # The same request from the CLI (in-process) writes the same design.json, byte for byte.
        out = os.path.join(self.tmp, "hypar-cli")
        run = T.cli("design", "example:hypar", "--resolution", "16", "--out", out, "--quiet")
        self.assertEqual(run.returncode, 0, run.stderr)
        with open(os.path.join(out, "design.json"), "rb") as f:
            self.assertEqual(files["design.json"], f.read())
        with open(os.path.join(out, "planar.svg"), "rb") as f:
            self.assertEqual(files["planar.svg"], f.read())
        # The parsed result is the same message as the file.
        self.assertEqual(json.loads(files["design.json"]), result["design"])
        # Without a progress callback the call is a plain JSON POST with the same design.
        plain = self.client.design(mesh, corners, options=QUICK)
        self.assertEqual(plain["design"], result["design"])

    def test_mesh_forms_agree(self):
        positions, indices, corners = square_grid()
        flat = gs.mesh_arrays(positions, indices, name="dome")
        rows = gs.mesh_arrays(
            [positions[k : k + 3] for k in range(0, len(positions), 3)],
            [tuple(indices[k : k + 3]) for k in range(0, len(indices), 3)],
            name="dome",
        )
        self.assertEqual(flat, rows)
        obj = os.path.join(self.tmp, "dome.obj")
        T.write_obj(obj, positions, indices)
        from_file = gs.mesh_file(obj)
        self.assertEqual(from_file["name"], "dome.obj")
        self.assertEqual(from_file["format"], "obj")
        loaded = self.client.load(from_file)
        self.assertEqual(loaded["mesh"]["positions"], positions)
        self.assertEqual(loaded["mesh"]["indices"], indices)
        self.assertEqual(loaded["report"]["format"], "obj")
        self.assertEqual(loaded["report"]["vertices"], len(positions) // 3)
        with open(obj, "rb") as f:
            self.assertEqual(gs.mesh_file(f.read(), name="dome.obj"), from_file)
        # Arrays and file give the same design (the label aside: the name is the same).
        a = self.client.design(dict(flat, name="dome.obj"), corners=corners, options=QUICK)
        b = self.client.design(from_file, corners=corners, options=QUICK)
        self.assertEqual(a["design"], b["design"])
        self.assertEqual(a["design"]["options"]["corners"], ",".join(map(str, corners)))

    def test_simulate_takes_design_json_bytes_or_dict(self):
        designed = self.client.design(gs.mesh_example("hypar"), options=QUICK, files=True)
        raw = gs.files_of(designed)["design.json"]
        options = {"notches": "on", "edges_per_interval": 1, "unit": "cm"}
        from_bytes = self.client.simulate(raw, options=options, design_name="hypar")
        from_dict = self.client.simulate(designed["design"], options=options, design_name="hypar")
        a, b = from_bytes["deployment"], from_dict["deployment"]
        self.assertEqual(a["rods"], b["rods"])
        self.assertEqual(a["rms_with_notches"], b["rms_with_notches"])
        self.assertEqual(a["design"], "hypar")
        self.assertEqual(a["options"]["unit"], "cm")
        self.assertGreater(a["rms_with_notches"], 0)
        self.assertIn("deployed.obj", gs.files_of(from_bytes))

    def test_run_is_design_then_simulate(self):
        stages = []
        run = self.client.run(
            gs.mesh_example("hypar"),
            design_options=QUICK,
            simulation={"notches": "on", "edges_per_interval": 1},
            progress=lambda p: stages.append(p.stage),
        )
        self.assertIn("simulate with notches", stages)
        self.assertIn("distance maps", stages)
        alone = self.client.design(gs.mesh_example("hypar"), options=QUICK)
        self.assertEqual(run["design"]["design"], alone["design"])
        self.assertGreater(run["simulation"]["deployment"]["rms_with_notches"], 0)

    def test_layouts_automatic_and_run(self):
        knet = gs.mesh_file(os.path.join(T.MESHES, "knet1.obj"))
        cut = self.client.layout(knet, automatic={})
        self.assertGreaterEqual(cut["report"]["coverage"], 0.95)
        self.assertGreaterEqual(len(cut["report"]["automatic"]["trials"]), 1)
        # The layout it found, given back as a layout, is cut the same.
        again = self.client.layout(knet, layout=cut["report"]["layout"])
        self.assertAlmostEqual(again["report"]["coverage"], cut["report"]["coverage"], places=6)
        stages = []
        run = self.client.run_layout(
            knet,
            layout=cut["report"]["layout"],
            design_options={"members_u": 3, "members_v": 3},
            simulation={"notches": "on"},
            progress=lambda p: stages.append(p.stage),
        )
        self.assertIn("layout: patches designed and simulated", stages)
        whole = run["deployment"]
        self.assertEqual(len(whole["patches"]), len(cut["report"]["patches"]))
        self.assertTrue(whole["converged"])
        self.assertGreater(run["design"]["seam_bolts"], 0)
        with self.assertRaises(gs.InvalidInput) as caught:
            self.client.layout(knet, automatic={"coverage_goal": 2})
        self.assertEqual(caught.exception.field, "automatic.coverage_goal")
        # One patch of the layout designed alone, with the run's cross-section: its design in the
        # run (this daemon keeps no cache, so it cuts the layout again).
        p2 = run["patches"][1]["design"]["design"]
        options = {"members_u": 3, "members_v": 3,
                   "lamella_width": p2["options"]["lamella_width"]}
        alone = self.client.design(knet, options=options,
                                   layout_patch=(cut["report"]["layout"], "P2"))["design"]
        self.assertEqual(alone["alpha_bar"], p2["alpha_bar"])
        self.assertEqual(alone["crossings"], p2["crossings"])
        with self.assertRaises(gs.InvalidInput) as caught:
            self.client.design(knet, layout_patch=(cut["report"]["layout"], "P99"))
        self.assertEqual(caught.exception.field, "layout_patch.patch")
        with self.assertRaises(ValueError):
            self.client.design(knet, corners=[0, 1, 2, 3], layout_patch=(cut["report"]["layout"], "P2"))

    def test_invalid_input_names_the_field(self):
        positions, indices, corners = square_grid()
        positions[7] = float("nan")
        with self.assertRaises(gs.InvalidInput) as caught:
            self.client.design(gs.mesh_arrays(positions, indices), corners=corners)
        e = caught.exception
        self.assertEqual(e.status, "INVALID_ARGUMENT")
        self.assertEqual(e.code, 3)
        self.assertEqual(e.http_status, 400)
        self.assertEqual(e.field, "mesh.positions[7]")
        self.assertIn("NaN", e.message)
        self.assertEqual(str(e), "mesh.positions[7]: " + e.message)
        # An option out of range, with and without the event stream.
        for progress in (None, lambda p: None):
            with self.assertRaises(gs.InvalidInput) as caught:
                self.client.design(
                    gs.mesh_example("hypar"), options={"eta_max": 0.5}, progress=progress
                )
            self.assertEqual(caught.exception.field, "options.eta_max")
        with self.assertRaises(gs.InvalidInput) as caught:
            self.client.design(gs.mesh_example("no-such-surface"))
        self.assertEqual(caught.exception.field, "mesh.example")
        with self.assertRaises(gs.InvalidInput) as caught:
            self.client.design(gs.mesh_example("hypar"), corners=[1, 2, 3])
        self.assertEqual(caught.exception.field, "corners")
        self.assertEqual(self.client.health(), "SERVING")

    def test_infeasible_design_is_infeasible(self):
        for progress in (None, lambda p: None):
            with self.assertRaises(gs.Infeasible) as caught:
                self.client.design(
                    gs.mesh_example("plane"), corners=DART, options=QUICK, progress=progress
                )
            e = caught.exception
            self.assertEqual(e.status, "FAILED_PRECONDITION")
            self.assertEqual(e.http_status, 422)
            self.assertIn("criterion iv", e.message)
            self.assertEqual(e.suggestions, e.details.get("suggestions", []))

    def test_cancel_stops_the_work_on_the_daemon(self):
        cancel = gs.Cancel()
        in_maps = threading.Event()
        outcome = {}

        def progress(p):
            if p.stage == "distance maps":
                in_maps.set()

        def work():
            try:
                self.client.design(
                    gs.mesh_example("double-vault"), options=SLOW, cancel=cancel, progress=progress
                )
                outcome["result"] = "finished"
            except gs.GridshellError as e:
                outcome["error"] = e
                # What the daemon had logged of the job when the call returned.
                outcome["logged"] = [e for e in self.daemon.log[since:] if e.get("method") == "Design"]

        since = len(self.daemon.log)
        thread = threading.Thread(target=work)
        thread.start()
        self.assertTrue(in_maps.wait(120), "no progress of the distance maps")
        cancel.cancel()
        thread.join(120)  # a bound against a hang, not a speed requirement
        self.assertFalse(thread.is_alive())
        self.assertIsInstance(outcome.get("error"), gs.Cancelled, outcome)
        # The call returned at once, not at the work's end: the daemon had not finished the job
        # (no line with an OK status), and it cancelled it, seeing the client go.
        self.assertFalse([e for e in outcome["logged"] if e.get("status") == "OK"], outcome)
        entry = self.daemon.wait_for(
            lambda e: e.get("method") == "Design" and e.get("status") == "CANCELLED", 30, since=since
        )
        self.assertIsNotNone(entry, self.daemon.log[since:])
        self.assertEqual(self.client.health(), "SERVING")
        # A call with a cancelled flag does not start.
        with self.assertRaises(gs.Cancelled):
            self.client.examples(cancel=cancel)

    def test_deadline(self):
        since = len(self.daemon.log)
        with self.assertRaises(gs.DeadlineExceeded) as caught:
            self.client.design(
                gs.mesh_example("double-vault"), options=SLOW, timeout=0.3
            )
        self.assertEqual(caught.exception.status, "DEADLINE_EXCEEDED")
        entry = self.daemon.wait_for(lambda e: e.get("status") == "DEADLINE_EXCEEDED", 30, since=since)
        self.assertIsNotNone(entry)
        with self.assertRaises(gs.InvalidInput) as caught:
            self.client.examples(timeout=-1)
        self.assertEqual(caught.exception.field, "timeout")

    def test_unknown_method(self):
        with self.assertRaises(gs.GridshellError) as caught:
            self.client.call("frobnicate", {})
        self.assertEqual(caught.exception.http_status, 404)
        self.assertEqual(caught.exception.status, "NOT_FOUND")

    def test_encoding(self):
        self.assertEqual(
            encode_request({"a": gs.RawJSON(b' {"x": [1, 2]} '), "b": {"c": 1.5}}),
            b'{"a":{"x": [1, 2]},"b":{"c":1.5}}',
        )
        self.assertEqual(
            json.loads(encode_request({"v": [1.0, float("inf"), float("nan")]})),
            {"v": [1.0, "Infinity", "NaN"]},
        )


class UnreachableTest(unittest.TestCase):
    def test_nobody_listening(self):
        """Refused connections are retried `retries` times, then raised; nothing more."""
        with T.refusing_port() as port:
            client = gs.Client("127.0.0.1:%d" % port, retries=2, backoff=0.05)
            events = []
            with self.assertRaises(gs.Unavailable) as caught:
                client.examples(progress=events.append)
            self.assertIn("cannot reach http://127.0.0.1:%d" % port, str(caught.exception))
            self.assertEqual([e.stage for e in events], ["gridshelld unavailable, retry 1 of 2",
                                                         "gridshelld unavailable, retry 2 of 2"])
            with self.assertRaises(gs.Unavailable):
                client.health()

    def test_bad_addresses(self):
        for server, field in [
            ("", "server"),
            ("ftp://x:1", "server"),
            ("http://127.0.0.1:notaport", "server"),
        ]:
            with self.assertRaises(gs.InvalidInput) as caught:
                gs.Client(server)
            self.assertEqual(caught.exception.field, field)
        with self.assertRaises(gs.InvalidInput) as caught:
            gs.Client("http://127.0.0.1:1", ca_file="/nonexistent")
        self.assertEqual(caught.exception.field, "ca_file")

    def test_retry_until_the_daemon_is_up(self):
        """A refused call is tried again with backoff; a daemon that starts meanwhile answers."""
        # The port: one the kernel gave a daemon (bound to port 0), free again once it stopped.
        # The new daemon binds it again after the client's first refused attempt.
        with T.Daemon() as first:
            port = first.http_port
        client = gs.Client("127.0.0.1:%d" % port, retries=8, backoff=0.2, backoff_max=1.0)
        outcome = {}
        refused = threading.Event()

        def progress(p):
            if p.stage.startswith("gridshelld unavailable"):
                refused.set()

        def work():
            try:
                outcome["result"] = client.examples(progress=progress)
            except gs.GridshellError as e:
                outcome["error"] = e

        thread = threading.Thread(target=work)
        thread.start()
        self.assertTrue(refused.wait(60), "the first attempt was not refused")
        with T.Daemon(http_port=port) as daemon:
            thread.join(30)
            self.assertNotIn("error", outcome)
            self.assertIn("examples", outcome["result"])
            # The daemon logs a request after it answered: wait for the line, then count.
            logged = daemon.wait_for(lambda e: e.get("method") == "Examples" and "status" in e, 10)
            self.assertIsNotNone(logged, daemon.log)
            self.assertEqual(len(daemon.requests("Examples")), 1)

    def test_unavailable_is_retried_a_bounded_number_of_times(self):
        """A daemon shutting down answers 503 (UNAVAILABLE): retried `retries` times, then raised."""
        with T.Daemon("--shutdown-grace", "30") as daemon:
            client = gs.Client(daemon.url, retries=2, backoff=0.05)
            busy = gs.Cancel()
            started = threading.Event()
            thread = threading.Thread(
                target=lambda: self.assertRaises(
                    gs.GridshellError,
                    client.design,
                    gs.mesh_example("double-vault"),
                    options=SLOW,
                    progress=lambda p: started.set(),
                    cancel=busy,
                )
            )
            thread.start()
            self.assertTrue(started.wait(60), "the design did not start")
            daemon.terminate()  # running work may finish; new calls get UNAVAILABLE
            self.assertIsNotNone(daemon.wait_for(lambda e: e.get("event") == "shutting down", 10))
            # The daemon logs "shutting down" just before it stops accepting: probe (no retries)
            # until it refuses.
            probe = gs.Client(daemon.url, retries=0)
            refused = lambda: [e for e in daemon.requests("Examples") if e["status"] == "UNAVAILABLE"]  # noqa: E731
            end = time.monotonic() + 10
            while not refused() and time.monotonic() < end:
                try:
                    probe.examples()
                except gs.Unavailable:
                    daemon.wait_for(lambda e: len(refused()) >= 1, 10)
            before = len(refused())
            self.assertGreaterEqual(before, 1)
            with self.assertRaises(gs.Unavailable) as caught:
                client.examples()
            self.assertEqual(caught.exception.http_status, 503)
            # The call and two retries, each logged (the log line may follow the answer).
            daemon.wait_for(lambda e: len(refused()) >= before + 3, 10)
            self.assertEqual(len(refused()), before + 3)
            busy.cancel()
            thread.join(30)


def make_certificate(folder):
    """A CA and a certificate for 127.0.0.1 signed by it (openssl), as PEM files."""

    def openssl(*args):
        subprocess.run(["openssl"] + list(args), check=True, capture_output=True, cwd=folder)

    openssl("req", "-x509", "-newkey", "rsa:2048", "-nodes", "-days", "2", "-subj",
            "/CN=gridshell test CA", "-keyout", "ca.key", "-out", "ca.pem")
    openssl("req", "-newkey", "rsa:2048", "-nodes", "-subj", "/CN=127.0.0.1",
            "-keyout", "server.key", "-out", "server.csr")
    with open(os.path.join(folder, "san.ext"), "w") as f:
        f.write("subjectAltName=IP:127.0.0.1\n")
    openssl("x509", "-req", "-in", "server.csr", "-CA", "ca.pem", "-CAkey", "ca.key",
            "-CAcreateserial", "-days", "2", "-extfile", "san.ext", "-out", "server.pem")
    return {name: os.path.join(folder, name) for name in ("ca.pem", "server.pem", "server.key")}


@unittest.skipIf(shutil.which("openssl") is None, "needs openssl")
class SecurityTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.mkdtemp(prefix="gridshell-tls-")
        cls.pem = make_certificate(cls.tmp)
        cls.token_file = os.path.join(cls.tmp, "token")
        with open(cls.token_file, "w") as f:
            f.write("s3cret-token\n")
        cls.daemon = T.Daemon(
            "--tls-cert", cls.pem["server.pem"], "--tls-key", cls.pem["server.key"],
            "--token-file", cls.token_file, tls=True,
        )

    @classmethod
    def tearDownClass(cls):
        cls.daemon.stop()
        shutil.rmtree(cls.tmp, ignore_errors=True)

    def test_tls_with_custom_ca_and_token(self):
        client = gs.Client(self.daemon.url, ca_file=self.pem["ca.pem"], token="s3cret-token")
        self.assertEqual(client.health(), "SERVING")
        events = []
        result = client.design(gs.mesh_example("hypar"), options=QUICK, progress=events.append)
        self.assertTrue(events)
        self.assertGreater(len(result["design"]["members"]), 4)
        from_file = gs.Client(self.daemon.url, ca_file=self.pem["ca.pem"], token_file=self.token_file)
        self.assertIn("examples", from_file.examples())

    def test_wrong_or_missing_token(self):
        for token in (None, "wrong"):
            client = gs.Client(self.daemon.url, ca_file=self.pem["ca.pem"], token=token)
            with self.assertRaises(gs.Unauthenticated) as caught:
                client.examples()
            self.assertEqual(caught.exception.http_status, 401)
            with self.assertRaises(gs.Unauthenticated):
                client.health()

    def test_unknown_ca_is_refused(self):
        client = gs.Client(self.daemon.url, token="s3cret-token", retries=0)
        with self.assertRaises(gs.Unavailable) as caught:
            client.examples()
        self.assertIn("certificate", str(caught.exception))
        plain = gs.Client(self.daemon.url.replace("https", "http"), retries=0)
        with self.assertRaises(gs.Unavailable):
            plain.examples()


if __name__ == "__main__":
    unittest.main()
