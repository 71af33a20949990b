# SPDX-License-Identifier: GPL-3.0-or-later
"""What the CAD plugins (Blender add-on, FreeCAD workbench) share, independent of either program:
a call running on a background thread that the program's UI loop polls, error text for a report,
the deployed lamellas of a SimulateResult as a mesh with a deviation per vertex, and the
deviation colour map of deviation.ply.
"""

import base64
import json
import math
import os
import re
import threading
import time

from .client import Cancel, files_of
from .errors import (
    Cancelled,
    DeadlineExceeded,
    GridshellError,
    Infeasible,
    InvalidInput,
    Unauthenticated,
    Unavailable,
)

__all__ = [
    "BackgroundCall",
    "error_text",
    "progress_text",
    "parse_obj",
    "deployed_mesh",
    "deviation_colour",
    "ProgressPrinter",
]


class BackgroundCall:
    """Runs ``function(progress=..., cancel=...)`` on a thread; the UI thread polls ``done``,
    reads ``progress`` (the latest Progress or None), calls ``cancel()``, and finally takes
    ``result()`` (the return value, or the exception raised again).

    Once ``cancel()`` was called, ``result()`` raises ``Cancelled`` even when the work finished
    meanwhile: a user who pressed Esc while the answer was on its way sees nothing change (the
    UI takes the result only at its next poll, which may come after the key)."""

    def __init__(self, function):
        self._function = function
        self._cancel = Cancel()
        self._lock = threading.Lock()
        self._progress = None
        self._result = None
        self._error = None
        self._done = threading.Event()
        self.started = time.monotonic()
        self.finished = None
        self._thread = threading.Thread(target=self._run, name="gridshell call", daemon=True)
        self._thread.start()

    def _on_progress(self, progress):
        with self._lock:
            self._progress = progress

    def _run(self):
        try:
            self._result = self._function(progress=self._on_progress, cancel=self._cancel)
        except BaseException as e:  # handed to the UI thread, raised there
            self._error = e
        self.finished = time.monotonic()
        self._done.set()

    @property
    def progress(self):
        with self._lock:
            return self._progress

    @property
    def done(self):
        return self._done.is_set()

    def wait(self, seconds=None):
        return self._done.wait(seconds)

    def cancel(self):
        self._cancel.cancel()

    @property
    def cancelled(self):
        return self._cancel.cancelled

    def result(self):
        self._done.wait()
        self._thread.join()
        if self.cancelled and not isinstance(self._error, Cancelled):
            raise Cancelled("cancelled by the client", "CANCELLED")
        if self._error is not None:
            raise self._error
        return self._result


def progress_text(progress, elapsed=None):
    """'distance maps 42%' (and the time so far), for a status bar."""
    if progress is None:
        text = "starting"
    else:
        text = "%s %d%%" % (progress.stage, round(100 * min(max(progress.fraction, 0.0), 1.0)))
        if progress.message:
            text += " (%s)" % progress.message
    if elapsed is not None:
        text += ", %.0f s" % elapsed
    return text


class ProgressPrinter:
    """Progress as lines for a terminal or log, one every ``interval`` seconds at most (and at a
    new stage), like the CLI's progress when stderr is not a terminal."""

    def __init__(self, write, interval=2.0, prefix="gridshell: "):
        self._write = write
        self._interval = interval
        self._prefix = prefix
        self._last = 0.0
        self._stage = None

    def __call__(self, progress):
        now = time.monotonic()
        if progress.stage == self._stage and now - self._last < self._interval:
            return
        self._stage, self._last = progress.stage, now
        self._write(self._prefix + progress_text(progress))


def error_text(error, server="", field_names=None, source=""):
    """One or more lines for a report: what went wrong and where, in the plugin's terms.

    ``field_names`` maps request fields (``options.lamella_width``) or their first part
    (``corners``) to the names the plugin shows (``Lamella width``, ``selected corner``); a
    vertex or triangle of the mesh is named as such in ``source`` (the object's name).
    """
    names = field_names or {}
    if isinstance(error, Cancelled):
        return ["gridshell: cancelled"]
    if isinstance(error, Unavailable):
        return [
            "gridshell: cannot reach the daemon at %s (%s); start gridshelld or set the server"
            % (server or "?", error.message)
        ]
    if isinstance(error, Unauthenticated):
        return ["gridshell: the daemon at %s refused the token (%s)" % (server or "?", error.message)]
    if isinstance(error, DeadlineExceeded):
        return ["gridshell: the deadline passed (%s)" % error.message]
    if not isinstance(error, GridshellError):
        return ["gridshell: internal error: %s: %s" % (type(error).__name__, error)]
    where = _field_name(error.field, names, source)
    if isinstance(error, Infeasible):
        kind = "infeasible design"
    elif isinstance(error, InvalidInput):
        kind = "invalid input"
    else:
        kind = error.status.lower().replace("_", " ")
    lines = ["gridshell: %s: %s%s" % (kind, where + ": " if where else "", error.message)]
    for rank, suggestion in enumerate(error.suggestions, 1):
        lines.append("  suggestion %d: %s" % (rank, _suggestion_text(suggestion)))
    return lines


def _field_name(field, names, source=""):
    if not field:
        return ""
    if field in names:
        return "%s (%s)" % (names[field], field)
    match = re.match(r"^(?:[a-z]+\.)?(mesh)\.(positions|indices)\[(\d+)\]", field)
    if match:
        what = "vertex" if match.group(2) == "positions" else "triangle"
        return "%s %d of %s (%s)" % (what, int(match.group(3)) // 3, source or "the mesh", field)
    match = re.match(r"^(?:[a-z]+\.)?(corners)(?:\.vertices|\.points)?\[(\d+)\]", field)
    if match and "corners" in names:
        index = int(match.group(2))
        if ".points" in field:
            index //= 3
        return "%s %d (%s)" % (names["corners"], index + 1, field)
    head = field.split(".")[0].split("[")[0]
    if head in names:
        return "%s (%s)" % (names[head], field)
    return field


def _suggestion_text(suggestion):
    if isinstance(suggestion, str):
        return suggestion
    if isinstance(suggestion, dict):
        text = suggestion.get("description") or suggestion.get("message") or ""
        rest = ", ".join(
            "%s %s" % (k, v)
            for k, v in suggestion.items()
            if k not in ("description", "message") and not isinstance(v, (dict, list))
        )
        return (text + (" (" + rest + ")" if rest and text else rest)) or str(suggestion)
    return str(suggestion)


def parse_obj(data):
    """Vertices (flat x, y, z list) and polygons (lists of 0-based indices) of an OBJ's bytes, as
    the daemon's views write them (v and f lines; o lines name the parts)."""
    positions, polygons = [], []
    for line in data.split(b"\n"):
        if line.startswith(b"v "):
            x, y, z = line.split()[1:4]
            positions += (float(x), float(y), float(z))
        elif line.startswith(b"f "):
            polygons.append([int(token.split(b"/")[0]) - 1 for token in line.split()[1:]])
    return positions, polygons


def deployed_mesh(simulate_result, views, notches=True):
    """The deployed lamellas as boxes (deployed.obj of the run with or without notches) and the
    deviation of every box vertex from the target, as ``(positions, polygons, deviation)``.

    deployed.obj has four corners per rod vertex, rod after rod in the order of the deployment's
    ``rods`` (``rods_without_notches``), so each corner takes its rod vertex's ``deviation``.
    """
    deployment = simulate_result["deployment"]
    suffix = "" if notches else "_without_notches"
    name = "deployed%s.obj" % suffix
    if name not in views:
        raise GridshellError("the result has no %s" % name, "INTERNAL")
    positions, polygons = parse_obj(views[name])
    rods = deployment.get("rods" if notches else "rods_without_notches", [])
    deviation = []
    for rod in rods:
        values = rod.get("deviation", [])
        if len(rod.get("centerline", [])) < 2:
            continue
        for d in values:
            deviation += (d, d, d, d)
    if len(deviation) * 3 != len(positions):
        raise GridshellError(
            "%s has %d vertices, the rods %d" % (name, len(positions) // 3, len(deviation)),
            "INTERNAL",
        )
    return positions, polygons, deviation


def deviation_colour(value, top):
    """deviation.ply's colour map: blue at 0, green at top/2, red at ``top`` (RGB in 0..1)."""
    f = min(max(value / top, 0.0), 1.0) if top > 0 and math.isfinite(value) else 0.0
    r = min(max(2 * f - 1, 0.0), 1.0)
    b = min(max(1 - 2 * f, 0.0), 1.0)
    return (r, 1 - r - b, b)


def layout_of(data, where):
    """The ``gridshell.v1.Layout`` in ``data``: a Layout itself, or the ``layout`` member of a
    LayoutReport (layout.json as ``gridshell layout`` writes it), of a LayoutResult's report, or
    of a layout run's design.json. ValueError naming ``where`` when it holds none."""
    node = data
    for _ in range(4):
        if not isinstance(node, dict):
            break
        if isinstance(node.get("corners"), list) and isinstance(node.get("patches"), list):
            return {"corners": node["corners"], "patches": node["patches"]}
        if isinstance(node.get("layout"), dict):
            node = node["layout"]
        elif isinstance(node.get("report"), dict):
            node = node["report"]
        else:
            break
    raise ValueError(
        "%s holds no layout: expected a gridshell.v1.Layout (corners, patches) or a layout report "
        "with one as its 'layout'" % where
    )


def automatic_grid(automatic):
    """An automatic layout's grid as both plugins show it: "3 x 2" on a disk, "14 x 1 round the
    ring" on a ring or tube, "6 faces x 1 x 1" on a closed surface (split along a cube)."""
    grid = "%d x %d" % (automatic.get("columns", 0), automatic.get("rows", 0))
    surface = automatic.get("surface", "disk")
    if surface == "ring":
        return grid + " round the ring"
    if surface == "closed":
        return "6 faces x " + grid
    return grid


def joining_note(deployment):
    """What a layout run's deployment.json says about joining its patches, for a status line:
    the patches alone and the bolts' largest force when the seams were joined, why not when a
    joined run failed, "" otherwise."""
    diagonal = deployment.get("diagonal", 0.0)
    percent = (lambda x: 100 * x / diagonal) if diagonal > 0 else (lambda x: 0.0)
    if deployment.get("seams_joined"):
        alone = deployment.get("rms_before_joining")
        note = "; patches alone RMS %.4g (%.3f %%)" % (alone, percent(alone)) if alone is not None else ""
        return note + "; largest bolt force %.4g %s" % (
            deployment.get("max_bolt_force", 0.0), deployment.get("force_unit", ""))
    why = [run.get("termination", "") for run in (deployment.get("joined_with_notches"),
                                                   deployment.get("joined_without_notches")) if run]
    why = [w for w in why if w]
    return " (%s)" % "; ".join(why) if why else ""


def joined_patch_results(result):
    """Each patch's lamellas in the whole joined at its seams, shaped as its own SimulateResult
    would be (its joined rods in ``deployment``, its share of the whole's deployed.obj as the
    view), by patch name, for drawing the whole per patch. ``{}`` when the seams were not joined
    (each patch's own result is then what there is to draw)."""
    deployment = result.get("deployment", {}) if isinstance(result, dict) else {}
    rods = deployment.get("rods", [])
    names = deployment.get("rod_patches", [])
    views = files_of(result)
    if not deployment.get("seams_joined") or not rods or len(names) != len(rods) or "deployed.obj" not in views:
        return {}
    with_notches = "joined_with_notches" in deployment
    run = deployment.get("joined_with_notches" if with_notches else "joined_without_notches", {})
    # The whole's deployed.obj names its objects "<patch>-<lamella>" (a patch name may hold "-":
    # the longest name that prefixes the object wins); face indices count over the whole file.
    patches = sorted(set(names), key=len, reverse=True)
    owner, vertices, faces = None, {}, {}
    where = []  # per vertex of the file: (patch, its index there)
    for line in views["deployed.obj"].decode("utf-8").splitlines():
        if line.startswith("o "):
            object_name = line[2:].strip()
            owner = next((p for p in patches if object_name.startswith(p + "-")), None)
        elif line.startswith("v "):
            vertices.setdefault(owner, []).append(line)
            where.append((owner, len(vertices[owner])))
        elif line.startswith("f ") and owner is not None:
            faces.setdefault(owner, []).append("f " + " ".join(
                str(where[int(v.split("/")[0]) - 1][1]) for v in line[2:].split()))
    out = {}
    for name in patches:
        own = [rod for rod, patch in zip(rods, names) if patch == name]
        obj = "\n".join(["o %s" % name] + vertices.get(name, []) + faces.get(name, [])) + "\n"
        suffix = "" if with_notches else "_without_notches"
        out[name] = {
            "deployment": {
                "rods" + suffix: own,
                ("with_notches" if with_notches else "without_notches"): {
                    "rms": next((p.get("joined_rms", 0.0) for p in deployment.get("patches", [])
                                 if p.get("name") == name), 0.0),
                    "max_deviation": max((d for rod in own for d in rod.get("deviation", [])), default=0.0),
                },
            },
            "views": [{"name": "deployed%s.obj" % suffix,
                       "content": base64.b64encode(obj.encode("utf-8")).decode("ascii")}],
        }
    return out


def read_layout_file(path):
    """The layout of a layout.json file (``layout_of``); ValueError saying what is wrong."""
    if not path:
        raise ValueError("choose a layout file (Layout file: a layout.json)")
    try:
        with open(path, "r", encoding="utf-8") as f:
            data = json.load(f)
    except OSError as e:
        raise ValueError("cannot read the layout file %s: %s" % (path, e.strerror)) from None
    except ValueError as e:
        raise ValueError("the layout file %s is not JSON: %s" % (path, e)) from None
    return layout_of(data, "the layout file %s" % os.path.basename(path))
