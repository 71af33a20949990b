# SPDX-License-Identifier: GPL-3.0-or-later
"""A client of gridshelld's HTTP/JSON API (docs/api.md), standard library only.

It loads in any Python 3.8+ (Blender's and FreeCAD's included) and speaks exactly what the API
documents: ``POST /v1/NAME`` with the request message in protobuf's JSON mapping, the result
message back, or with a progress callback the same call as Server-Sent Events (progress events,
then the result). Results are the API's JSON as Python dicts and lists.

    from gridshell_client import Client, mesh_example
    client = Client("http://127.0.0.1:8080")
    result = client.design(mesh_example("double-vault"), progress=print)
    print(result["design"]["alpha_bar"])

Cancelling: pass a ``Cancel`` and call its ``cancel()`` from any thread; the call's connection is
shut, the daemon stops the work within milliseconds (a client that goes away cancels its job) and
the call raises ``Cancelled``. Deadlines: ``timeout`` seconds per call, sent as ``X-Timeout-Ms``
(the daemon stops the work when it passes) and kept by the client too.

Replicas (docs/api.md, "Replicas and the patch key" and "Retries"): Design and Run carry the
patch routing key (``X-Gridshell-Patch-Key``, routing.py) so that a proxy sends every design on
one patch to the replica that has its work cached; a call the daemon could not answer (refused or
cut connection, 502, 503, an event stream cut before its result) is made again, at most 5 times,
after 0.25 s doubling to 4 s, each wait times a random factor in [0.5, 1), within the deadline and
never after a cancel.
"""

import base64
import collections
import hashlib
import http.client
import json
import math
import random
import socket
import ssl
import threading
import time
import urllib.parse

from . import errors, routing
from .errors import (
    Cancelled,
    DeadlineExceeded,
    GridshellError,
    InternalError,
    InvalidInput,
    Unavailable,
)

__all__ = ["Client", "Cancel", "Progress", "RawJSON", "files_of"]

USER_AGENT = "gridshell-python/0.1"

# Every API method is a pure function of its request (the same request gives the same result on
# any daemon), so trying it again on another replica is safe.
IDEMPOTENT_METHODS = frozenset(
    ["patch", "design", "simulate", "run", "geodesic", "load", "examples", "options"]
)
# The calls that use the daemon's per-patch cache and so carry the patch routing key.
ROUTED_METHODS = frozenset(["design", "run"])
PATCH_KEY_HEADER = "X-Gridshell-Patch-Key"

# The retry policy of docs/api.md ("Retries"), the same numbers as the CLI and the web page: at
# most RETRIES more attempts, the k-th after min(BACKOFF_MAX, BACKOFF * 2^(k-1)) seconds times a
# random factor in [0.5, 1).
RETRIES = 5
BACKOFF = 0.25
BACKOFF_MAX = 4.0
# HTTP statuses the daemon did not answer itself (the proxy found no replica, or lost the one
# serving the call) or answered because it is shutting down: the call is made again.
RETRY_STATUSES = frozenset([502, 503])
# Meshes whose loaded form (for the patch key) the process remembers, least recently used dropped.
MESH_MEMO = 8
# (server, mesh identity) -> routing.MeshDigest or None, shared by every Client of the process: the
# plugins make a new Client per operation, and the loaded form of a mesh is the daemon's, not the
# client's.
_MESHES = collections.OrderedDict()
_MESHES_LOCK = threading.Lock()


def retry_delay(retry, backoff=BACKOFF, backoff_max=BACKOFF_MAX, draw=random.random):
    """Seconds to wait before the ``retry``-th retry (1-based): min(backoff_max, backoff *
    2^(retry-1)) times a random factor in [0.5, 1), so that many clients do not return in step."""
    return min(backoff_max, backoff * 2.0 ** (retry - 1)) * (0.5 + 0.5 * draw())


def retry_stage(retry, retries):
    """The progress stage shown while a call waits for its ``retry``-th retry."""
    return "gridshelld unavailable, retry %d of %d" % (retry, retries)

Progress = collections.namedtuple("Progress", "stage fraction message")
Progress.__doc__ = """One progress event: the kernel's stage name, the fraction (0..1) of that
stage done, and a note (the queue position while waiting, else empty)."""


class RawJSON:
    """JSON text to put into a request as it is (e.g. a design.json's bytes as
    ``SimulateRequest.design``): neither parsed nor printed again."""

    __slots__ = ("text",)

    def __init__(self, text):
        if isinstance(text, (bytes, bytearray)):
            text = bytes(text).decode("utf-8")
        if not isinstance(text, str):
            raise TypeError("RawJSON takes str or bytes, got %s" % type(text).__name__)
        self.text = text.strip()


class Cancel:
    """A cancellation flag shared between the thread that makes a call and any other thread.

    ``cancel()`` sets the flag and shuts the connection of every call running with it, so a call
    waiting for the daemon returns at once (raising ``Cancelled``); the daemon sees the
    connection close and cancels the work.
    """

    def __init__(self):
        self._event = threading.Event()
        self._lock = threading.Lock()
        self._lines = set()

    @property
    def cancelled(self):
        return self._event.is_set()

    def cancel(self):
        with self._lock:
            self._event.set()
            lines = list(self._lines)
        for line in lines:
            _shut(line)

    def wait(self, seconds):
        """Sleeps up to ``seconds``; True when cancelled meanwhile."""
        return self._event.wait(seconds)

    def _attach(self, line):
        with self._lock:
            if self._event.is_set():
                return False
            self._lines.add(line)
            return True

    def _detach(self, line):
        with self._lock:
            self._lines.discard(line)


class _Line:
    """The socket of one call (None until connected)."""

    __slots__ = ("sock",)

    def __init__(self):
        self.sock = None

    def close(self):
        if self.sock is not None:
            self.sock.close()


def _shut(line):
    """Ends a call's connection from another thread: a blocked read returns (EOF) at once."""
    sock = line.sock
    if sock is None:
        return
    try:
        # The plain socket's shutdown also for TLS: SSLSocket.shutdown would drop the TLS state
        # under the reading thread's feet.
        socket.socket.shutdown(sock, socket.SHUT_RDWR)
    except OSError:
        pass


def files_of(result):
    """The ``views`` of a result (``File {name, content}``, content base64 in JSON) as a dict of
    file name -> bytes: ``files_of(result)["planar.svg"]``."""
    views = result.get("views", []) if isinstance(result, dict) else []
    return {view["name"]: base64.b64decode(view.get("content", "")) for view in views}


def _finite_json(value):
    """Non-finite floats as protobuf's JSON mapping writes them ("NaN", "Infinity")."""
    if isinstance(value, float) and not math.isfinite(value):
        return "NaN" if math.isnan(value) else ("Infinity" if value > 0 else "-Infinity")
    if isinstance(value, dict):
        return {k: _finite_json(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_finite_json(v) for v in value]
    return value


def _dumps(value):
    try:
        return json.dumps(value, separators=(",", ":"), allow_nan=False, ensure_ascii=False)
    except ValueError:
        # Rare: send NaN as the API's "NaN", so the daemon answers with the field that holds it.
        return json.dumps(_finite_json(value), separators=(",", ":"), ensure_ascii=False)


def encode_request(request):
    """A request (dicts, lists, numbers, strings; RawJSON anywhere in the dicts) as JSON bytes."""

    def encode(value):
        if isinstance(value, RawJSON):
            return value.text
        if isinstance(value, dict) and _holds_raw(value):
            return (
                "{"
                + ",".join(json.dumps(str(k)) + ":" + encode(v) for k, v in value.items())
                + "}"
            )
        return _dumps(value)

    return encode(request).encode("utf-8")


def _holds_raw(value):
    return any(
        isinstance(v, RawJSON) or (isinstance(v, dict) and _holds_raw(v)) for v in value.values()
    )


class _Retry(Exception):
    """An attempt that may be made again (refused or cut connection, 502, 503, a cut stream)."""

    def __init__(self, error):
        super().__init__(str(error))
        self.error = error


class Client:
    """A client of one gridshelld HTTP endpoint (or a load balancer in front of replicas).

    server           ``http://HOST:PORT`` or ``https://HOST:PORT`` (a bare ``HOST:PORT`` means
                     http); the daemon's ``--http`` address.
    token            bearer token (``gridshelld --token-file``), sent as ``Authorization``.
    token_file       read the token from this file instead (surrounding whitespace dropped).
    ca_file          PEM file of the CA (or the daemon's self-signed certificate) to verify an
                     https server against; without it the system's roots are used.
    timeout          default deadline of a call in seconds (None: no deadline); each call may
                     give its own. Sent as X-Timeout-Ms, so the daemon stops the work too.
    connect_timeout  seconds to connect (default 10).
    retries          further attempts of a call the daemon could not answer: a refused or cut
                     connection, 502, 503, an event stream cut before its result (default 5, as
                     docs/api.md documents; 0 = none).
    backoff          wait before the first retry in seconds (default 0.25); doubles per retry up
                     to ``backoff_max`` (4 s), each wait times a random factor in [0.5, 1).
    headers          extra headers sent with every call (a dict).
    patch_keys       send the patch routing key with Design and Run (default True): the mesh is
                     loaded once by the daemon (``Load``) to learn its repaired arrays, then
                     remembered; see ``patch_key``.
    """

    def __init__(
        self,
        server="http://127.0.0.1:8080",
        token=None,
        token_file=None,
        ca_file=None,
        timeout=None,
        connect_timeout=10.0,
        retries=RETRIES,
        backoff=BACKOFF,
        backoff_max=BACKOFF_MAX,
        headers=None,
        patch_keys=True,
    ):
        if not isinstance(server, str) or not server.strip():
            raise InvalidInput("empty: give the daemon's HTTP address", "INVALID_ARGUMENT", "server")
        text = server.strip()
        if "://" not in text:
            text = "http://" + text
        url = urllib.parse.urlsplit(text)
        if url.scheme not in ("http", "https") or not url.hostname:
            raise InvalidInput(
                "expected http://HOST:PORT or https://HOST:PORT, got '%s'" % server,
                "INVALID_ARGUMENT",
                "server",
            )
        try:
            port = url.port
        except ValueError:
            raise InvalidInput(
                "'%s' has no valid port" % server, "INVALID_ARGUMENT", "server"
            ) from None
        self.server = "%s://%s" % (url.scheme, url.netloc)
        self._https = url.scheme == "https"
        self._host = url.hostname
        self._port = port or (443 if self._https else 80)
        self._prefix = url.path.rstrip("/")
        if token_file:
            try:
                with open(token_file, "r", encoding="utf-8") as f:
                    token = f.read().strip()
            except OSError as e:
                raise InvalidInput(
                    "cannot read %s: %s" % (token_file, e.strerror), "INVALID_ARGUMENT", "token_file"
                ) from None
        self.token = token or None
        self._ssl = None
        if self._https:
            try:
                self._ssl = ssl.create_default_context(cafile=ca_file)
            except (OSError, ssl.SSLError) as e:
                raise InvalidInput(
                    "cannot use %s as a CA: %s" % (ca_file, e), "INVALID_ARGUMENT", "ca_file"
                ) from None
        elif ca_file:
            raise InvalidInput(
                "a CA file needs an https:// server address", "INVALID_ARGUMENT", "ca_file"
            )
        self.timeout = timeout
        self.connect_timeout = connect_timeout
        self.retries = max(0, int(retries))
        self.backoff = backoff
        self.backoff_max = backoff_max
        self.headers = dict(headers or {})
        # A key the caller set for every call (the workaround before the client computed one)
        # is kept as it is.
        given = any(name.lower() == PATCH_KEY_HEADER.lower() for name in self.headers)
        self.patch_keys = bool(patch_keys) and not given

    # ---- the API's methods -----------------------------------------------------------------

    def health(self, timeout=None):
        """``GET /healthz``: ``"SERVING"`` or ``"NOT_SERVING"`` (raises when unreachable)."""
        deadline = _deadline(timeout if timeout is not None else self.timeout or 30)
        connection = self._connect(deadline)
        try:
            connection.request("GET", self._prefix + "/healthz", headers=self._headers(None))
            response = connection.getresponse()
            body = response.read()
            if response.status in (200, 503):
                return json.loads(body.decode("utf-8")).get("status", "UNKNOWN")
            raise _error_from_response(response.status, body)
        except (OSError, http.client.HTTPException) as e:
            raise self._transport_error(e, deadline, None) from None
        finally:
            connection.close()

    def examples(self, **call):
        """The built-in example surfaces: ``{"examples": [{name, description, vertices, corners}]}``."""
        return self.call("examples", {}, **call)

    def options(self, **call):
        """The description of every request option and of the material presets
        (``OptionsResult``): ``{"options": [{group, name, flag, type, default_value, minimum,
        maximum, zero_allowed, choices, unit, help, label, ...}], "materials": [{name, label,
        young_modulus, ...}], "mesh_formats": [...], "length_units": [...]}``; a site's own
        materials (the daemon's ``GRIDSHELL_MATERIALS``) included. ``Description(result)``
        (options.py) looks options and materials up; ``describe(client)`` keeps it per daemon."""
        return self.call("options", {}, **call)

    def load(self, mesh, **call):
        """A mesh as the daemon reads it: ``{"mesh": arrays as loaded, "report": ..., ...}``."""
        return self.call("load", {"mesh": mesh}, **call)

    def patch(self, mesh, corners=None, options=None, **call):
        """Cut, check and smooth the target patch (``PatchResult``)."""
        return self.call("patch", _with(mesh=mesh, corners=_corners(corners), options=options), **call)

    def design(self, mesh, corners=None, options=None, files=False, layout_patch=None, **call):
        """Patch stage, then the grid design (``DesignResult``: design, report, views).

        mesh     a ``Mesh`` message: ``mesh_arrays(...)``, ``mesh_file(...)``, ``mesh_example(...)``
        corners  None (automatic), 4 vertex indices, 4 points (x, y, z) or a ``Corners`` dict
        options  ``DesignRequest.Options`` as a dict: alpha, members_u, members_v,
                 lamella_width, lamella_thickness, resolution, geodesic_method, eta_max,
                 interior_anchors, ... (``options()`` describes each: type, default, range)
        files    also return design.json and report.json in ``views``, the CLI's bytes
        layout_patch  (layout, patch name) or a ``LayoutPatch`` dict: design that patch of a
                 layout instead (corners None); the daemon keeps every patch's work of a layout
                 it cut or ran, so a redesign skips the cut and the maps
        """
        request = _with(mesh=mesh, corners=_corners(corners), options=options)
        if layout_patch is not None:
            if corners is not None:
                raise ValueError("give corners or layout_patch, not both")
            request["layout_patch"] = _layout_patch(layout_patch)
        if files:
            request["files"] = True
        return self.call("design", request, **call)

    def simulate(self, design, options=None, design_name="", files=False, **call):
        """The deployment simulation of a design (``SimulateResult``: deployment, views).

        design   the ``Design``: a dict, or design.json's text or bytes (sent as they are)
        options  ``SimulationOptions`` as a dict: notches, material, unit, ... (``options()``
                 describes each, and lists the daemon's materials)
        """
        if isinstance(design, (str, bytes, bytearray)):
            design = RawJSON(design)
        request = _with(design=design, options=options)
        if design_name:
            request["design_name"] = design_name
        if files:
            request["files"] = True
        return self.call("simulate", request, **call)

    def run(self, mesh, corners=None, design_options=None, simulation=None, files=False,
            layout_patch=None, **call):
        """Patch, design and simulation in one call (``RunResult``: design, simulation);
        ``layout_patch`` as for ``design``."""
        design = _with(mesh=mesh, corners=_corners(corners), options=design_options)
        if layout_patch is not None:
            if corners is not None:
                raise ValueError("give corners or layout_patch, not both")
            design["layout_patch"] = _layout_patch(layout_patch)
        if files:
            design["files"] = True
        return self.call("run", _with(design=design, simulation=simulation), **call)

    def layout(self, mesh, layout=None, automatic=None, options=None, **call):
        """Several patches that share corners and seams (``LayoutResult``: report, patches,
        views). ``layout`` a ``Layout`` dict (corners, patches), or ``automatic`` an
        ``AutoLayoutOptions`` dict (``{}`` for the defaults) to compute one for a disk."""
        request = _with(mesh=mesh, layout=layout, options=options)
        if automatic is not None:
            request["automatic"] = automatic
        return self.call("layout", request, **call)

    def run_layout(self, mesh, layout=None, automatic=None, design_options=None, simulation=None,
                   **call):
        """Every patch of a layout designed and simulated, the whole measured
        (``LayoutRunResult``: layout, patches, design, deployment, views)."""
        request = _with(mesh=mesh, layout=layout, design=design_options, simulation=simulation)
        if automatic is not None:
            request["automatic"] = automatic
        return self.call("runlayout", request, **call)

    def geodesic(self, mesh, source, method="", compare="", repeat=0, distances=False, **call):
        """One exact single-source geodesic distance field (``GeodesicResult``)."""
        request = {"mesh": mesh, "source": source}
        if method:
            request["method"] = method
        if compare:
            request["compare"] = compare
        if repeat:
            request["repeat"] = repeat
        if distances:
            request["distances"] = True
        return self.call("geodesic", request, **call)

    def patch_key(self, mesh, corners=None, options=None, cancel=None, timeout=None):
        """The patch routing key (docs/api.md) that ``design`` and ``run`` send for this mesh,
        corners and design options: 32 hex digits, equal to the daemon's ``report["patch_key"]``;
        None where the daemon would refuse the request (it then answers with the reason).

        The key hashes the mesh as the daemon loads it (after welding duplicates, dropping
        isolated vertices and degenerate faces, fixing the orientation), which only the daemon's
        loader knows for sure: the first key on a mesh asks the daemon (``Load``, one call, no
        patch work) and remembers the loaded mesh's hash state (the last 8 meshes of the process,
        by server and content), so the keys of further designs on it (an angle slider, other
        member counts), from any Client of the process, cost nothing.
        """
        deadline = _deadline(timeout if timeout is not None else self.timeout)
        digest = self._mesh_digest(mesh, None, cancel, deadline)
        return None if digest is None else digest.key(_corners(corners), options)

    # ---- one call --------------------------------------------------------------------------

    def call(self, method, request, progress=None, cancel=None, timeout=None, response_headers=None):
        """``POST /v1/METHOD`` with ``request`` (a dict in the API's JSON form, or JSON bytes).

        progress  called as ``progress(Progress(stage, fraction, message))`` on this thread for
                  every progress event (the call then streams Server-Sent Events), and with the
                  stage ``gridshelld unavailable, retry k of 5`` (fraction 0, the error as the
                  message) while the call waits to be made again
        cancel    a ``Cancel``; its ``cancel()`` from another thread ends the call (``Cancelled``)
        timeout   deadline in seconds for this call (default: the client's)
        response_headers  a dict that the call fills with the answer's HTTP headers (lowercase
                  names): ``x-request-id``, and behind the proxy ``x-gridshell-replica``
        Design and Run given as dicts carry the patch routing key (``patch_key``); a request given
        as JSON bytes is sent as it is, without one.
        Returns the result message as a dict; raises a GridshellError subclass.
        """
        if not isinstance(method, str) or not method.isidentifier():
            raise InvalidInput("not an API method name: %r" % (method,), "INVALID_ARGUMENT", "method")
        body = request if isinstance(request, (bytes, bytearray)) else encode_request(request)
        deadline = _deadline(timeout if timeout is not None else self.timeout)
        key = None
        if self.patch_keys and method in ROUTED_METHODS and isinstance(request, dict):
            design = request if method == "design" else request.get("design")
            if isinstance(design, dict):
                digest = self._mesh_digest(design.get("mesh"), progress, cancel, deadline)
                if digest is not None:
                    key = digest.key(design.get("corners"), design.get("options"))
        return self._call(method, body, progress, cancel, deadline, key, response_headers)

    def _call(self, method, body, progress, cancel, deadline, key=None, response_headers=None,
              stream=None):
        """One call with the retry policy (docs/api.md, "Retries"). ``stream`` (default: a
        progress callback is given) asks for Server-Sent Events."""
        if stream is None:
            stream = progress is not None
        retries = self.retries if method in IDEMPOTENT_METHODS else 0
        retry = 0
        while True:
            if cancel is not None and cancel.cancelled:
                raise Cancelled("cancelled by the client", "CANCELLED")
            try:
                return self._attempt(
                    method, body, progress if stream else None, cancel, deadline, key,
                    response_headers,
                )
            except _Retry as failed:
                retry += 1
                if retry > retries:
                    raise failed.error from None
                pause = retry_delay(retry, self.backoff, self.backoff_max)
                # No retry starts after the deadline: the last error is the answer.
                if deadline is not None and time.monotonic() + pause >= deadline:
                    raise failed.error from None
                if progress is not None:
                    progress(Progress(retry_stage(retry, retries), 0.0, str(failed.error)))
                if self._wait(pause, cancel):
                    raise Cancelled("cancelled by the client", "CANCELLED") from None

    @staticmethod
    def _wait(seconds, cancel):
        """Sleeps before a retry; True when cancelled meanwhile."""
        if cancel is not None:
            return cancel.wait(seconds)
        time.sleep(seconds)
        return False

    def _mesh_digest(self, mesh, progress, cancel, deadline):
        """The routing.MeshDigest of a request's mesh as the daemon loads it (remembered per
        mesh content), or None where there is none: the daemon refuses the mesh, or the mesh is
        not one this client can name (then the call goes without a key)."""
        identity = _mesh_identity(mesh)
        if identity is None:
            return None
        identity = (self.server + self._prefix, identity)
        with _MESHES_LOCK:
            if identity in _MESHES:
                _MESHES.move_to_end(identity)
                return _MESHES[identity]
        try:
            loaded = self._call(
                "load", encode_request({"mesh": mesh}), progress, cancel, deadline, stream=False
            )
            arrays = loaded["mesh"]
            digest = routing.MeshDigest(
                arrays.get("positions", []), arrays.get("indices", []), loaded.get("vertex_map")
            )
        except (Cancelled, DeadlineExceeded, Unavailable):
            raise  # the call itself would end the same way
        except InvalidInput:
            # The daemon refuses the mesh: the call goes without a key, and its own answer names
            # the problem in the call's terms (design.mesh...). The same mesh is refused again.
            digest = None
        except GridshellError:
            return None  # a full queue, a token refused: the call answers for itself
        except (KeyError, TypeError, ValueError, AttributeError, OverflowError):
            digest = None  # an answer without the loaded arrays: no key rather than a wrong one
        with _MESHES_LOCK:
            _MESHES[identity] = digest
            while len(_MESHES) > MESH_MEMO:
                _MESHES.popitem(last=False)
        return digest

    # ---- internals -------------------------------------------------------------------------

    def _headers(self, deadline, stream=False, key=None):
        headers = {"User-Agent": USER_AGENT}
        headers.update(self.headers)
        if key:
            headers[PATCH_KEY_HEADER] = key
        if self.token:
            headers["Authorization"] = "Bearer " + self.token
        if deadline is not None:
            headers["X-Timeout-Ms"] = "%d" % max(1, int((deadline - time.monotonic()) * 1000))
        if stream:
            headers["Accept"] = "text/event-stream"
        return headers

    def _connect(self, deadline):
        timeout = self.connect_timeout
        if deadline is not None:
            timeout = min(timeout, max(0.001, deadline - time.monotonic()))
        if self._https:
            connection = http.client.HTTPSConnection(
                self._host, self._port, timeout=timeout, context=self._ssl
            )
        else:
            connection = http.client.HTTPConnection(self._host, self._port, timeout=timeout)
        return connection

    def _attempt(self, method, body, progress, cancel, deadline, key=None, response_headers=None):
        stream = progress is not None
        connection = self._connect(deadline)
        # http.client hands the socket over to the response of a "Connection: close" answer
        # (connection.sock becomes None): keep it here, to shut it on cancel and to close it at
        # the end, so the daemon sees the client go at once (it cancels the work then).
        line = _Line()
        response = None
        if cancel is not None and not cancel._attach(line):
            raise Cancelled("cancelled by the client", "CANCELLED")
        try:
            connection.connect()
            line.sock = connection.sock
            if cancel is not None and cancel.cancelled:
                raise Cancelled("cancelled by the client", "CANCELLED")
            # From here on, the deadline bounds every read (the daemon answers 504 before it).
            line.sock.settimeout(None if deadline is None else _remaining(deadline) + 5)
            headers = self._headers(deadline, stream, key)
            headers["Content-Type"] = "application/json"
            connection.request("POST", "%s/v1/%s" % (self._prefix, method), body, headers)
            response = connection.getresponse()
            if response_headers is not None:
                response_headers.clear()
                response_headers.update((k.lower(), v) for k, v in response.getheaders())
            content_type = response.getheader("Content-Type", "")
            if response.status == 200 and content_type.startswith("text/event-stream"):
                return _read_events(response, progress, cancel, method)
            data = response.read()
            if cancel is not None and cancel.cancelled:
                raise Cancelled("cancelled by the client", "CANCELLED")
            if response.status == 200:
                return _parse_json(data, "the result")
            error = _error_from_response(response.status, data)
            if response.status in RETRY_STATUSES and method in IDEMPOTENT_METHODS:
                raise _Retry(error)
            raise error
        except _Cut as e:
            if cancel is not None and cancel.cancelled:
                raise Cancelled("cancelled by the client", "CANCELLED") from None
            raise self._transport_error(e.cause, deadline, cancel, retry=True) from None
        except (OSError, http.client.HTTPException) as e:
            raise self._transport_error(e, deadline, cancel, retry=True) from None
        finally:
            if cancel is not None:
                cancel._detach(line)
            if response is not None:
                response.close()
            connection.close()
            line.close()

    def _transport_error(self, e, deadline, cancel, retry=False):
        """The exception for a connection failure: Cancelled, DeadlineExceeded or Unavailable."""
        if cancel is not None and cancel.cancelled:
            return Cancelled("cancelled by the client", "CANCELLED")
        if isinstance(e, ssl.SSLCertVerificationError):
            return Unavailable(
                "cannot verify %s's certificate: %s" % (self.server, e.verify_message or e),
                "UNAVAILABLE",
            )
        if (
            isinstance(e, (socket.timeout, TimeoutError))
            and deadline is not None
            and time.monotonic() >= deadline - 0.01
        ):
            return DeadlineExceeded(
                "no answer from %s within the deadline" % self.server, "DEADLINE_EXCEEDED"
            )
        reason = getattr(e, "strerror", None) or str(e) or type(e).__name__
        error = Unavailable("cannot reach %s: %s" % (self.server, reason), "UNAVAILABLE")
        return _Retry(error) if retry else error


class _Cut(Exception):
    """The event stream ended before its result (the connection was cut)."""

    def __init__(self, cause):
        super().__init__(str(cause))
        self.cause = cause


def _mesh_identity(mesh):
    """What identifies a ``Mesh`` message's surface for the daemon's loader (not its name or
    warnings): a digest of its arrays, file bytes and format, or example name; None for a value
    that is not a mesh message this client builds (no key then)."""
    if not isinstance(mesh, dict):
        return None
    h = hashlib.sha256()
    try:
        positions, indices = mesh.get("positions"), mesh.get("indices")
        if positions or indices:
            positions, indices = list(positions or []), list(indices or [])
            h.update(b"arrays %d %d\n" % (len(positions), len(indices)))
            h.update(routing._packed("d", positions))
            h.update(routing._packed("q", indices))
        for name in ("file", "format", "example"):
            value = mesh.get(name)
            if value is not None and not isinstance(value, str):
                return None
            if value:
                h.update(b"%s %d\n" % (name.encode("ascii"), len(value)))
                h.update(value.encode("utf-8"))
    except (TypeError, ValueError, OverflowError):
        return None  # e.g. a RawJSON mesh or numbers in strings: the call goes without a key
    return h.digest()


def _deadline(timeout):
    if timeout is None:
        return None
    if not (isinstance(timeout, (int, float)) and timeout > 0 and math.isfinite(timeout)):
        raise InvalidInput(
            "expected a positive number of seconds, got %r" % (timeout,), "INVALID_ARGUMENT", "timeout"
        )
    return time.monotonic() + timeout


def _remaining(deadline):
    return max(0.001, deadline - time.monotonic())


def _with(**fields):
    """A request dict of the fields that are given (None = left out: the API's default)."""
    return {k: v for k, v in fields.items() if v is not None}


def _layout_patch(value):
    """(layout, name) -> a LayoutPatch dict; a dict as is."""
    if isinstance(value, dict):
        return value
    layout, name = value
    return {"layout": layout, "patch": str(name)}


def _corners(corners):
    """None -> automatic; 4 ints -> vertices; 4 points or 12 numbers -> points; a dict as is."""
    if corners is None or isinstance(corners, dict):
        return corners
    items = list(corners)
    if len(items) == 4 and all(isinstance(c, int) and not isinstance(c, bool) for c in items):
        return {"vertices": items}
    if len(items) == 4 and all(hasattr(c, "__len__") and len(c) == 3 for c in items):
        return {"points": [float(x) for c in items for x in c]}
    if len(items) == 12:
        return {"points": [float(x) for x in items]}
    raise InvalidInput(
        "expected 4 vertex indices or 4 points (x, y, z), got %d items" % len(items),
        "INVALID_ARGUMENT",
        "corners",
    )


def _json_int(text):
    """An integer of the answer's JSON; "-0" is a double's negative zero as protobuf prints it
    (json would make it the integer 0 and lose the sign bit, which the patch key hashes)."""
    return -0.0 if text == "-0" else int(text)


def _parse_json(data, what):
    try:
        text = data.decode("utf-8") if isinstance(data, (bytes, bytearray)) else data
        return json.loads(text, parse_int=_json_int)
    except (ValueError, UnicodeDecodeError) as e:
        raise InternalError("%s is not JSON: %s" % (what, e), "INTERNAL") from None


def _error_from_response(status, data):
    try:
        body = json.loads(data.decode("utf-8"))
    except (ValueError, UnicodeDecodeError):
        body = None
    return errors.error_from_body(body, status)


def _read_events(response, progress, cancel, method):
    """Reads Server-Sent Events until the result (returned) or an error (raised)."""
    event, data = "", []
    buffer = bytearray()  # appends and deletes from the front are amortized O(1)
    while True:
        try:
            chunk = response.read1(1 << 16)
        except (OSError, http.client.HTTPException) as e:
            raise _Cut(e) from None
        if not chunk:
            if cancel is not None and cancel.cancelled:
                raise Cancelled("cancelled by the client", "CANCELLED")
            raise _Cut(ConnectionError("the event stream ended before the result"))
        start = len(buffer)
        buffer += chunk
        end = buffer.find(b"\n", start)
        while end >= 0:
            line = bytes(buffer[: end - 1 if end and buffer[end - 1] == 13 else end])
            del buffer[: end + 1]
            end = buffer.find(b"\n")
            if line:
                name, _, value = line.partition(b":")
                if value.startswith(b" "):
                    value = value[1:]
                if name == b"event":
                    event = value.decode("utf-8")
                elif name == b"data":
                    data.append(value)
                continue
            if not data and not event:
                continue
            payload = b"\n".join(data)
            kind, event, data = event or "message", "", []
            if kind == "progress":
                report = _parse_json(payload, "a progress event")
                progress(
                    Progress(
                        report.get("stage", ""),
                        float(report.get("fraction", 0.0)),
                        report.get("message", ""),
                    )
                )
                if cancel is not None and cancel.cancelled:
                    raise Cancelled("cancelled by the client", "CANCELLED")
            elif kind == "result":
                return _parse_json(payload, "the result of " + method)
            elif kind == "error":
                error = errors.error_from_body(_parse_json(payload, "an error event"))
                if isinstance(error, Unavailable) and method in IDEMPOTENT_METHODS:
                    raise _Retry(error)  # a replica shutting down: another may answer
                raise error
