// gridshell — connectivity of a triangle mesh: face adjacency, one-rings, boundary loops.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "gridshell/mesh/mesh.h"

namespace gridshell {

/// Connectivity of a manifold triangle mesh. Local edge i of face f runs from faces[f][i] to
/// faces[f][(i+1)%3].
struct MeshTopology {
  /// #F x 3: the face across local edge i of face f, or -1 if that edge is on the boundary.
  std::vector<std::array<int, 3>> face_neighbors;
  /// #V lists of incident faces.
  std::vector<std::vector<int>> vertex_faces;
  /// #V flags: 1 if the vertex lies on a boundary edge.
  std::vector<char> is_boundary_vertex;
  /// Boundary loops as vertex indices, each ordered along the face orientation (the mesh
  /// interior lies to the left when the faces are counter-clockwise seen from above).
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
  std::string message() const;
};

/// First problem that prevents `build_topology`, or Kind::None. Faces must be non-degenerate
/// index triples (three distinct indices).
TopologyProblem check_manifold(const TriangleMesh& mesh);

/// Connectivity; throws InvalidInput with TopologyProblem::message() for a non-manifold mesh.
MeshTopology build_topology(const TriangleMesh& mesh);

/// Index of the face containing the directed or undirected edge (a,b) and the local edge index,
/// or {-1,-1}.
std::array<int, 2> find_edge(const TriangleMesh& mesh, const MeshTopology& topology, int a, int b);

}  // namespace gridshell
