// SPDX-License-Identifier: GPL-3.0-or-later
// gridshell — private interfaces shared by the geodesic engines (geodesic*.cpp only).
//
// DistanceField::Impl and GeodesicSolver::Impl are abstract; each engine (fast window
// propagation, CGAL oracle, CGAL heat method) derives from them. Nothing here is public API.
#pragma once

#include <array>
#include <memory>
#include <vector>

#include "gridshell/geodesic/geodesic.h"

namespace gridshell {

/// One solved distance field. `source` is the validated (normalised) source point.
class DistanceField::Impl {
 public:
  virtual ~Impl() = default;
  virtual double distance_to(const SurfacePoint& target) const = 0;
  virtual std::vector<SurfacePoint> path_to(const SurfacePoint& target) const = 0;
  /// Memory the field holds for its queries (windows and their index), bytes.
  virtual std::size_t memory_bytes() const { return 0; }
  /// Memory the solve held at its largest (more than memory_bytes() where it dropped windows).
  virtual std::size_t peak_memory_bytes() const { return memory_bytes(); }

  SurfacePoint source;
  std::vector<double> distances;         ///< per vertex, +inf if unreachable
  std::vector<double> target_distances;  ///< per SolveOptions::targets
};

/// Per-mesh precomputation of one engine; `solve` must be const and thread-safe.
class GeodesicSolver::Impl {
 public:
  virtual ~Impl() = default;
  /// `source` and `options.targets` have been validated by `normalize_surface_point`; the field
  /// returned has its `target_distances` filled.
  virtual DistanceField solve(const SurfacePoint& source, const SolveOptions& options,
                              const Progress& progress) const = 0;

  TriangleMesh mesh;
  GeodesicMethod method = GeodesicMethod::Fast;
};

namespace geodesic_detail {

/// Checks a surface point against `mesh` (face index in range, finite non-negative weights
/// summing to 1 within 1e-9) and returns it with weights below 1e-14 snapped to exactly 0 and
/// renormalised, so that points on edges and vertices are recognised exactly. Throws
/// InvalidInput otherwise, with `field` naming the point ("source", "target").
SurfacePoint normalize_surface_point(const TriangleMesh& mesh, const SurfacePoint& point,
                                     const std::string& field);

/// Number of exactly-zero weights: 0 = face interior, 1 = on an edge, 2 = at a vertex.
int zero_weight_count(const SurfacePoint& point);

/// Engines. The mesh has already been checked to be manifold (build_topology succeeded).
std::unique_ptr<GeodesicSolver::Impl> make_fast_solver(const TriangleMesh& mesh);
std::unique_ptr<GeodesicSolver::Impl> make_cgal_solver(const TriangleMesh& mesh);
std::unique_ptr<GeodesicSolver::Impl> make_heat_solver(const TriangleMesh& mesh);

}  // namespace geodesic_detail
}  // namespace gridshell
