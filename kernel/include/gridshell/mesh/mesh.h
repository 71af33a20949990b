// SPDX-License-Identifier: GPL-3.0-or-later
// gridshell — the triangle mesh every kernel stage works on: positions, faces and their
// connectivity, built once when the mesh is made.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>  // cross products
#include <array>
#include <memory>
#include <vector>

#include "gridshell/mesh/mesh_topology.h"

namespace gridshell {

using Vec2 = Eigen::Vector2d;
using Vec3 = Eigen::Vector3d;

/// Largest coordinate magnitude accepted in meshes and points. gridshell works in double
/// precision with tolerances relative to the model's size; beyond this, squared distances and
/// areas lose their meaning long before they overflow (at ~1e154).
constexpr double kMaxCoordinate = 1e15;

/// A manifold, consistently oriented triangle mesh: #V vertex positions, #F triangles indexing
/// them, and their connectivity (MeshTopology). The connectivity is built once, when the mesh is
/// made, and shared by copies; every stage (patch cut, geodesic solvers, curvature, grid) reads
/// it instead of rebuilding it. Positions may move (smoothing); faces may not change: a mesh
/// with other faces is a new mesh. Lengths are in the mesh's own units. The kernel never keeps
/// a mesh in global state.
class TriangleMesh {
 public:
  /// The empty mesh (no vertices, no faces).
  TriangleMesh();
  /// Checks the faces (indices in range, three distinct vertices, manifold edges and vertices,
  /// consistent orientation) and builds the connectivity. Throws InvalidInput naming the element
  /// ("faces[12]", "vertices[3]"). Vertices that no face uses are allowed (they are isolated).
  TriangleMesh(std::vector<Vec3> vertices, std::vector<Face> faces);

  const std::vector<Vec3>& vertices() const { return vertices_; }
  const std::vector<Face>& faces() const { return faces_; }
  const MeshTopology& topology() const { return *topology_; }
  int vertex_count() const { return static_cast<int>(vertices_.size()); }
  int face_count() const { return static_cast<int>(faces_.size()); }

  /// Moves vertex v to `position`.
  void set_vertex(int v, const Vec3& position) { vertices_[v] = position; }
  /// Moves every vertex; `positions` has one entry per vertex (std::invalid_argument otherwise).
  void set_vertices(std::vector<Vec3> positions);

 private:
  std::vector<Vec3> vertices_;
  std::vector<Face> faces_;
  std::shared_ptr<const MeshTopology> topology_;
};

/// Axis-aligned extent (max - min) of the vertices, {0,0,0} for an empty mesh.
Vec3 bounding_box_size(const TriangleMesh& mesh);

/// Total surface area.
double surface_area(const TriangleMesh& mesh);

/// Index of a face containing the directed or undirected edge (a,b) and the local edge index,
/// or {-1,-1}.
std::array<int, 2> find_edge(const TriangleMesh& mesh, int a, int b);

}  // namespace gridshell
