// SPDX-License-Identifier: GPL-3.0-or-later
#include "gridshell/mesh/curvature.h"

#include <cmath>
#include <numbers>

#include "gridshell/mesh/mesh_topology.h"

namespace gridshell {
namespace {
double angle_at(const Vec3& apex, const Vec3& a, const Vec3& b) {
  const Vec3 u = a - apex, v = b - apex;
  return std::atan2(u.cross(v).norm(), u.dot(v));
}
}  // namespace

std::vector<double> vertex_angle_sums(const TriangleMesh& mesh) {
  std::vector<double> sums(mesh.vertex_count(), 0.0);
  for (const Face& f : mesh.faces())
    for (int i = 0; i < 3; ++i)
      sums[f[i]] += angle_at(mesh.vertices()[f[i]], mesh.vertices()[f[(i + 1) % 3]],
                             mesh.vertices()[f[(i + 2) % 3]]);
  return sums;
}

std::vector<double> vertex_areas(const TriangleMesh& mesh) {
  std::vector<double> areas(mesh.vertex_count(), 0.0);
  for (const Face& f : mesh.faces()) {
    const Vec3& a = mesh.vertices()[f[0]];
    const double third = (mesh.vertices()[f[1]] - a).cross(mesh.vertices()[f[2]] - a).norm() / 6.0;
    for (int v : f) areas[v] += third;
  }
  return areas;
}

std::vector<double> mixed_voronoi_areas(const TriangleMesh& mesh) {
  std::vector<double> areas(mesh.vertex_count(), 0.0);
  for (const Face& f : mesh.faces()) {
    const Vec3 p[3] = {mesh.vertices()[f[0]], mesh.vertices()[f[1]], mesh.vertices()[f[2]]};
    const double area = 0.5 * (p[1] - p[0]).cross(p[2] - p[0]).norm();
    if (area <= 0) continue;
    double cot[3];
    bool obtuse = false;
    int obtuse_at = -1;
    for (int i = 0; i < 3; ++i) {
      const Vec3 u = p[(i + 1) % 3] - p[i], v = p[(i + 2) % 3] - p[i];
      cot[i] = u.dot(v) / u.cross(v).norm();
      if (u.dot(v) < 0) {
        obtuse = true;
        obtuse_at = i;
      }
    }
    for (int i = 0; i < 3; ++i) {
      if (obtuse) {
        areas[f[i]] += i == obtuse_at ? area / 2 : area / 4;
      } else {
        // Voronoi region: (|e_ij|^2 cot(angle opposite e_ij) + |e_ik|^2 cot(opposite e_ik)) / 8.
        const int j = (i + 1) % 3, k = (i + 2) % 3;
        areas[f[i]] +=
            ((p[j] - p[i]).squaredNorm() * cot[k] + (p[k] - p[i]).squaredNorm() * cot[j]) / 8;
      }
    }
  }
  return areas;
}

std::vector<double> gaussian_curvature(const TriangleMesh& mesh) {
  const MeshTopology& topology = mesh.topology();
  const std::vector<double> sums = vertex_angle_sums(mesh);
  const std::vector<double> areas = mixed_voronoi_areas(mesh);
  std::vector<double> k(mesh.vertex_count(), 0.0);
  for (int v = 0; v < mesh.vertex_count(); ++v)
    if (!topology.is_boundary_vertex[v] && areas[v] > 0)
      k[v] = (2 * std::numbers::pi - sums[v]) / areas[v];
  return k;
}

}  // namespace gridshell
