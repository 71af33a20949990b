# SPDX-License-Identifier: GPL-3.0-or-later
"""Building the API's ``Mesh`` message (docs/api.md): packed arrays, a file's bytes, or an example.

The daemon reads every form with the CLI's own loader (the same repairs, warnings and errors), so
a client never parses mesh files itself, nor checks their format: the formats the daemon reads
are in its description (``Client.options()["mesh_formats"]``), and a format it does not read is
refused with the field ``mesh.format``, naming the ones it does.
"""

import base64
import os

from .errors import InvalidInput

__all__ = ["mesh_arrays", "mesh_file", "mesh_example"]


def _flat(values, width, what):
    """Numbers as one flat list: a flat sequence, or rows of ``width`` (lists, tuples, numpy)."""
    if hasattr(values, "tolist"):  # numpy arrays without importing numpy
        values = values.tolist()
    out = []
    for item in values:
        if isinstance(item, (list, tuple)):
            if len(item) != width:
                raise InvalidInput(
                    "expected rows of %d numbers, got one of %d" % (width, len(item)),
                    "INVALID_ARGUMENT",
                    what,
                )
            out.extend(item)
        else:
            out.append(item)
    return out


def mesh_arrays(positions, indices, name=""):
    """A mesh as packed arrays: ``positions`` x0, y0, z0, ... (or rows (x, y, z)), ``indices``
    i, j, k per triangle, 0-based (or rows (i, j, k)). ``name`` is recorded as ``input``."""
    mesh = {
        "positions": [float(x) for x in _flat(positions, 3, "mesh.positions")],
        "indices": [int(i) for i in _flat(indices, 3, "mesh.indices")],
    }
    if name:
        mesh["name"] = name
    return mesh


def mesh_file(source, format=None, name=None):
    """A mesh file's bytes for the daemon's loader: ``source`` is a path or the bytes themselves.

    ``format`` is one of the daemon's ``mesh_formats`` (``Client.options()``: obj, off, ply, stl)
    (default: the path's or name's extension); ``name`` is recorded as ``input`` (default: the
    path's file name). The format is not checked here: without one (bytes without a name with
    an extension) or with one the daemon does not read, the call is refused with the field
    ``mesh.format`` and the daemon's list."""
    if isinstance(source, (bytes, bytearray, memoryview)):
        data = bytes(source)
    else:
        path = os.fspath(source)
        try:
            with open(path, "rb") as f:
                data = f.read()
        except OSError as e:
            raise InvalidInput("cannot read %s: %s" % (path, e.strerror), "INVALID_ARGUMENT", "mesh.file") from None
        if name is None:
            name = os.path.basename(path)
        if format is None:
            format = os.path.splitext(path)[1].lstrip(".")
    if format is None and name:
        format = os.path.splitext(name)[1].lstrip(".")
    mesh = {"file": base64.b64encode(data).decode("ascii")}
    if format:
        mesh["format"] = format
    if name:
        mesh["name"] = name
    return mesh


def mesh_example(name):
    """A built-in example surface by name (``Client.examples()`` lists them)."""
    return {"example": name}
