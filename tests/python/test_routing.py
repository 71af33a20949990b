# SPDX-License-Identifier: GPL-3.0-or-later
"""The Python client and the replica contract of docs/api.md (issues 20 and 21), against a real
gridshelld on loopback behind a small recording proxy started here:

- the X-Gridshell-Patch-Key it sends on Design and Run equals the daemon's own
  ``report.patch_key``, for packed arrays, a file's bytes and a mesh the loader repairs (welded
  duplicates, an isolated vertex, a flipped face), vertex and point corners, options;
- retries exactly as "Retries" documents: 502, 503, refused connections and cut event streams are
  retried at most 5 times with the documented waits and progress; other statuses never.

    python3 -m unittest discover -s tests/python -t tests/python -v -k Routing
"""

import http.client
import http.server
import json
import os
import shutil
import socket
import tempfile
import threading
import time
import unittest

import gridshell_testing as T  # noqa: N812 (puts client/python on sys.path)

import gridshell_client as gs
from gridshell_client import client as gsclient
from gridshell_client import routing

QUICK = {"resolution": 16}
KEY = "x-gridshell-patch-key"
# The error bodies the proxy answers with: HTTP status -> the gRPC code and name the gateway gives.
STATUSES = {
    400: (3, "INVALID_ARGUMENT"),
    401: (16, "UNAUTHENTICATED"),
    413: (8, "RESOURCE_EXHAUSTED"),
    429: (8, "RESOURCE_EXHAUSTED"),
    500: (13, "INTERNAL"),
    502: (14, "UNAVAILABLE"),
    503: (14, "UNAVAILABLE"),
    504: (4, "DEADLINE_EXCEEDED"),
}


def dome(n=6, size=10.0):
    """An (n+1) x (n+1) grid of a gentle dome as packed arrays, and its four corner vertices."""
    positions, indices = [], []
    for j in range(n + 1):
        for i in range(n + 1):
            u, v = 2 * i / n - 1, 2 * j / n - 1
            positions += [size * i / n, size * j / n, 1.0 - 0.5 * (u * u + v * v)]
    for j in range(n):
        for i in range(n):
            a = j * (n + 1) + i
            indices += [a, a + 1, a + n + 2, a, a + n + 2, a + n + 1]
    return positions, indices, [0, n, (n + 1) * (n + 1) - 1, n * (n + 1)]


def damaged(positions, indices, corners):
    """The dome as a mesh the loader repairs: an isolated vertex first (every index shifts), each
    face of the upper half on its own copies of its vertices (welded back), the first face
    flipped (its orientation fixed). Corners are indices into these arrays."""
    out = [50.0, 50.0, 50.0] + list(positions)
    faces = [i + 1 for i in indices]
    faces[0], faces[1] = faces[1], faces[0]
    half = len(faces) // 2 // 3 * 3
    for k in range(half, len(faces)):
        vertex = faces[k] - 1
        faces[k] = len(out) // 3
        out += positions[3 * vertex : 3 * vertex + 3]
    return out, faces, [c + 1 for c in corners]


class Proxy:
    """An HTTP server on 127.0.0.1:0 that records every request's path and headers and, for each
    request of the planned method in turn, follows ``plan``: an HTTP status (answered itself with an API error body),
    ``"cut"`` (an event stream's headers and one progress event, then the connection closed), or
    ``"pass"`` (forwarded to the daemon, the answer given back). When the plan is used up it
    passes everything on."""

    def __init__(self, upstream):
        self.upstream = upstream
        self.plan, self.planned, self.seen = [], "design", []
        self.lock = threading.Lock()
        proxy = self

        class Handler(http.server.BaseHTTPRequestHandler):
            protocol_version = "HTTP/1.1"

            def log_message(self, *args):
                pass

            def do_POST(self):  # noqa: N802 (the http.server name)
                body = self.rfile.read(int(self.headers.get("Content-Length", 0)))
                with proxy.lock:
                    proxy.seen.append((self.path, {k.lower(): v for k, v in self.headers.items()}))
                    planned = proxy.plan and self.path == "/v1/" + proxy.planned
                    step = proxy.plan.pop(0) if planned else "pass"
                if step == "cut":
                    self.send_response(200)
                    self.send_header("Content-Type", "text/event-stream")
                    self.send_header("Connection", "close")
                    self.end_headers()
                    self.wfile.write(b'event: progress\ndata: {"stage":"distance maps"}\n\n')
                    self.wfile.flush()
                    self.close_connection = True
                    return
                if step == "pass":
                    status, kind, data = proxy.forward(self.path, self.headers, body)
                else:
                    status, kind = step, "application/json"
                    code, name = STATUSES[step]
                    data = json.dumps(
                        {"error": {"code": code, "status": name, "message": "proxy %d" % step}}
                    ).encode()
                self.send_response(status)
                self.send_header("Content-Type", kind)
                self.send_header("Content-Length", str(len(data)))
                self.send_header("Connection", "close")
                self.end_headers()
                self.wfile.write(data)
                self.close_connection = True

        self.server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), Handler)
        self.server.daemon_threads = True
        self.url = "http://127.0.0.1:%d" % self.server.server_address[1]
        self.thread = threading.Thread(target=self.server.serve_forever, daemon=True)
        self.thread.start()

    def forward(self, path, headers, body):
        host, port = self.upstream.rsplit(":", 1)
        connection = http.client.HTTPConnection(host, int(port), timeout=120)
        try:
            sent = {k: v for k, v in headers.items() if k.lower() not in ("host", "connection")}
            connection.request("POST", path, body, sent)
            answer = connection.getresponse()
            return answer.status, answer.getheader("Content-Type", ""), answer.read()
        finally:
            connection.close()

    def reset(self, plan=(), method="design"):
        """Forgets what was seen; ``plan`` applies to the calls of ``method`` alone."""
        with self.lock:
            self.plan, self.planned, self.seen = list(plan), method, []

    def calls(self, method):
        with self.lock:
            return [headers for path, headers in self.seen if path == "/v1/" + method]

    def close(self):
        self.server.shutdown()
        self.server.server_close()


def setUpModule():  # noqa: N802 (unittest's name)
    global DAEMON, PROXY
    DAEMON = T.Daemon()
    PROXY = Proxy(DAEMON.http)


def tearDownModule():  # noqa: N802
    PROXY.close()
    DAEMON.stop()


class RoutingKeyTest(unittest.TestCase):
    """The key sent equals the daemon's report.patch_key."""

    def setUp(self):
        PROXY.reset()
        self.client = gs.Client(PROXY.url, backoff=0.01)

    def design_key(self, mesh, corners=None, options=QUICK, client=None):
        """Designs once; returns (the key the proxy saw on the Design, the daemon's key)."""
        PROXY.reset()
        result = (client or self.client).design(mesh, corners, options)
        sent = PROXY.calls("design")
        self.assertEqual(len(sent), 1)
        self.assertIn(KEY, sent[0], "no patch key sent")
        self.assertRegex(sent[0][KEY], r"\A[0-9a-f]{32}\Z")
        return sent[0][KEY], result["report"]["patch_key"]

    def test_arrays_points_automatic_and_options(self):
        positions, indices, corners = dome()
        mesh = gs.mesh_arrays(positions, indices, name="dome")
        points = [positions[3 * c : 3 * c + 3] for c in corners]
        seen = set()
        for n, (request_corners, options) in enumerate([
            (corners, QUICK),
            (points, QUICK),
            (None, QUICK),
            (corners, {"resolution": 24, "eta_max": 1.003}),
            (corners, {"resolution": "24", "eta_max": "1.003", "geodesic_method": "fast"}),
        ]):
            sent, daemon = self.design_key(mesh, request_corners, options)
            # Only the first design on a mesh asks the daemon to load it.
            self.assertEqual(len(PROXY.calls("load")), 1 if n == 0 else 0)
            self.assertEqual(sent, daemon, (request_corners, options))
            self.assertEqual(self.client.patch_key(mesh, request_corners, options), daemon)
            seen.add(sent)
        # String and number forms of one value share a key; different values do not.
        self.assertEqual(len(seen), 4)
        # Another Client of the process (the plugins make one per operation) loads it no more.
        sent, daemon = self.design_key(mesh, corners, QUICK, gs.Client(PROXY.url))
        self.assertEqual(len(PROXY.calls("load")), 0)
        self.assertEqual(sent, daemon)

    def test_a_file_the_loader_repairs(self):
        positions, indices, corners = dome()
        sent_positions, sent_indices, sent_corners = damaged(positions, indices, corners)
        folder = tempfile.mkdtemp(prefix="gridshell-routing-")
        self.addCleanup(shutil.rmtree, folder, True)
        obj = os.path.join(folder, "damaged.obj")
        T.write_obj(obj, sent_positions, sent_indices)
        loaded = self.client.load(gs.mesh_file(obj))
        self.assertEqual(loaded["report"]["vertices"], len(positions) // 3, loaded["report"])
        self.assertTrue(loaded.get("vertex_map"), "the loader renumbered: a vertex map expected")
        # The key of the sent arrays is not the daemon's: the repairs matter.
        naive = routing.patch_key(sent_positions, sent_indices, {"vertices": sent_corners}, QUICK)
        for mesh in [gs.mesh_file(obj), gs.mesh_arrays(sent_positions, sent_indices, name="d")]:
            sent, daemon = self.design_key(mesh, sent_corners)
            self.assertEqual(sent, daemon)
            self.assertNotEqual(naive, daemon)
            sent, daemon = self.design_key(mesh, None)
            self.assertEqual(sent, daemon)

    def test_example_and_run(self):
        mesh = gs.mesh_example("hypar")
        sent, daemon = self.design_key(mesh)
        self.assertEqual(sent, daemon)
        PROXY.reset()
        run = self.client.run(mesh, None, QUICK, {"notches": "on", "edges_per_interval": 1})
        self.assertEqual(PROXY.calls("run")[0][KEY], run["design"]["report"]["patch_key"])
        self.assertEqual(PROXY.calls("run")[0][KEY], daemon)
        # Calls that do not use the patch cache go without a key.
        PROXY.reset()
        self.client.simulate(run["design"]["design"], {"edges_per_interval": 1})
        self.client.examples()
        self.assertTrue(all(KEY not in headers for _, headers in PROXY.seen))

    def test_a_refused_mesh_goes_without_a_key(self):
        """No key rather than a wrong one: the daemon's own answer names the problem."""
        with self.assertRaises(gs.InvalidInput) as caught:
            self.client.design(gs.mesh_arrays([0, 0, 0, 1, 0, 0], [0, 1, 2]), None, QUICK)
        self.assertTrue(caught.exception.field.startswith("mesh"), caught.exception.field)
        self.assertNotIn(KEY, PROXY.calls("design")[0])


class RetryTest(unittest.TestCase):
    """docs/api.md "Retries": which answers are retried, how often, how long, with what progress."""

    def test_waits(self):
        # The k-th wait is min(4, 0.25 * 2^(k-1)) s times a factor in [0.5, 1).
        self.assertEqual(gsclient.RETRIES, 5)
        for k, full in enumerate([0.25, 0.5, 1.0, 2.0, 4.0, 4.0], start=1):
            self.assertAlmostEqual(gsclient.retry_delay(k, draw=lambda: 0.0), full / 2)
            self.assertAlmostEqual(gsclient.retry_delay(k, draw=lambda: 0.999999), full, places=5)
        total = [sum(gsclient.retry_delay(k, draw=lambda: d) for k in range(1, 6)) for d in (0, 1)]
        self.assertAlmostEqual(total[0], 3.875)
        self.assertAlmostEqual(total[1], 7.75)

    def call(self, plan, retries=gsclient.RETRIES, **call):
        PROXY.reset(plan)
        client = gs.Client(PROXY.url, retries=retries, backoff=0.01, backoff_max=0.04)
        events = []
        try:
            return client.design(gs.mesh_example("hypar"), None, QUICK,
                                 progress=events.append, **call), events
        finally:
            self.events = events

    def test_502_503_and_cut_streams_are_retried(self):
        result, events = self.call([503, 502, "cut", 503])
        self.assertIn("patch_key", result["report"])
        self.assertEqual(len(PROXY.calls("design")), 5)
        notices = [e for e in events if e.stage.startswith("gridshelld unavailable")]
        self.assertEqual([e.stage for e in notices],
                         ["gridshelld unavailable, retry %d of 5" % k for k in range(1, 5)])
        self.assertIn("proxy 503", notices[0].message)
        # Every attempt carries the same key.
        self.assertEqual(len({h[KEY] for h in PROXY.calls("design")}), 1)

    def test_at_most_five_retries(self):
        with self.assertRaises(gs.Unavailable) as caught:
            self.call([503] * 10)
        self.assertEqual(caught.exception.http_status, 503)
        self.assertEqual(len(PROXY.calls("design")), 6)
        with self.assertRaises(gs.Unavailable):
            self.call([502] * 3, retries=2)
        self.assertEqual(len(PROXY.calls("design")), 3)

    def test_answers_are_not_retried(self):
        for status, kind in [(400, gs.InvalidInput), (401, gs.Unauthenticated),
                             (413, gs.ResourceExhausted), (429, gs.ResourceExhausted), (500, gs.InternalError),
                             (504, gs.DeadlineExceeded)]:
            with self.assertRaises(kind, msg=status):
                self.call([status])
            self.assertEqual(len(PROXY.calls("design")), 1, status)
            self.assertFalse([e for e in self.events if "unavailable" in e.stage], status)

    def test_no_retry_after_cancel_or_past_the_deadline(self):
        PROXY.reset([503] * 10, "examples")
        # An hour before the first retry: the call can only come back if the cancel ends that
        # wait (the thread's join below is a bound against a hang, not a speed requirement).
        client = gs.Client(PROXY.url, backoff=3600, backoff_max=3600)
        cancel = gs.Cancel()
        waiting = threading.Event()
        outcome = {}

        def work():
            try:
                client.examples(cancel=cancel, progress=lambda p: waiting.set())
            except gs.GridshellError as e:
                outcome["error"] = e

        thread = threading.Thread(target=work, daemon=True)
        thread.start()
        self.assertTrue(waiting.wait(60), "no retry announced")  # the wait before retry 1
        cancel.cancel()
        thread.join(120)
        self.assertFalse(thread.is_alive(), "the wait before the retry did not end at the cancel")
        self.assertIsInstance(outcome.get("error"), gs.Cancelled, outcome)
        self.assertEqual(len(PROXY.calls("examples")), 1)
        # A 1 s deadline: the first wait would end past it, so the 503 is the answer.
        PROXY.reset([503] * 10, "examples")
        with self.assertRaises(gs.Unavailable):
            client.examples(timeout=1)
        self.assertEqual(len(PROXY.calls("examples")), 1)

    def test_refused_connections_are_retried(self):
        with socket.socket() as s:
            s.bind(("127.0.0.1", 0))
            port = s.getsockname()[1]  # bound, not listening: connections are refused
            client = gs.Client("127.0.0.1:%d" % port, retries=3, backoff=0.01, backoff_max=0.02)
            events = []
            with self.assertRaises(gs.Unavailable):
                client.call("examples", {}, progress=events.append)
        self.assertEqual([e.stage for e in events],
                         ["gridshelld unavailable, retry %d of 3" % k for k in range(1, 4)])


if __name__ == "__main__":
    unittest.main()
