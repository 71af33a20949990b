// SPDX-License-Identifier: GPL-3.0-or-later
#include "gridshell/mesh/surface_point.h"

#include <sstream>

#include "gridshell/foundation/errors.h"

namespace gridshell {

SurfacePoint SurfacePoint::at_vertex(const TriangleMesh& mesh, int vertex) {
  if (vertex < 0 || vertex >= mesh.vertex_count()) {
    std::ostringstream msg;
    msg << "vertex " << vertex << " is out of range (the mesh has " << mesh.vertex_count()
        << " vertices)";
    throw InvalidInput("", msg.str());
  }
  const std::vector<int>& faces = mesh.topology().vertex_faces[vertex];
  if (faces.empty())
    throw InvalidInput("", "vertex " + std::to_string(vertex) + " is isolated (no face uses it)");
  const int f = faces.front();
  const Face& face = mesh.faces()[f];
  SurfacePoint p;
  p.face = f;
  p.barycentric = Vec3::Zero();
  p.barycentric[face[0] == vertex ? 0 : face[1] == vertex ? 1 : 2] = 1.0;
  return p;
}

SurfacePoint SurfacePoint::on_edge(const TriangleMesh& mesh, int a, int b, double t) {
  if (!(t >= 0.0 && t <= 1.0)) {
    std::ostringstream msg;
    msg << "edge parameter t = " << t << " is outside [0, 1]";
    throw InvalidInput("", msg.str());
  }
  const auto [f, i] = find_edge(mesh, a, b);
  if (f >= 0) {
    const Face& face = mesh.faces()[f];
    const int j = (i + 1) % 3;
    SurfacePoint p;
    p.face = f;
    p.barycentric = Vec3::Zero();
    const int ia = face[i] == a ? i : j, ib = face[i] == a ? j : i;
    p.barycentric[ia] = 1.0 - t;
    p.barycentric[ib] = t;
    if (t == 0.0) p.barycentric[ia] = 1.0;  // exact vertex
    if (t == 1.0) p.barycentric[ib] = 1.0;
    return p;
  }
  throw InvalidInput("", "vertices " + std::to_string(a) + " and " + std::to_string(b) +
                             " are not joined by an edge of the mesh");
}

Vec3 SurfacePoint::position(const TriangleMesh& mesh) const {
  const Face& f = mesh.faces().at(face);
  return barycentric[0] * mesh.vertices()[f[0]] + barycentric[1] * mesh.vertices()[f[1]] +
         barycentric[2] * mesh.vertices()[f[2]];
}

int SurfacePoint::vertex(const TriangleMesh& mesh) const {
  if (face < 0 || face >= mesh.face_count()) return -1;
  for (int i = 0; i < 3; ++i)
    if (barycentric[i] == 1.0 && barycentric[(i + 1) % 3] == 0.0 && barycentric[(i + 2) % 3] == 0.0)
      return mesh.faces()[face][i];
  return -1;
}

Vec3 closest_point_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return {1, 0, 0};
  const Vec3 bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return {0, 1, 0};
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    const double v = d1 / (d1 - d3);
    return {1 - v, v, 0};
  }
  const Vec3 cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return {0, 0, 1};
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    const double w = d2 / (d2 - d6);
    return {1 - w, 0, w};
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return {0, 1 - w, w};
  }
  const double denom = 1.0 / (va + vb + vc);
  const double v = vb * denom, w = vc * denom;
  return {1 - v - w, v, w};
}

}  // namespace gridshell
