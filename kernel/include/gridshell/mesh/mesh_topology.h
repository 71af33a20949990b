// SPDX-License-Identifier: GPL-3.0-or-later
// gridshell — connectivity of a manifold triangle mesh: face adjacency, one-rings, boundary loops.
#pragma once

#include <array>
#include <string>
#include <vector>

namespace gridshell {

/// Three vertex indices of a triangle, counter-clockwise seen from the side the normal points to.
using Face = std::array<int, 3>;

/// Connectivity of a manifold, consistently oriented triangle mesh. Local edge i of face f runs
/// from faces[f][i] to faces[f][(i+1)%3]. Every TriangleMesh carries one, built once when the
/// mesh is made (mesh.h).
struct MeshTopology {
  /// #F x 3: the face across local edge i of face f, or -1 if that edge is on the boundary.
  std::vector<std::array<int, 3>> face_neighbors;
  /// #V lists of incident faces, in increasing face order.
  std::vector<std::vector<int>> vertex_faces;
  /// #V flags: 1 if the vertex lies on a boundary edge.
  std::vector<char> is_boundary_vertex;
  /// Boundary loops as vertex indices, each ordered along the face orientation (the mesh
  /// interior lies to the left when the faces are counter-clockwise seen from above); loops in
  /// the order of their smallest vertex. Empty for a closed mesh.
  std::vector<std::vector<int>> boundary_loops;
};

/// Problems `check_manifold` can find, with the offending element.
struct TopologyProblem {
  enum class Kind {
    None,
    InvalidIndex,
    NonManifoldEdge,
    NonManifoldVertex,
    InconsistentOrientation
  };
  Kind kind = Kind::None;
  int element = -1;  ///< face (InvalidIndex, InconsistentOrientation) or vertex index
  int other = -1;    ///< second vertex of a non-manifold edge
  /// Plain description ("non-manifold edge between vertices 3 and 7 (...)").
  std::string message() const;
  /// The element as a path into the mesh: "faces[12]" or "vertices[3]"; empty for None.
  std::string field() const;
};

/// First problem that prevents `build_topology` for `vertex_count` vertices and these faces, or
/// Kind::None. Faces must be index triples of three distinct vertices in [0, vertex_count).
TopologyProblem check_manifold(int vertex_count, const std::vector<Face>& faces);

/// Connectivity; throws InvalidInput (field TopologyProblem::field(), its message) for a mesh
/// that is not manifold and consistently oriented.
MeshTopology build_topology(int vertex_count, const std::vector<Face>& faces);

}  // namespace gridshell
