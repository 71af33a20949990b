// SPDX-License-Identifier: GPL-3.0-or-later
#include "gridshell/mesh/normals.h"

namespace gridshell {

std::vector<Vec3> vertex_normals(const TriangleMesh& mesh) {
  std::vector<Vec3> normals(mesh.vertex_count(), Vec3::Zero());
  for (const Face& f : mesh.faces()) {
    const Vec3 n = (mesh.vertices()[f[1]] - mesh.vertices()[f[0]])
                       .cross(mesh.vertices()[f[2]] - mesh.vertices()[f[0]]);  // |n| = 2 area
    for (int v : f) normals[v] += n;
  }
  for (Vec3& n : normals)
    if (n.norm() > 0) n.normalize();
  return normals;
}

}  // namespace gridshell
