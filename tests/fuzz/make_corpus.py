#!/usr/bin/env python3
# SPDX-License-Identifier: GPL-3.0-or-later
"""Writes the fuzz targets' seed corpora (tests/fuzz/corpus/<target>/): small, valid files of
each format and small requests of each RPC, so that fuzzing starts from inputs that reach deep
into the parsers. Deterministic; run it again after changing it and commit the result."""
import base64
import json
import os
import struct

HERE = os.path.dirname(os.path.abspath(__file__))


def grid(n=3, bump=0.1):
    """An n x n vertex square grid in z = bump*x*y, two triangles per cell."""
    vs = [(x / (n - 1), y / (n - 1), bump * x * y / (n - 1) ** 2) for y in range(n) for x in range(n)]
    fs = []
    for y in range(n - 1):
        for x in range(n - 1):
            a, b, c, d = y * n + x, y * n + x + 1, (y + 1) * n + x + 1, (y + 1) * n + x
            fs += [(a, b, c), (a, c, d)]
    return vs, fs


def write(target, name, data):
    folder = os.path.join(HERE, "corpus", target)
    os.makedirs(folder, exist_ok=True)
    with open(os.path.join(folder, name), "wb") as f:
        f.write(data if isinstance(data, bytes) else data.encode())


def obj(vs, fs, extras=False):
    out = ["# grid", "o patch"]
    out += ["v %g %g %g" % v for v in vs]
    if extras:
        out += ["vt 0 0", "vn 0 0 1", "s off", "g group"]
        out += ["f %d/1/1 %d/1/1 %d/1/1" % tuple(i + 1 for i in f) for f in fs]
    else:
        out += ["f %d %d %d" % tuple(i + 1 for i in f) for f in fs]
    return "\n".join(out) + "\n"


def off(vs, fs):
    out = ["OFF", "%d %d 0" % (len(vs), len(fs))]
    out += ["%g %g %g" % v for v in vs]
    out += ["3 %d %d %d" % f for f in fs]
    return "\n".join(out) + "\n"


def ply_ascii(vs, fs):
    head = ["ply", "format ascii 1.0", "comment seed", "element vertex %d" % len(vs),
            "property float x", "property float y", "property float z",
            "element face %d" % len(fs), "property list uchar int vertex_indices", "end_header"]
    body = ["%g %g %g" % v for v in vs] + ["3 %d %d %d" % f for f in fs]
    return "\n".join(head + body) + "\n"


def ply_binary(vs, fs, endian):
    name = "binary_little_endian" if endian == "<" else "binary_big_endian"
    head = ("ply\nformat %s 1.0\nelement vertex %d\nproperty double x\nproperty double y\n"
            "property double z\nproperty uchar red\nelement face %d\n"
            "property list uchar uint vertex_indices\nend_header\n" % (name, len(vs), len(fs)))
    body = b"".join(struct.pack(endian + "dddB", *v, 200) for v in vs)
    body += b"".join(struct.pack(endian + "BIII", 3, *f) for f in fs)
    return head.encode() + body


def stl_ascii(vs, fs):
    out = ["solid grid"]
    for f in fs:
        out += ["facet normal 0 0 1", " outer loop"]
        out += ["  vertex %g %g %g" % vs[i] for i in f]
        out += [" endloop", "endfacet"]
    return "\n".join(out + ["endsolid grid"]) + "\n"


def stl_binary(vs, fs):
    data = b"binary seed".ljust(80, b" ") + struct.pack("<I", len(fs))
    for f in fs:
        data += struct.pack("<3f", 0, 0, 1)
        for i in f:
            data += struct.pack("<3f", *vs[i])
        data += b"\0\0"
    return data


def packed(vs, fs):
    return {"name": "grid", "positions": [c for v in vs for c in v],
            "indices": [i for f in fs for i in f]}


def main():
    vs, fs = grid()
    vs5, fs5 = grid(5)
    write("mesh_obj", "grid.obj", obj(vs, fs))
    write("mesh_obj", "grid_slashes.obj", obj(vs5, fs5, extras=True))
    write("mesh_obj", "quad_negative.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf -4 -3 -2 -1\n")
    write("mesh_off", "grid.off", off(vs, fs))
    write("mesh_off", "quad.off", "OFF\n# a comment\n4 1 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n")
    write("mesh_ply", "grid_ascii.ply", ply_ascii(vs, fs))
    write("mesh_ply", "grid_le.ply", ply_binary(vs, fs, "<"))
    write("mesh_ply", "grid_be.ply", ply_binary(vs5, fs5, ">"))
    write("mesh_stl", "grid_ascii.stl", stl_ascii(vs, fs))
    write("mesh_stl", "grid_binary.stl", stl_binary(vs5, fs5))

    # Requests: first byte = RPC (0 patch, 1 design, 2 simulate, 3 run, 4 geodesic, 5 load,
    # 6 examples), the rest the JSON body as the gateway receives it.
    mesh = packed(vs5, fs5)
    corners = {"vertices": [0, 4, 24, 20]}
    file_mesh = {"name": "grid.obj", "file": base64.b64encode(obj(vs, fs).encode()).decode(),
                 "format": "obj"}
    requests = {
        "patch_arrays": (0, {"mesh": mesh, "corners": corners,
                             "options": {"maxSmoothingIterations": 2, "etaMax": 1.01}}),
        # Corners.points is a repeated double: x, y, z of each corner in turn.
        "patch_points": (0, {"mesh": mesh, "corners": {"points": [
            0, 0, 0, 1, 0, 0, 1, 1, 0.1, 0, 1, 0]}}),
        "design_example": (1, {"mesh": {"example": "double-vault"},
                               "options": {"alpha": "70deg", "membersU": 4, "membersV": 5,
                                           "lamellaWidth": 0.02, "resolution": 20,
                                           "interiorAnchors": 1}}),
        "design_file": (1, {"mesh": file_mesh, "corners": {"vertices": [0, 2, 8, 6]},
                            "files": True}),
        "simulate": (2, {"design": {"members": [], "crossings": []},
                         "options": {"frictionMu": 0.2, "unit": "mm", "notches": "on"}}),
        "run": (3, {"design": {"mesh": {"example": "sphere"}}, "simulation": {"notches": "both"}}),
        "geodesic": (4, {"mesh": mesh, "source": 3, "method": "fast", "compare": "cgal",
                         "distances": True}),
        "load_file": (5, {"mesh": file_mesh}),
        "load_ply": (5, {"mesh": {"file": base64.b64encode(ply_binary(vs, fs, "<")).decode(),
                                  "format": "grid.PLY"}}),
        "examples": (6, {}),
    }
    for name, (rpc, body) in requests.items():
        write("request_json", name, bytes([rpc]) + json.dumps(body).encode())

    for i, text in enumerate(["auto", "0,1,2,3", " 12, 7 ,99,4 ", "0,0,0;1,0,0;1,1,0.5;0,1,0",
                              "1e3,-2.5e-1,0;1,2,3;4,5,6;7,8,9"]):
        write("corners", "corners_%d" % i, b"\0" + text.encode())
    for i, text in enumerate(["min", "max", "1.2", "70deg", " 0.5 "]):
        write("corners", "alpha_%d" % i, b"\1" + text.encode())


if __name__ == "__main__":
    main()
