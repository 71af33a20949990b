// SPDX-License-Identifier: GPL-3.0-or-later
// gridshell — closest points and distances from points to a triangle mesh (one CGAL AABB tree):
// corners given as points, the deviation of a deployed grid from its target surface.
#pragma once

#include <memory>
#include <optional>

#include "gridshell/mesh/mesh.h"
#include "gridshell/mesh/surface_point.h"

namespace gridshell {

/// Closest-point queries on a fixed triangle mesh. Build once (O(F log F)), query from any
/// number of threads.
class SurfaceDistance {
 public:
  /// The mesh is copied. Throws InvalidInput for a mesh without faces.
  explicit SurfaceDistance(const TriangleMesh& mesh);
  ~SurfaceDistance();
  SurfaceDistance(SurfaceDistance&&) noexcept;
  SurfaceDistance& operator=(SurfaceDistance&&) noexcept;

  /// Euclidean distance from `point` to the closest point of the surface.
  double distance(const Vec3& point) const;
  /// The closest surface point (face and barycentric weights, up to rounding).
  SurfacePoint closest(const Vec3& point) const;
  /// Unit surface normal at the closest point: area-weighted vertex normals interpolated with
  /// the barycentric weights.
  Vec3 normal_at_closest(const Vec3& point) const;
  /// Where the ray from `origin` along `direction` first meets the surface (none if it misses).
  std::optional<Vec3> first_hit(const Vec3& origin, const Vec3& direction) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// One-off closest surface point (builds a SurfaceDistance; keep one for many queries). Throws
/// InvalidInput for a mesh without faces.
SurfacePoint closest_surface_point(const TriangleMesh& mesh, const Vec3& point);

}  // namespace gridshell
