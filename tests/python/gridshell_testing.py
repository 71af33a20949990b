# SPDX-License-Identifier: GPL-3.0-or-later
"""Test support shared by the Python client's tests and the CAD plugins' tests (tests/cad): a real
gridshelld on free loopback ports, started and stopped by the test, and the gridshell CLI.

Binaries come from $GRIDSHELL_BUILD (default: ./build of this checkout); $GRIDSHELLD and
$GRIDSHELL override each one. Only the standard library: Blender and FreeCAD import this too.
"""

import contextlib
import json
import os
import signal
import socket
import subprocess
import sys
import threading
import time

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
BUILD = os.environ.get("GRIDSHELL_BUILD", os.path.join(ROOT, "build"))
GRIDSHELLD = os.environ.get("GRIDSHELLD", os.path.join(BUILD, "gridshelld"))
GRIDSHELL = os.environ.get("GRIDSHELL", os.path.join(BUILD, "gridshell"))
MESHES = os.path.join(ROOT, "tests", "data", "meshes")  # real meshes with their licence
CLIENT_PATH = os.path.join(ROOT, "client", "python")

if CLIENT_PATH not in sys.path:
    sys.path.insert(0, CLIENT_PATH)


@contextlib.contextmanager
def refusing_port():
    """A TCP port on 127.0.0.1 where nobody listens, for as long as the ``with`` block lasts:
    bound here to port 0 (the kernel picks it) but never listened on, so every connection to it
    is refused and no other program can take it meanwhile."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind(("127.0.0.1", 0))
        yield s.getsockname()[1]


class Daemon:
    """gridshelld on 127.0.0.1 (any free ports unless ``http_port`` is given), its log kept.

    ``url`` is the HTTP address (http:// or https:// with TLS), ``log`` the JSON lines so far.
    ``env``: environment variables to set for the daemon (e.g. GRIDSHELL_MATERIALS), on top of
    this process's. Use as a context manager, or call ``stop()``.
    """

    def __init__(self, *args, http_port=0, tls=False, start_timeout=60, env=None):
        self.log = []
        self._lines = threading.Condition()
        command = [
            GRIDSHELLD,
            "--listen",
            "127.0.0.1:0",
            "--http",
            "127.0.0.1:%d" % http_port,
            "--no-static",
        ] + list(args)
        self.process = subprocess.Popen(
            command,
            stdin=subprocess.DEVNULL,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.PIPE,
            env=dict(os.environ, **env) if env else None,
        )
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()
        listening = self.wait_for(lambda e: e.get("event") == "listening", start_timeout)
        if listening is None:
            self.stop()
            raise RuntimeError("gridshelld did not start: %s" % "\n".join(map(str, self.log)))
        self.http = listening["http"]
        self.grpc = listening["grpc"]
        self.http_port = int(self.http.rsplit(":", 1)[1])
        self.url = ("https://" if tls else "http://") + self.http

    def _read(self):
        for raw in self.process.stderr:
            text = raw.decode("utf-8", "replace").strip()
            try:
                entry = json.loads(text)
            except ValueError:
                entry = {"text": text}
            with self._lines:
                self.log.append(entry)
                self._lines.notify_all()

    def wait_for(self, predicate, timeout, since=0):
        """The first log entry matching ``predicate`` within ``timeout`` seconds, else None.
        ``since``: look only at entries from that index on (``len(daemon.log)`` taken before the
        action whose entry the test waits for)."""
        end = time.monotonic() + timeout
        with self._lines:
            while True:
                for entry in self.log[since:]:
                    if isinstance(entry, dict) and predicate(entry):
                        return entry
                left = end - time.monotonic()
                if left <= 0 or self.process.poll() is not None:
                    return None
                self._lines.wait(min(left, 0.5))

    def requests(self, method=None):
        """Log lines of finished requests (optionally of one method, e.g. "Design")."""
        with self._lines:
            return [
                e
                for e in self.log
                if "method" in e and "status" in e and (method is None or e["method"] == method)
            ]

    def terminate(self):
        """SIGTERM: the daemon stops accepting, lets running work finish, then exits."""
        self.process.send_signal(signal.SIGTERM)

    def stop(self):
        if self.process.poll() is None:
            self.process.send_signal(signal.SIGTERM)
            try:
                self.process.wait(30)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait(10)
        self._reader.join(10)
        self.process.stderr.close()
        return self.process.returncode

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.stop()


# A site's material library (gridshell.v1.MaterialLibrary) with one material besides the built-in
# ones, for the daemon's GRIDSHELL_MATERIALS: the tests check that every client lists it from the
# daemon's description and that a simulation with it selected uses it.
SITE_MATERIAL = {
    "name": "test-larch",
    "label": "test larch",
    "young_modulus": 1.1e10,
    "shear_modulus": 0.7e9,
    "bending_strength": 7.0e7,
    "shear_strength": 8e6,
    "source": "test",
}


def material_library(folder):
    """Writes a material library with SITE_MATERIAL into ``folder``; returns the daemon's
    environment that names it (``Daemon(env=...)``)."""
    path = os.path.join(folder, "materials.json")
    with open(path, "w", encoding="utf-8") as f:
        json.dump({"materials": [SITE_MATERIAL]}, f)
    return {"GRIDSHELL_MATERIALS": path}


def cli(*args, timeout=600):
    """Runs the gridshell CLI; returns the CompletedProcess (text output)."""
    return subprocess.run(
        [GRIDSHELL] + [str(a) for a in args],
        stdin=subprocess.DEVNULL,
        capture_output=True,
        text=True,
        timeout=timeout,
    )


def write_obj(path, positions, indices):
    """An OBJ of packed arrays, every coordinate with 17 significant digits (read back exactly)."""
    lines = []
    for k in range(0, len(positions), 3):
        lines.append("v %.17g %.17g %.17g\n" % tuple(positions[k : k + 3]))
    for k in range(0, len(indices), 3):
        lines.append("f %d %d %d\n" % (indices[k] + 1, indices[k + 1] + 1, indices[k + 2] + 1))
    with open(path, "w", encoding="ascii") as f:
        f.writelines(lines)
