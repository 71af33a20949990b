// gridshell — triangle mesh value type shared by every kernel stage.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>  // cross products
#include <array>
#include <vector>

namespace gridshell {

using Vec2 = Eigen::Vector2d;
using Vec3 = Eigen::Vector3d;
/// Three vertex indices of a triangle, counter-clockwise seen from the side the normal points to.
using Face = std::array<int, 3>;

/// Largest coordinate magnitude accepted in meshes and points. gridshell works in double
/// precision with tolerances relative to the model's size; beyond this, squared distances and
/// areas lose their meaning long before they overflow (at ~1e154).
constexpr double kMaxCoordinate = 1e15;

/// A triangle mesh as plain data: #V vertex positions and #F triangles indexing them.
/// Lengths are in the mesh's own units. The kernel never keeps a mesh in global state.
struct TriangleMesh {
  std::vector<Vec3> vertices;  ///< #V positions
  std::vector<Face> faces;     ///< #F triangles, indices into `vertices`

  int vertex_count() const { return static_cast<int>(vertices.size()); }
  int face_count() const { return static_cast<int>(faces.size()); }
};

/// Axis-aligned extent (max - min) of the vertices, {0,0,0} for an empty mesh.
Vec3 bounding_box_size(const TriangleMesh& mesh);

/// Total surface area.
double surface_area(const TriangleMesh& mesh);

}  // namespace gridshell
