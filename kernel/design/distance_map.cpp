// SPDX-License-Identifier: GPL-3.0-or-later
// Distance maps between opposite patch boundaries (paper Section 4.2).
//
// For each family, R source points at u1_i = i/(R-1) on the first boundary get one exact
// single-source solve each for the R target points u2_j on the second boundary. The solves ask
// only for those targets and keep no windows (SolveOptions), which gives the same exact distances
// as querying a complete field and lets the engine propagate in batches (geodesic_fast.cpp, 2.5-4x
// faster than its window-ordered propagation). They do not stop at the targets: the targets lie on
// the opposite boundary, beyond which little of the patch is left (no vertex of the examples'
// patches is farther from a row's source than that row's farthest target), and only the ordered
// propagation can stop early. The 2R solves (both
// families) are independent: worker threads take them from an atomic counter and write to
// distinct matrix rows, so the result does not depend on the number of threads or on scheduling.
//
// Threads and errors: the calling thread only reports progress ("distance maps", fraction) and
// waits. Workers check cancellation before every solve and (through a wrapper Progress) at the
// solver's own progress points. The first exception of any worker (including Cancelled) stops
// the others from taking new sources; all threads are joined and that exception is rethrown on
// the calling thread. If reporting throws on the calling thread (cancellation, or a throwing
// callback), the workers are stopped and joined the same way before it propagates.
#include "gridshell/design/distance_map.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <sstream>
#include <string>

#include "gridshell/foundation/errors.h"
#include "gridshell/foundation/parallel.h"

namespace gridshell {
namespace {

constexpr const char* kStage = "distance maps";

void check_patch(const Patch& patch) {
  for (int s = 0; s < 4; ++s) {
    if (patch.sides[s].size() < 2) {
      throw InvalidInput("patch.sides[" + std::to_string(s) + "]", "fewer than two vertices");
    }
  }
}

}  // namespace

std::vector<int> family_boundary(const Patch& patch, Family family, int end) {
  if (end != 0 && end != 1) {
    throw InvalidInput("end", "must be 0 or 1, got " + std::to_string(end));
  }
  // G: side 0 (c0 -> c1) and side 2 reversed (c3 -> c2); H: side 1 (c1 -> c2) and side 3
  // reversed (c0 -> c3).
  const int side = (family == Family::G ? 0 : 1) + 2 * end;
  std::vector<int> chain = patch.sides[side];
  if (end == 1) std::reverse(chain.begin(), chain.end());
  return chain;
}

double chain_length(const TriangleMesh& mesh, const std::vector<int>& chain) {
  double length = 0;
  for (size_t k = 0; k + 1 < chain.size(); ++k) {
    length += (mesh.vertices().at(chain[k + 1]) - mesh.vertices().at(chain[k])).norm();
  }
  return length;
}

SurfacePoint point_on_chain(const TriangleMesh& mesh, const std::vector<int>& chain, double t) {
  if (!(t >= 0.0 && t <= 1.0)) {
    std::ostringstream message;
    message << t << " is outside [0, 1]";
    throw InvalidInput("t", message.str());
  }
  if (chain.empty()) throw InvalidInput("chain", "empty vertex chain");
  for (int v : chain) {
    if (v < 0 || v >= mesh.vertex_count()) {
      throw InvalidInput("chain", "vertex " + std::to_string(v) + " is out of range");
    }
  }
  if (t == 0.0 || chain.size() == 1) return SurfacePoint::at_vertex(mesh, chain.front());
  if (t == 1.0) return SurfacePoint::at_vertex(mesh, chain.back());

  // Cumulative arc length; the segment holding arc length t * L, then the local parameter.
  std::vector<double> cumulative(chain.size(), 0.0);
  for (size_t k = 0; k + 1 < chain.size(); ++k) {
    cumulative[k + 1] =
        cumulative[k] + (mesh.vertices()[chain[k + 1]] - mesh.vertices()[chain[k]]).norm();
  }
  const double total = cumulative.back();
  if (!(total > 0)) return SurfacePoint::at_vertex(mesh, chain.front());
  const double target = t * total;
  // First k with cumulative[k + 1] >= target (segments of zero length are skipped naturally).
  size_t k = static_cast<size_t>(
      std::lower_bound(cumulative.begin() + 1, cumulative.end(), target) - cumulative.begin() - 1);
  k = std::min(k, chain.size() - 2);
  const double segment = cumulative[k + 1] - cumulative[k];
  double local = segment > 0 ? (target - cumulative[k]) / segment : 0.0;
  local = std::clamp(local, 0.0, 1.0);
  if (local == 0.0) return SurfacePoint::at_vertex(mesh, chain[k]);
  if (local == 1.0) return SurfacePoint::at_vertex(mesh, chain[k + 1]);
  return SurfacePoint::on_edge(mesh, chain[k], chain[k + 1], local);
}

int distance_map_resolution(const Patch& patch, const DistanceMapOptions& options) {
  if (options.resolution == 1 || options.resolution < 0) {
    throw InvalidInput("options.resolution", "must be 0 (adaptive) or at least 2, got " +
                                                 std::to_string(options.resolution));
  }
  if (options.resolution > 0) return options.resolution;
  size_t edges = 0;
  for (const auto& side : patch.sides) edges = std::max(edges, side.empty() ? 0 : side.size() - 1);
  return static_cast<int>(std::clamp<size_t>(edges, 32, 200));
}

DistanceMaps compute_distance_maps(const Patch& patch, const GeodesicSolver& solver,
                                   const DistanceMapOptions& options, const Progress& progress,
                                   std::shared_ptr<const MapCopy> copy) {
  if (options.threads < 0) {
    throw InvalidInput("options.threads", "must be >= 0 (0 = hardware concurrency), got " +
                                              std::to_string(options.threads));
  }
  if (options.max_vertices < 0) {
    throw InvalidInput("options.max_vertices", "must be >= 0 (0 = exact maps), got " +
                                                   std::to_string(options.max_vertices));
  }
  check_patch(patch);
  const int R = distance_map_resolution(patch, options);
  progress.report(kStage, 0.0);

  // Above max_vertices the maps are computed on a simplified copy whose boundary holds the R
  // sample points of each chain as vertices (distance_map_copy.h); a copy made for the same
  // size and samples (the coverability's, on the same patch) is reused.
  const bool on_copy = options.max_vertices > 0 && patch.mesh.vertex_count() > options.max_vertices;
  if (on_copy && !(copy && copy->samples == R && copy->max_vertices == options.max_vertices &&
                   copy->patch_vertices == patch.mesh.vertex_count()))
    copy = std::make_shared<const MapCopy>(
        make_map_copy(patch, options.max_vertices, R, progress.checker()));
  std::optional<GeodesicSolver> copy_solver;
  if (on_copy) copy_solver.emplace(copy->patch.mesh, GeodesicOptions{solver.method()});
  const TriangleMesh& mesh = on_copy ? copy->patch.mesh : patch.mesh;
  const GeodesicSolver& engine = on_copy ? *copy_solver : solver;

  // Sources and targets of both families, computed up front on the calling thread.
  std::array<std::vector<SurfacePoint>, 2> sources;
  std::array<SolveOptions, 2> targets;
  for (int f = 0; f < 2; ++f) {
    const Family family = static_cast<Family>(f);
    const std::vector<int> first = family_boundary(patch, family, 0);
    const std::vector<int> second = family_boundary(patch, family, 1);
    sources[f].resize(R);
    targets[f].targets.resize(R);
    targets[f].keep_windows = false;
    for (int i = 0; i < R; ++i) {
      const double t = static_cast<double>(i) / (R - 1);
      if (on_copy) {  // the same points, as vertices of the copy
        sources[f][i] = SurfacePoint::at_vertex(mesh, copy->chains[f][i]);
        targets[f].targets[i] = SurfacePoint::at_vertex(mesh, copy->chains[2 + f][i]);
      } else {
        sources[f][i] = point_on_chain(mesh, first, t);
        targets[f].targets[i] = point_on_chain(mesh, second, t);
      }
    }
  }

  DistanceMaps maps;
  maps.g.family = Family::G;
  maps.h.family = Family::H;
  maps.g.distances.resize(R, R);
  maps.h.distances.resize(R, R);
  maps.mesh_vertices = mesh.vertex_count();
  std::array<Eigen::MatrixXd*, 2> out{&maps.g.distances, &maps.h.distances};

  // The 2R single-source solves in parallel, each into its own row (deterministic for any thread
  // count); the solver polls the caller's cancellation flag, so a cancel stops within ms.
  ParallelOptions parallel;
  parallel.threads = options.threads;
  parallel.stage = kStage;
  parallel_for(
      2 * static_cast<std::size_t>(R),
      [&](std::size_t task, const Progress& inner) {
        const int f = static_cast<int>(task) / R, i = static_cast<int>(task) % R;
        const DistanceField field = engine.solve(sources[f][i], targets[f], inner);
        const std::vector<double>& row = field.target_distances();
        for (int j = 0; j < R; ++j) (*out[f])(i, j) = row[j];
      },
      progress, parallel);

  if (on_copy) {
    // The corner entries are the side lengths, exactly on the patch (its sides are its shortest
    // geodesics); the cladding functions pass through them and demand agreement to 1e-9.
    // G: (0,0) = d(c0, c3) = side 3, (R-1,R-1) = d(c1, c2) = side 1; H: (0,0) = d(c1, c0) =
    // side 0, (R-1,R-1) = d(c2, c3) = side 2.
    const std::array<double, 4> sides = side_lengths(patch);
    const std::array<std::array<int, 2>, 2> corner_sides{{{3, 1}, {0, 2}}};
    for (int f = 0; f < 2; ++f)
      for (int end = 0; end < 2; ++end) {
        const int k = end * (R - 1);
        const double exact = sides[corner_sides[f][end]];
        double& entry = (*out[f])(k, k);
        if (exact > 0)
          maps.corner_error = std::max(maps.corner_error, std::abs(entry - exact) / exact);
        entry = exact;
      }
    maps.copy = std::move(copy);
  }
  return maps;
}

}  // namespace gridshell
