// SPDX-License-Identifier: GPL-3.0-or-later
// gridshell — points on a triangle mesh: a face and barycentric weights.
#pragma once

#include "gridshell/mesh/mesh.h"

namespace gridshell {

/// A point on the surface: a face and barycentric weights of the face's three vertices
/// (non-negative, summing to 1). A point on an edge has the weight of the opposite vertex
/// exactly 0.0; a vertex has its own weight exactly 1.0 and the others exactly 0.0.
struct SurfacePoint {
  int face = -1;
  Vec3 barycentric = Vec3::Zero();

  /// The point at vertex `vertex` (in any face incident to it). Throws InvalidInput for an
  /// out-of-range or isolated vertex.
  static SurfacePoint at_vertex(const TriangleMesh& mesh, int vertex);
  /// The point (1-t)*a + t*b on the edge between vertices a and b. Throws InvalidInput if ab is
  /// not an edge of the mesh or t is outside [0,1].
  static SurfacePoint on_edge(const TriangleMesh& mesh, int a, int b, double t);
  /// 3D position of the point.
  Vec3 position(const TriangleMesh& mesh) const;
  /// The vertex index if the point is exactly at a vertex, otherwise -1.
  int vertex(const TriangleMesh& mesh) const;
};

/// Closest point on triangle abc to p (Ericson, Real-Time Collision Detection 5.1.5), as
/// barycentric weights of (a, b, c).
Vec3 closest_point_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c);

}  // namespace gridshell
