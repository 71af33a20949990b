# SPDX-License-Identifier: GPL-3.0-or-later
"""The patch routing key (docs/api.md, "Replicas and the patch key"): the first 16 bytes of SHA-256
over the mesh as the daemon loads it, the corners and the options a design's patch work depends
on, as 32 lowercase hex digits. The client sends it as ``X-Gridshell-Patch-Key`` with every Design
and Run, so that haproxy in front of several daemons sends the designs of one patch to the replica
whose per-patch cache holds its work.

The byte layout is application/include/gridshell/application/patch_routing_key.h's (all numbers little-endian, f64
as IEEE 754 bits); every design result carries the daemon's own computation
(``report["patch_key"]``), which the tests compare with this one.

    "gridshell-patch-key-v1\\n"
    u32 V, V x 3 f64      positions of the mesh as loaded (after the loader's repairs)
    u32 F, F x 3 u32      faces
    u8 corners            0 automatic, 1 vertex indices into the loaded mesh, 2 points;
                          then 4 x u32 or 12 x f64
    u32 n, n bytes        geodesic engine ("fast" or "cgal")
    f64                   eta_max
    u32                   the smoothing iteration cap (60: a design request cannot change it)
    u8                    smoothing on (1: a design request cannot turn it off)
    u32                   distance map resolution (0 = adaptive)
"""

import array
import hashlib
import math
import re
import struct
import sys

__all__ = ["patch_key", "MeshDigest", "DEFAULT_RESOLUTION", "DEFAULT_ETA_MAX"]

MAGIC = b"gridshell-patch-key-v1\n"
# The daemon's defaults for what a design request leaves out, and the smoothing settings a design
# request cannot change (docs/api.md; the daemon's DesignOptions).
DEFAULT_METHOD = "fast"
DEFAULT_ETA_MAX = 1.0015
SMOOTHING_ITERATIONS = 60
DEFAULT_RESOLUTION = 100
METHODS = ("fast", "cgal")  # the exact engines a design accepts ("heat" is refused)

_U32 = next(code for code in "IL" if array.array(code).itemsize == 4)
_BIG_ENDIAN = sys.byteorder == "big"
# A JSON number as protobuf's JSON parser takes it in a string ("1.5", "2e3").
_NUMBER = re.compile(r"-?(?:0|[1-9][0-9]*)(?:\.[0-9]+)?(?:[eE][+-]?[0-9]+)?\Z")


def _packed(code, values):
    data = array.array(code, values)
    if _BIG_ENDIAN:
        data.byteswap()
    return data.tobytes()


class MeshDigest:
    """The mesh part of the key (magic, vertices, faces) hashed once, for any number of keys on
    that mesh: ``key(corners, options)`` copies the hash state and adds the rest.

    ``positions`` and ``indices`` are the packed arrays as the daemon loaded them (``Load``'s
    ``mesh``); ``vertex_map`` is Load's ``vertex_map`` (sent vertex -> loaded vertex, -1 removed;
    empty or None: the identity), through which corner vertex indices of a request, given as
    sent, are mapped to the loaded mesh.
    """

    __slots__ = ("_hash", "vertices", "vertex_map")

    def __init__(self, positions, indices, vertex_map=None):
        if len(positions) % 3 or len(indices) % 3:
            raise ValueError("positions and indices must be multiples of 3")
        h = hashlib.sha256(MAGIC)
        h.update(struct.pack("<I", len(positions) // 3))
        h.update(_packed("d", positions))
        h.update(struct.pack("<I", len(indices) // 3))
        h.update(_packed(_U32, indices))
        self._hash = h
        self.vertices = len(positions) // 3
        self.vertex_map = list(vertex_map) if vertex_map else None

    def key(self, corners=None, options=None):
        """The key of a design on this mesh with ``corners`` (a ``Corners`` dict as sent: vertex
        indices into the mesh as sent, or points; None: automatic) and ``options`` (the design
        request's options dict), or None where the daemon would refuse the request (then no key
        is sent, and the daemon's answer says what is wrong)."""
        tail = _tail(corners, options, self._loaded_vertex)
        if tail is None:
            return None
        h = self._hash.copy()
        h.update(tail)
        return h.hexdigest()[:32]

    def _loaded_vertex(self, v):
        if self.vertex_map is None:
            return v if 0 <= v < self.vertices else None
        if not 0 <= v < len(self.vertex_map) or self.vertex_map[v] < 0:
            return None
        return self.vertex_map[v]


def patch_key(positions, indices, corners=None, options=None):
    """The key of a design on a mesh given as packed arrays **as the daemon loads them** (after
    its repairs: what ``Client.load`` returns), corner vertex indices into those arrays; None where
    the daemon would refuse the request. ``Client.patch_key`` does the loading for any mesh."""
    return MeshDigest(positions, indices).key(corners, options)


def _field(message, name, camel):
    """A field of a request dict by its proto name or its lowerCamelCase JSON name (both are
    accepted by the daemon); ``_MISSING`` when neither is there, ``_BAD`` when both are."""
    if not isinstance(message, dict):
        return _MISSING
    has, has_camel = name in message, camel != name and camel in message
    if has and has_camel:
        return _BAD
    value = message.get(name) if has else message.get(camel, _MISSING)
    return _MISSING if value is None else value  # JSON null: the field's default


_MISSING = object()
_BAD = object()


def _number(value):
    """A double as protobuf's JSON parser reads it (number, or number in a string), else None."""
    if isinstance(value, bool):
        return None
    if isinstance(value, (int, float)):
        return float(value)
    if isinstance(value, str):
        if value in ("NaN", "Infinity", "-Infinity") or _NUMBER.match(value):
            return float(value.replace("Infinity", "inf"))
    return None


def _integer(value):
    """An int32 as protobuf's JSON parser reads it (an integral number, or one in a string)."""
    number = _number(value)
    if number is None or not math.isfinite(number) or number != int(number):
        return None
    return int(number)


def _tail(corners, options, loaded_vertex):
    """The key's bytes after the mesh, or None where the daemon would refuse the values."""
    out = bytearray()
    if corners is None:
        corners = {}
    if not isinstance(corners, dict):
        return None
    vertices = _field(corners, "vertices", "vertices")
    points = _field(corners, "points", "points")
    vertices = [] if vertices is _MISSING else vertices
    points = [] if points is _MISSING else points
    if vertices is _BAD or points is _BAD or not isinstance(vertices, list):
        return None
    if not isinstance(points, list) or (vertices and points):
        return None
    if vertices:
        if len(vertices) != 4:
            return None
        out.append(1)
        for v in vertices:
            index = _integer(v)
            loaded = None if index is None else loaded_vertex(index)
            if loaded is None:
                return None
            out += struct.pack("<I", loaded)
    elif points:
        values = [_number(p) for p in points]
        if len(values) != 12 or any(x is None or not math.isfinite(x) for x in values):
            return None
        out.append(2)
        out += struct.pack("<12d", *values)
    else:
        out.append(0)

    if options is None:
        options = {}
    if not isinstance(options, dict):
        return None
    method = _field(options, "geodesic_method", "geodesicMethod")
    method = DEFAULT_METHOD if method is _MISSING or method == "" else method
    if method not in METHODS:
        return None
    eta_max = _field(options, "eta_max", "etaMax")
    eta_max = DEFAULT_ETA_MAX if eta_max is _MISSING else _number(eta_max)
    if eta_max is None or not eta_max >= 1.0:
        return None
    resolution = _field(options, "resolution", "resolution")
    resolution = DEFAULT_RESOLUTION if resolution is _MISSING else _integer(resolution)
    if resolution is None or not (resolution == 0 or 8 <= resolution <= 1000):
        return None
    name = method.encode("ascii")
    out += struct.pack("<I", len(name)) + name
    out += struct.pack("<dIBI", eta_max, SMOOTHING_ITERATIONS, 1, resolution)
    return bytes(out)
