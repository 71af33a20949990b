#!/usr/bin/env python3
# SPDX-License-Identifier: GPL-3.0-or-later
"""Builds the CAD plugins' installable zips into the build folder (default ./build):

  gridshell_blender.zip   Blender: Edit > Preferences > Add-ons > Install... (docs/blender.md)
  gridshell_freecad.zip   FreeCAD: unzip into the user Mod folder (docs/freecad.md)

Each carries a copy of the Python client (client/python/gridshell_client) inside its package, so
it needs nothing else. The zips are reproducible: sorted entries, fixed timestamps.
"""

import os
import sys
import zipfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
CLIENT = os.path.join(ROOT, "client", "python", "gridshell_client")


def files(folder):
    """(path, path relative to folder) of the package's files, sorted, without caches."""
    out = []
    for base, dirs, names in os.walk(folder):
        dirs[:] = sorted(d for d in dirs if d != "__pycache__")
        for name in sorted(names):
            if name.endswith((".pyc", ".pyo")):
                continue
            path = os.path.join(base, name)
            out.append((path, os.path.relpath(path, folder)))
    return out


def write_zip(target, entries):
    """entries: (source path, name in the zip)."""
    partial = target + ".partial"
    with zipfile.ZipFile(partial, "w", zipfile.ZIP_DEFLATED) as z:
        for source, name in sorted(entries, key=lambda e: e[1]):
            info = zipfile.ZipInfo(name, date_time=(1980, 1, 1, 0, 0, 0))
            info.compress_type = zipfile.ZIP_DEFLATED
            info.external_attr = 0o644 << 16
            with open(source, "rb") as f:
                z.writestr(info, f.read())
    os.replace(partial, target)  # atomically: never a half-written zip
    print("plugins: wrote %s (%d files)" % (os.path.relpath(target, ROOT), len(entries)))


def main():
    out = os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else os.path.join(ROOT, "build"))
    os.makedirs(out, exist_ok=True)
    blender = os.path.join(ROOT, "client", "blender", "gridshell_blender")
    entries = [(p, "gridshell_blender/" + r) for p, r in files(blender)]
    entries += [(p, "gridshell_blender/gridshell_client/" + r) for p, r in files(CLIENT)]
    write_zip(os.path.join(out, "gridshell_blender.zip"), entries)
    freecad = os.path.join(ROOT, "client", "freecad")
    entries = [(p, "gridshell/" + r) for p, r in files(freecad)]
    entries += [(p, "gridshell/gridshell_freecad/gridshell_client/" + r) for p, r in files(CLIENT)]
    write_zip(os.path.join(out, "gridshell_freecad.zip"), entries)


if __name__ == "__main__":
    main()
