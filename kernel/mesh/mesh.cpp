// SPDX-License-Identifier: GPL-3.0-or-later
#include "gridshell/mesh/mesh.h"

#include <stdexcept>

namespace gridshell {

TriangleMesh::TriangleMesh() : topology_(std::make_shared<const MeshTopology>()) {}

TriangleMesh::TriangleMesh(std::vector<Vec3> vertices, std::vector<Face> faces)
    : vertices_(std::move(vertices)),
      faces_(std::move(faces)),
      topology_(std::make_shared<const MeshTopology>(
          build_topology(static_cast<int>(vertices_.size()), faces_))) {}

void TriangleMesh::set_vertices(std::vector<Vec3> positions) {
  if (positions.size() != vertices_.size())
    throw std::invalid_argument("TriangleMesh::set_vertices: " + std::to_string(positions.size()) +
                                " positions for " + std::to_string(vertices_.size()) + " vertices");
  vertices_ = std::move(positions);
}

Vec3 bounding_box_size(const TriangleMesh& mesh) {
  if (mesh.vertices().empty()) return Vec3::Zero();
  Vec3 lo = mesh.vertices().front(), hi = lo;
  for (const Vec3& p : mesh.vertices()) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  return hi - lo;
}

double surface_area(const TriangleMesh& mesh) {
  double area = 0;
  const std::vector<Vec3>& x = mesh.vertices();
  for (const Face& f : mesh.faces())
    area += 0.5 * (x[f[1]] - x[f[0]]).cross(x[f[2]] - x[f[0]]).norm();
  return area;
}

std::array<int, 2> find_edge(const TriangleMesh& mesh, int a, int b) {
  if (a < 0 || a >= mesh.vertex_count()) return {-1, -1};
  for (int f : mesh.topology().vertex_faces[a]) {
    const Face& t = mesh.faces()[f];
    for (int i = 0; i < 3; ++i) {
      const int x = t[i], y = t[(i + 1) % 3];
      if ((x == a && y == b) || (x == b && y == a)) return {f, i};
    }
  }
  return {-1, -1};
}

}  // namespace gridshell
