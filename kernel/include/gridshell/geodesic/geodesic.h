// SPDX-License-Identifier: GPL-3.0-or-later
// gridshell — exact polyhedral geodesic distances and shortest paths on a triangle mesh.
//
// Paper Sections 3.3 and 4.2 need many single-source exact distance fields per design. The
// default engine (`GeodesicMethod::Fast`) is our own exact window-propagation algorithm
// (kernel/geodesic/geodesic_fast.cpp); CGAL's Surface_mesh_shortest_path (Xin-Wang) is kept as the
// oracle (`Cgal`) and CGAL's heat method (`Heat`, approximate) for comparison.
//
// Usage: build one GeodesicSolver per mesh (precomputes connectivity and per-face geometry),
// then call `solve` for as many sources as needed, from as many threads as wanted.
#pragma once

#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "gridshell/foundation/progress.h"
#include "gridshell/mesh/mesh.h"
#include "gridshell/mesh/surface_point.h"

namespace gridshell {

enum class GeodesicMethod {
  Fast,  ///< exact, our own window propagation (default)
  Cgal,  ///< exact, CGAL Surface_mesh_shortest_path (oracle; slow)
  Heat,  ///< approximate, CGAL Heat_method_3 (intrinsic Delaunay); distances only, no paths
};

/// "fast" | "cgal" | "heat"; throws InvalidInput naming the value otherwise.
GeodesicMethod parse_geodesic_method(const std::string& name);
std::string to_string(GeodesicMethod method);

struct GeodesicOptions {
  GeodesicMethod method = GeodesicMethod::Fast;  // default: our exact engine
};

/// What one single-source solve must provide. The defaults give a complete field: exact
/// distances to every vertex and to any surface point, and shortest paths. A caller that needs
/// less can say so and pay less (fast engine; CGAL and heat honour `targets` and ignore the rest).
struct SolveOptions {
  /// Surface points whose exact distances the caller needs; DistanceField::target_distances()
  /// lists them in this order. Default: none.
  std::vector<SurfacePoint> targets;
  /// false: the field keeps no propagation windows, so it answers vertex_distances() and
  /// target_distances() only (distance_to and path_to throw InvalidInput). Saves the windows'
  /// memory (56 bytes each, about 40 per vertex on a 4k-vertex mesh), the query index and about
  /// half the time. Default: true.
  bool keep_windows = true;
  /// true: the solve stops as soon as the distance field is final on every closed face that
  /// contains a target, instead of covering the whole mesh. Then target_distances() are exact and,
  /// with keep_windows, so are distance_to and path_to for points of those faces; all other
  /// values are upper bounds (lengths of real paths, or +inf where not reached). Requires at
  /// least one target. The fast engine then propagates windows one at a time in distance order,
  /// 2.5-4x slower per window than its default batches: worth it only for targets near the
  /// source. Default: false.
  bool stop_at_targets = false;
  /// Goal-directed pruning, for a solve that needs exact answers in one small place only (a grid
  /// member's end on the opposite boundary): a ball and a distance bound. The fast engine drops
  /// every window whose paths cannot reach the ball within the bound: its own distance (sigma
  /// plus the distance from its image to its interval) plus the straight distance from its
  /// interval to the ball is a lower bound of any continuation, as in A*. Then distance_to and
  /// path_to are exact for every surface point inside the ball whose distance is at most
  /// `bound`; every other value (vertex_distances included) is an upper bound, the length of a
  /// real path, or +inf. With keep_windows, the fast engine also drops, once a solve holds 2M
  /// windows, those no answer inside the ball can use; path_to elsewhere may then throw
  /// InvalidInput("target"). Other engines ignore it (their answers are exact everywhere).
  /// bound = +inf (default): no pruning.
  struct Goal {
    Vec3 center = Vec3::Zero();
    double radius = 0;
    double bound = std::numeric_limits<double>::infinity();
  };
  Goal goal;
};

/// Result of one single-source solve. Holds whatever the method needs to answer distance and
/// path queries to arbitrary surface points afterwards (windows for the exact methods).
class DistanceField {
 public:
  class Impl;
  explicit DistanceField(std::shared_ptr<const Impl> impl);
  ~DistanceField();
  DistanceField(DistanceField&&) noexcept;
  DistanceField& operator=(DistanceField&&) noexcept;

  const SurfacePoint& source() const;
  /// #V exact geodesic distances from the source to every vertex (+inf for vertices in another
  /// connected component).
  const std::vector<double>& vertex_distances() const;
  /// Exact distances to SolveOptions::targets, in that order (empty without targets).
  const std::vector<double>& target_distances() const;
  /// Exact geodesic distance from the source to an arbitrary surface point.
  double distance_to(const SurfacePoint& target) const;
  /// Exact shortest path from the source to `target` as a polyline of surface points, source
  /// first, target last; interior points lie on edges or at vertices (saddle / boundary vertices
  /// the path turns around). Throws InvalidInput for the heat method.
  std::vector<SurfacePoint> path_to(const SurfacePoint& target) const;
  /// Memory the field holds for distance_to and path_to (the exact engine's windows and their
  /// index), bytes; 0 for the other engines.
  std::size_t memory_bytes() const;
  /// Memory the solve held at its largest, bytes: more than memory_bytes() for a goal-pruned
  /// solve of the exact engine, which drops the windows no answer can use as it goes.
  std::size_t peak_memory_bytes() const;

 private:
  std::shared_ptr<const Impl> impl_;
};

class GeodesicSolver {
 public:
  /// Precomputes what every solve on `mesh` shares. The mesh is copied. Throws InvalidInput for
  /// a mesh with non-manifold edges or invalid face indices.
  explicit GeodesicSolver(const TriangleMesh& mesh, GeodesicOptions options = {});
  ~GeodesicSolver();
  GeodesicSolver(GeodesicSolver&&) noexcept;
  GeodesicSolver& operator=(GeodesicSolver&&) noexcept;

  const TriangleMesh& mesh() const;
  GeodesicMethod method() const;

  /// Single-source distance field. Thread-safe (const); cancellable through `progress`.
  DistanceField solve(const SurfacePoint& source, const Progress& progress = {}) const;
  /// Single-source distance field restricted to what `options` asks for (see SolveOptions).
  /// Throws InvalidInput for invalid targets or stop_at_targets without targets.
  DistanceField solve(const SurfacePoint& source, const SolveOptions& options,
                      const Progress& progress = {}) const;
  /// Shorthand: exact distances from `source` to all vertices (a solve without windows).
  std::vector<double> distances(const SurfacePoint& source, const Progress& progress = {}) const;
  /// Shorthand: exact shortest path between two surface points (see DistanceField::path_to).
  /// The solve is goal-pruned (SolveOptions::goal: the point `to`, bounded by the length of a
  /// path along mesh edges, edge_path_bound), so it covers only the part of the mesh a shortest
  /// path could cross: the same path, at a fraction of a complete field's time and memory.
  std::vector<SurfacePoint> shortest_path(const SurfacePoint& from, const SurfacePoint& to,
                                          const Progress& progress = {}) const;
  /// Exact geodesic distance between two surface points, goal-pruned as shortest_path (no
  /// windows kept). +inf if no path joins them.
  double distance(const SurfacePoint& from, const SurfacePoint& to,
                  const Progress& progress = {}) const;

  class Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

/// Length of a polyline of surface points.
double path_length(const TriangleMesh& mesh, const std::vector<SurfacePoint>& path);

/// An upper bound of the geodesic distance between two surface points: the shortest path along
/// mesh edges between corners of their faces, plus the straight segments from the points to those
/// corners inside their faces (all real surface paths); +inf if no such path exists (the points
/// lie on separate pieces). Dijkstra over the edges, O(E log V).
double edge_path_bound(const TriangleMesh& mesh, const SurfacePoint& from, const SurfacePoint& to);

}  // namespace gridshell
