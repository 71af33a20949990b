#include "gridshell/mesh/mesh.h"

namespace gridshell {

Vec3 bounding_box_size(const TriangleMesh& mesh) {
  if (mesh.vertices.empty()) return Vec3::Zero();
  Vec3 lo = mesh.vertices.front(), hi = lo;
  for (const Vec3& p : mesh.vertices) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  return hi - lo;
}

double surface_area(const TriangleMesh& mesh) {
  double area = 0;
  for (const Face& f : mesh.faces) {
    const Vec3& a = mesh.vertices[f[0]];
    area += 0.5 * (mesh.vertices[f[1]] - a).cross(mesh.vertices[f[2]] - a).norm();
  }
  return area;
}

}  // namespace gridshell
