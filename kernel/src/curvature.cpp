#include "gridshell/curvature.h"

#include <cmath>
#include <numbers>

#include "gridshell/mesh_topology.h"

namespace gridshell {
namespace {
double angle_at(const Vec3& apex, const Vec3& a, const Vec3& b) {
  const Vec3 u = a - apex, v = b - apex;
  return std::atan2(u.cross(v).norm(), u.dot(v));
}
}  // namespace

std::vector<double> vertex_angle_sums(const TriangleMesh& mesh) {
  std::vector<double> sums(mesh.vertex_count(), 0.0);
  for (const Face& f : mesh.faces)
    for (int i = 0; i < 3; ++i)
      sums[f[i]] += angle_at(mesh.vertices[f[i]], mesh.vertices[f[(i + 1) % 3]],
                             mesh.vertices[f[(i + 2) % 3]]);
  return sums;
}

std::vector<double> vertex_areas(const TriangleMesh& mesh) {
  std::vector<double> areas(mesh.vertex_count(), 0.0);
  for (const Face& f : mesh.faces) {
    const Vec3& a = mesh.vertices[f[0]];
    const double third =
        (mesh.vertices[f[1]] - a).cross(mesh.vertices[f[2]] - a).norm() / 6.0;
    for (int v : f) areas[v] += third;
  }
  return areas;
}

std::vector<double> gaussian_curvature(const TriangleMesh& mesh) {
  const MeshTopology topology = build_topology(mesh);
  const std::vector<double> sums = vertex_angle_sums(mesh);
  const std::vector<double> areas = vertex_areas(mesh);
  std::vector<double> k(mesh.vertex_count(), 0.0);
  for (int v = 0; v < mesh.vertex_count(); ++v)
    if (!topology.is_boundary_vertex[v] && areas[v] > 0)
      k[v] = (2 * std::numbers::pi - sums[v]) / areas[v];
  return k;
}

}  // namespace gridshell
