#!/usr/bin/python3
# SPDX-License-Identifier: GPL-3.0-or-later
"""Reads a kit's cut sheets with independent readers -- Debian's python3-ezdxf for the DXF files,
the standard library's XML parser for the SVG files -- and prints what they contain as one JSON
document on stdout, for tests/cli/test_cli_fabricate.cpp and tests/fabrication/test_kit.cpp to
check against design.json.

Usage: read_sheets.py KIT_FOLDER

Output: {"sheets": [{"name", "dxf": {...}, "svg": {...}}]} where each of dxf/svg holds
  "units" ($INSUNITS; SVG: the unit of width/height), "width", "height" (SVG only),
  "polylines": [{"layer", "closed", "points": [[x, y, bulge], ...]}],
  "circles": [{"layer", "x", "y", "r"}], "texts": [{"layer", "text", "x", "y", "height"}].
SVG coordinates are turned back to y up (y = height - y_svg); SVG arcs to bulges."""
import json
import math
import os
import re
import sys
import xml.etree.ElementTree as ET

import ezdxf


def read_dxf(path):
    doc = ezdxf.readfile(path)
    out = {"version": doc.dxfversion, "units": doc.header.get("$INSUNITS", 0),
           "layers": sorted(layer.dxf.name for layer in doc.layers),
           "polylines": [], "circles": [], "texts": [], "other": []}
    for e in doc.modelspace():
        kind = e.dxftype()
        if kind == "LWPOLYLINE":
            points = [[p[0], p[1], p[4]] for p in e.get_points("xyseb")]
            out["polylines"].append({"layer": e.dxf.layer, "closed": bool(e.closed),
                                     "points": points})
        elif kind == "CIRCLE":
            c = e.dxf.center
            out["circles"].append({"layer": e.dxf.layer, "x": c[0], "y": c[1],
                                   "r": e.dxf.radius})
        elif kind == "TEXT":
            p = e.dxf.insert
            out["texts"].append({"layer": e.dxf.layer, "text": e.dxf.text, "x": p[0], "y": p[1],
                                 "height": e.dxf.height})
        else:
            out["other"].append(kind)
    return out


def svg_length_mm(text):
    m = re.fullmatch(r"([0-9.eE+-]+)mm", text)
    return float(m.group(1)) if m else None


def parse_path(d, height):
    tokens = re.findall(r"[MLAZ]|-?[0-9.]+(?:[eE][-+]?[0-9]+)?", d)
    points, closed, i = [], False, 0
    while i < len(tokens):
        t = tokens[i]
        if t in ("M", "L"):
            points.append([float(tokens[i + 1]), height - float(tokens[i + 2]), 0.0])
            i += 3
        elif t == "A":
            r, large, sweep = float(tokens[i + 1]), int(tokens[i + 4]), int(tokens[i + 5])
            x, y = float(tokens[i + 6]), height - float(tokens[i + 7])
            a = points[-1]
            chord = math.hypot(x - a[0], y - a[1])
            half = math.asin(min(1.0, chord / (2 * r)))
            theta = 2 * half if not large else 2 * math.pi - 2 * half
            # sweep 1: SVG's positive angle direction (y down), which is clockwise once y points
            # up again: a negative bulge.
            a[2] = math.tan(theta / 4) * (-1 if sweep else 1)
            points.append([x, y, 0.0])
            i += 8
        elif t == "Z":
            closed = True
            i += 1
        else:
            raise ValueError("unexpected path token " + t)
    if closed and len(points) > 1 and abs(points[-1][0] - points[0][0]) < 1e-9 and \
            abs(points[-1][1] - points[0][1]) < 1e-9:
        points[0][2] = points[-1][2] if points[0][2] == 0 else points[0][2]
        points.pop()
    return points, closed


def read_svg(path):
    ns = "{http://www.w3.org/2000/svg}"
    root = ET.parse(path).getroot()
    width, height = svg_length_mm(root.get("width")), svg_length_mm(root.get("height"))
    out = {"units": "mm" if width is not None else root.get("width"), "width": width,
           "height": height, "polylines": [], "circles": [], "texts": []}
    for group in root.iter(ns + "g"):
        layer = group.get("id")
        colour = group.get("stroke")
        for e in group:
            if e.tag == ns + "path":
                points, closed = parse_path(e.get("d"), height)
                out["polylines"].append({"layer": layer, "colour": colour, "closed": closed,
                                         "points": points})
            elif e.tag == ns + "circle":
                out["circles"].append({"layer": layer, "colour": colour,
                                       "x": float(e.get("cx")),
                                       "y": height - float(e.get("cy")), "r": float(e.get("r"))})
            elif e.tag == ns + "text":
                out["texts"].append({"layer": layer, "colour": e.get("fill"), "text": e.text,
                                     "x": float(e.get("x")), "y": height - float(e.get("y")),
                                     "height": float(e.get("font-size"))})
    return out


def main():
    folder = sys.argv[1]
    kit = json.load(open(os.path.join(folder, "kit.json")))
    sheets = []
    for sheet in kit["sheets"]:
        sheets.append({"name": sheet["dxf"],
                       "dxf": read_dxf(os.path.join(folder, sheet["dxf"])),
                       "svg": read_svg(os.path.join(folder, sheet["svg"]))})
    json.dump({"sheets": sheets, "ezdxf": ezdxf.__version__}, sys.stdout)


if __name__ == "__main__":
    main()
