# SPDX-License-Identifier: GPL-3.0-or-later
"""The target surface of a request from a Blender mesh object: its evaluated mesh (modifiers
applied) in world coordinates as packed arrays, and the corners from the selected vertices."""

import math
from array import array

import bmesh

from .remote import gs


class InputError(Exception):
    """The scene does not give a target (no mesh object, a wrong number of corners)."""


def world_positions(mesh, matrix):
    """Vertex coordinates of ``mesh`` transformed by ``matrix``, in double precision, flat."""
    co = array("f", bytes(4 * 3 * len(mesh.vertices)))
    mesh.vertices.foreach_get("co", co)
    m = [[float(matrix[r][c]) for c in range(4)] for r in range(3)]
    (a, b, c, d), (e, f, g, h), (i, j, k, l) = m
    out = [0.0] * len(co)
    for n in range(0, len(co), 3):
        x, y, z = co[n], co[n + 1], co[n + 2]
        out[n] = a * x + b * y + c * z + d
        out[n + 1] = e * x + f * y + g * z + h
        out[n + 2] = i * x + j * y + k * z + l
    return out


def triangles(mesh):
    mesh.calc_loop_triangles()
    tris = array("i", bytes(4 * 3 * len(mesh.loop_triangles)))
    mesh.loop_triangles.foreach_get("vertices", tris)
    return tris.tolist()


def selected_corners(obj):
    """The selected vertices of the object's own mesh: (indices in selection order, how many
    vertices the mesh has). Without a recorded order for all four, they are ordered around their
    centroid (any starting vertex)."""
    mesh = obj.data
    flags = array("b", bytes(len(mesh.vertices)))
    mesh.vertices.foreach_get("select", flags)
    selected = [v for v, s in enumerate(flags) if s]
    if len(selected) == len(mesh.vertices):
        return [], len(mesh.vertices)  # everything selected: nothing chosen, automatic
    if len(selected) != 4:
        return selected, len(mesh.vertices)
    bm = bmesh.new()
    try:
        bm.from_mesh(mesh)
        history = [e.index for e in bm.select_history if isinstance(e, bmesh.types.BMVert)]
    finally:
        bm.free()
    ordered = [v for v in history if v in selected]
    if sorted(ordered) == sorted(selected) and len(ordered) == 4:
        return ordered, len(mesh.vertices)
    return around_centroid(mesh, selected), len(mesh.vertices)


def around_centroid(mesh, vertices):
    points = [tuple(mesh.vertices[v].co) for v in vertices]
    c = [sum(p[k] for p in points) / len(points) for k in range(3)]
    # Newell normal of the polygon through the points, any order: a plane to sort them in.
    n = [0.0, 0.0, 0.0]
    for a in range(len(points)):
        p, q = points[a], points[(a + 1) % len(points)]
        n[0] += (p[1] - q[1]) * (p[2] + q[2])
        n[1] += (p[2] - q[2]) * (p[0] + q[0])
        n[2] += (p[0] - q[0]) * (p[1] + q[1])
    axis = max(range(3), key=lambda k: abs(n[k]))
    u, w = [k for k in range(3) if k != axis]
    order = sorted(range(len(points)), key=lambda a: math.atan2(points[a][w] - c[w], points[a][u] - c[u]))
    return [vertices[a] for a in order]


def _check_object(obj):
    if obj is None or obj.type != "MESH":
        raise InputError(
            "select a mesh object as the target surface (%s)"
            % ("there is no active object" if obj is None else "the active object %s is of type %s" % (obj.name, obj.type.lower()))
        )
    if obj.mode == "EDIT":
        obj.update_from_editmode()


def _evaluated_arrays(obj, depsgraph):
    """(world positions, triangle indices, vertex count) of the object's evaluated mesh."""
    evaluated = obj.evaluated_get(depsgraph)
    mesh = evaluated.to_mesh()
    try:
        if len(mesh.polygons) == 0:
            raise InputError("%s has no faces" % obj.name)
        return world_positions(mesh, obj.matrix_world), triangles(mesh), len(mesh.vertices)
    finally:
        evaluated.to_mesh_clear()


def target(obj, depsgraph):
    """(mesh message, corners or None, description) for a design of ``obj``'s surface."""
    _check_object(obj)
    corners, base_count = selected_corners(obj)
    if corners and len(corners) != 4:
        raise InputError(
            "select 4 corner vertices of %s in order (or none for automatic corners); %d are selected"
            % (obj.name, len(corners))
        )
    evaluated = obj.evaluated_get(depsgraph)
    mesh = evaluated.to_mesh()
    try:
        if len(mesh.polygons) == 0:
            raise InputError("%s has no faces" % obj.name)
        positions = world_positions(mesh, obj.matrix_world)
        indices = triangles(mesh)
        same_vertices = len(mesh.vertices) == base_count
    finally:
        evaluated.to_mesh_clear()
    request_corners = None
    if corners and same_vertices:
        request_corners = {"vertices": corners}
    elif corners:
        # Modifiers changed the vertices: send the corners as points, snapped to the surface.
        base = world_positions(obj.data, obj.matrix_world)
        request_corners = {"points": [base[3 * v + k] for v in corners for k in range(3)]}
    mesh_message = gs.mesh_arrays(positions, indices, name=obj.name)
    how = "vertices %s" % ",".join(map(str, corners)) if corners else "automatic"
    return mesh_message, request_corners, "%s (%d vertices), corners %s" % (
        obj.name,
        len(positions) // 3,
        how,
    )


def request_mesh_for_scene(context):
    """The request's mesh and corners for the active object of ``context`` (for scripts)."""
    return target(context.active_object, context.evaluated_depsgraph_get())


def layout_target(obj, depsgraph):
    """(mesh message, description, vertex count of the evaluated mesh) of ``obj``'s surface for
    a layout of several patches (the selection plays no part: the layout says where the corners
    are)."""
    _check_object(obj)
    positions, indices, count = _evaluated_arrays(obj, depsgraph)
    what = "%s (%d vertices)" % (obj.name, len(positions) // 3)
    return gs.mesh_arrays(positions, indices, name=obj.name), what, count


def vertex_group_layout(obj, evaluated_count=None):
    """A ``gridshell.v1.Layout`` from the object's vertex groups: every vertex group of exactly 4
    vertices is one patch, named by the group; a vertex in several groups is one corner that the
    patches share. Each patch's corners are ordered around their centre, counter-clockwise seen
    from the side the mesh's normals point to (the sum of the 4 vertices' normals), so that all
    patches turn the same way. ``evaluated_count``: the vertices of the mesh sent (modifiers
    that change them: the corners go as points). Returns (layout, the groups left out)."""
    _check_object(obj)
    mesh = obj.data
    members = {group.index: [] for group in obj.vertex_groups}
    for vertex in mesh.vertices:
        for element in vertex.groups:
            if element.weight > 0 and element.group in members:
                members[element.group].append(vertex.index)
    patches, ignored, corner_of = [], [], {}
    for group in obj.vertex_groups:
        vertices = members[group.index]
        if len(vertices) != 4:
            ignored.append("%s (%d vertices)" % (group.name, len(vertices)))
            continue
        ordered = around_normal(mesh, vertices)
        ids = []
        for v in ordered:
            if v not in corner_of:
                corner_of[v] = len(corner_of)
            ids.append(corner_of[v])
        patches.append({"name": group.name, "corners": ids})
    if not patches:
        raise InputError(
            "%s has no vertex group of 4 vertices: each patch of a layout from vertex groups is a "
            "vertex group holding its 4 corner vertices%s"
            % (obj.name, " (groups: %s)" % ", ".join(ignored) if ignored else "")
        )
    corners = sorted(corner_of, key=corner_of.get)
    if evaluated_count is None or evaluated_count == len(mesh.vertices):
        layout_corners = [{"vertex": v} for v in corners]
    else:  # modifiers changed the vertices: the corners as points, snapped to the surface
        base = world_positions(mesh, obj.matrix_world)
        layout_corners = [{"point": base[3 * v : 3 * v + 3]} for v in corners]
    return {"corners": layout_corners, "patches": patches}, ignored


def around_normal(mesh, vertices):
    """``vertices`` ordered counter-clockwise around their centre, seen from the side their
    normals point to."""
    points = [tuple(mesh.vertices[v].co) for v in vertices]
    c = [sum(p[k] for p in points) / len(points) for k in range(3)]
    n = [sum(mesh.vertices[v].normal[k] for v in vertices) for k in range(3)]
    if math.sqrt(sum(x * x for x in n)) < 1e-12:
        return around_centroid(mesh, vertices)
    # A basis (u, w) of the plane across n, right-handed with n: (u, w, n).
    a = [1.0, 0.0, 0.0] if abs(n[0]) < 0.9 * math.sqrt(sum(x * x for x in n)) else [0.0, 1.0, 0.0]
    u = _cross(a, n)
    w = _cross(n, u)
    angle = []
    for p in points:
        d = [p[k] - c[k] for k in range(3)]
        angle.append(math.atan2(sum(d[k] * w[k] for k in range(3)), sum(d[k] * u[k] for k in range(3))))
    return [vertices[k] for k in sorted(range(len(points)), key=angle.__getitem__)]


def _cross(a, b):
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
