// SPDX-License-Identifier: GPL-3.0-or-later
#include "gridshell/design/coverability.h"

#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseLU>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <future>
#include <limits>
#include <map>
#include <numbers>
#include <optional>
#include <sstream>

#include "gridshell/foundation/errors.h"
#include "gridshell/foundation/parallel.h"
#include "gridshell/mesh/curvature.h"
#include "gridshell/mesh/mesh_topology.h"

namespace gridshell {
namespace {

int interior_peak(const Patch& patch, const std::vector<double>& k) {
  std::vector<char> boundary(patch.mesh.vertex_count(), 0);
  for (const auto& side : patch.sides)
    for (int v : side) boundary[v] = 1;
  int peak = -1;
  for (int v = 0; v < patch.mesh.vertex_count(); ++v)
    if (!boundary[v] && (peak < 0 || k[v] > k[peak])) peak = v;
  return peak;
}

}  // namespace

GapFactor gap_factor(const Patch& patch, const GeodesicSolver& solver, const std::vector<double>& k,
                     const Progress& progress) {
  GapFactor gap;
  gap.peak = interior_peak(patch, k);
  if (gap.peak < 0) return gap;  // no interior vertex: nothing can be uncovered
  const TriangleMesh& mesh = patch.mesh;
  // The solves poll the cancellation flag (a daemon must stop within 200 ms, also on big meshes).
  const std::vector<double> from_peak =
      solver.distances(SurfacePoint::at_vertex(mesh, gap.peak), progress.checker());
  // p1: boundary vertex closest to the peak, and the sides it lies on.
  double best = std::numeric_limits<double>::infinity();
  for (const auto& side : patch.sides)
    for (int v : side)
      if (from_peak[v] < best) {
        best = from_peak[v];
        gap.p1 = v;
      }
  const std::vector<double> from_p1 =
      solver.distances(SurfacePoint::at_vertex(mesh, gap.p1), progress.checker());
  gap.eta = 1.0;
  for (int s = 0; s < 4; ++s) {
    if (std::find(patch.sides[s].begin(), patch.sides[s].end(), gap.p1) == patch.sides[s].end())
      continue;
    const auto& opposite = patch.sides[(s + 2) % 4];
    int q1 = -1;
    double minimum = std::numeric_limits<double>::infinity();
    for (int q : opposite) {
      const double excess = from_peak[gap.p1] + from_peak[q] - from_p1[q];
      if (excess < minimum) {
        minimum = excess;
        q1 = q;
      }
    }
    const double eta = (from_peak[gap.p1] + from_peak[q1]) / from_p1[q1];
    if (gap.q1 < 0 || eta > gap.eta) {
      gap.eta = eta;
      gap.q1 = q1;
    }
  }
  return gap;
}

CoverabilityReport analyze_coverability(const Patch& patch, const GeodesicOptions& geodesic,
                                        const CoverabilityOptions& options,
                                        const Progress& progress) {
  CoverabilityReport report;
  progress.report("coverability", 0.0);
  const std::vector<double> k = gaussian_curvature(patch.mesh);
  const int peak = interior_peak(patch, k);
  report.gaussian_curvature_max_vertex = peak;
  report.gaussian_curvature_max = peak >= 0 ? k[peak] : 0.0;
  report.injectivity_bound = report.gaussian_curvature_max > 0
                                 ? std::numbers::pi / std::sqrt(report.gaussian_curvature_max)
                                 : std::numeric_limits<double>::infinity();
  GeodesicSolver solver(patch.mesh, geodesic);
  // The gap factor (two complete exact solves on the patch, one after the other) does not depend
  // on the copy below: with a second core it runs while the copy is made and measured (0.26 s of
  // a 15k design, 1.1 s at 59k, were spent after it). Stopped early if the rest fails.
  std::atomic<bool> stop{false};
  std::future<GapFactor> gap;
  if (resolve_threads(options.threads) > 1)
    gap = std::async(std::launch::async, [&, inner = progress.checker_stopped_by(&stop)] {
      return gap_factor(patch, solver, k, inner);
    });
  struct StopOnExit {
    std::atomic<bool>& stop;
    ~StopOnExit() { stop = true; }  // before gap's destructor waits for it
  } stop_on_exit{stop};
  // Longest member: members join opposite sides (0-2 and 1-3); sample sources on one side. On a
  // patch above max_vertices, on its simplified copy (about 1e-4 relative off, see
  // distance_map_copy.h): 18 exact solves on the patch cost as much as the rest of the design.
  if (options.max_vertices > 0 && patch.mesh.vertex_count() > options.max_vertices)
    report.map_copy = std::make_shared<const MapCopy>(
        make_map_copy(patch, options.max_vertices, kDefaultMapSamples, progress.checker()));
  const Patch& measured = report.map_copy ? report.map_copy->patch : patch;
  report.longest_member_vertices = measured.mesh.vertex_count();
  std::optional<GeodesicSolver> copy_solver;
  if (report.map_copy) copy_solver.emplace(measured.mesh, geodesic);
  const GeodesicSolver& engine = report.map_copy ? *copy_solver : solver;
  const int samples = std::max(2, options.member_distance_samples);
  std::vector<std::pair<int, int>> jobs;  // (source vertex, side it starts on)
  for (int s = 0; s < 2; ++s) {
    const auto& from = measured.sides[s];
    for (int i = 0; i < samples; ++i)
      jobs.push_back(
          {from[static_cast<size_t>(std::lround(i * (from.size() - 1.0) / (samples - 1)))], s});
  }
  progress.report("coverability: member lengths", 0.1);
  // The sources' solves in parallel, each into its own slot (deterministic for any thread count).
  std::vector<double> longest(jobs.size(), 0.0);
  ParallelOptions parallel;
  parallel.threads = options.threads;
  parallel_for(
      jobs.size(),
      [&](std::size_t job, const Progress& inner) {
        const auto [v, side] = jobs[job];
        const std::vector<double> d =
            engine.distances(SurfacePoint::at_vertex(measured.mesh, v), inner);
        for (int q : measured.sides[side + 2]) longest[job] = std::max(longest[job], d[q]);
      },
      progress, parallel);
  for (double d : longest)
    report.longest_member_distance = std::max(report.longest_member_distance, d);
  report.injectivity_ok = report.longest_member_distance < report.injectivity_bound;
  progress.report("coverability: gap factor", 0.9);
  report.gap = gap.valid() ? gap.get() : gap_factor(patch, solver, k, progress);
  progress.report("coverability", 1.0);
  return report;
}

double laplacian_smoothing_step(TriangleMesh& mesh, const std::vector<char>& fixed, double step) {
  const int n = mesh.vertex_count();
  std::vector<int> free_index(n, -1);
  int free_count = 0;
  for (int v = 0; v < n; ++v)
    if (!fixed[v]) free_index[v] = free_count++;
  if (free_count == 0) return 0.0;
  double edge_sum = 0;
  int edge_count = 0;
  std::vector<Eigen::Triplet<double>> triplets;
  std::vector<double> mass(n, 0.0);
  std::vector<Eigen::Triplet<double>> stiffness;  // L over all vertices
  for (const Face& f : mesh.faces()) {
    const Vec3& a = mesh.vertices()[f[0]];
    const double area = 0.5 * (mesh.vertices()[f[1]] - a).cross(mesh.vertices()[f[2]] - a).norm();
    for (int i = 0; i < 3; ++i) {
      mass[f[i]] += area / 3;
      const int o = f[i], p = f[(i + 1) % 3], q = f[(i + 2) % 3];
      const Vec3 u = mesh.vertices()[p] - mesh.vertices()[o],
                 v = mesh.vertices()[q] - mesh.vertices()[o];
      const double cot = u.dot(v) / std::max(u.cross(v).norm(), 1e-300);
      const double w = 0.5 * cot;  // weight of edge (p,q), opposite vertex o
      stiffness.push_back({p, q, -w});
      stiffness.push_back({q, p, -w});
      stiffness.push_back({p, p, w});
      stiffness.push_back({q, q, w});
      edge_sum += (mesh.vertices()[p] - mesh.vertices()[q]).norm();
      ++edge_count;
    }
  }
  const double mean_edge = edge_sum / edge_count;
  const double h = step * mean_edge * mean_edge;
  Eigen::SparseMatrix<double> L(n, n);
  L.setFromTriplets(stiffness.begin(), stiffness.end());
  // A = M + h L restricted to free vertices; right-hand side M x - h L_fixed x_fixed.
  Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(free_count, 3);
  for (int v = 0; v < n; ++v)
    if (free_index[v] >= 0) {
      triplets.push_back({free_index[v], free_index[v], mass[v]});
      rhs.row(free_index[v]) = mass[v] * mesh.vertices()[v].transpose();
    }
  for (int col = 0; col < L.outerSize(); ++col)
    for (Eigen::SparseMatrix<double>::InnerIterator it(L, col); it; ++it) {
      const int r = static_cast<int>(it.row()), c = static_cast<int>(it.col());
      if (free_index[r] < 0) continue;
      if (free_index[c] >= 0)
        triplets.push_back({free_index[r], free_index[c], h * it.value()});
      else
        rhs.row(free_index[r]) -= h * it.value() * mesh.vertices()[c].transpose();
    }
  Eigen::SparseMatrix<double> A(free_count, free_count);
  A.setFromTriplets(triplets.begin(), triplets.end());
  Eigen::MatrixXd x;
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(A);
  if (ldlt.info() == Eigen::Success) {
    x = ldlt.solve(rhs);
  } else {  // obtuse triangles can make the cotangent matrix indefinite; LU still solves it
    Eigen::SparseLU<Eigen::SparseMatrix<double>> lu(A);
    if (lu.info() != Eigen::Success)
      throw Infeasible("corners", "smoothing: the fairing system is singular");
    x = lu.solve(rhs);
  }
  double moved = 0;
  for (int v = 0; v < n; ++v)
    if (free_index[v] >= 0) {
      const Vec3 p = x.row(free_index[v]).transpose();
      if (!p.allFinite()) throw Infeasible("corners", "smoothing produced non-finite positions");
      moved = std::max(moved, (p - mesh.vertices()[v]).norm());
      mesh.set_vertex(v, p);
    }
  return moved;
}

std::array<double, 4> boundary_geodesic_excess(const Patch& patch, const GeodesicOptions& geodesic,
                                               const Progress& progress, int threads) {
  const GeodesicSolver solver(patch.mesh, geodesic);
  const std::array<double, 4> lengths = side_lengths(patch);
  const double margin = 1e-12 * bounding_box_size(patch.mesh).norm();
  std::array<double, 4> excess{};
  ParallelOptions parallel;
  parallel.threads = threads;
  parallel_for(
      4,
      [&](std::size_t i, const Progress& inner) {
        const SurfacePoint from = SurfacePoint::at_vertex(patch.mesh, patch.corners[i]);
        const SurfacePoint to = SurfacePoint::at_vertex(patch.mesh, patch.corners[(i + 1) % 4]);
        // The side is a real path between its corners, so the shortest geodesic is at most as
        // long: a solve pruned to paths no longer than the side (goal pruning, A* with the
        // straight distance) is exact at the far corner. On a 59k-vertex patch it explores a
        // band around the side instead of the whole patch (2.9 s -> see docs/decisions.md).
        SolveOptions options;
        options.keep_windows = false;
        options.targets = {to};
        options.goal.center = to.position(patch.mesh);
        options.goal.radius = 0;
        options.goal.bound = lengths[i] * (1 + 1e-9) + margin;
        const double shortest =
            std::min(lengths[i], solver.solve(from, options, inner).target_distances().front());
        excess[i] = lengths[i] > 0 ? (lengths[i] - shortest) / lengths[i] : 0.0;
      },
      progress, parallel);
  return excess;
}

namespace {

// The patch cut again out of itself along the shortest geodesics between its corners (on its
// current, smoothed surface). Input vertices are composed, so they still name the input mesh.
Patch recut(const Patch& patch, const GeodesicOptions& geodesic, const Progress& progress) {
  std::array<SurfacePoint, 4> corners;
  for (int i = 0; i < 4; ++i) corners[i] = SurfacePoint::at_vertex(patch.mesh, patch.corners[i]);
  Patch cut = cut_patch(patch.mesh, corners, geodesic, {}, progress);
  for (int& v : cut.input_vertex)
    if (v >= 0) v = patch.input_vertex[v];
  cut.corners_reversed = patch.corners_reversed;
  return cut;
}

std::string excess_text(const std::array<double, 4>& excess) {
  std::ostringstream out;
  out << "the boundary exceeds the shortest geodesics between its corners by up to "
      << *std::max_element(excess.begin(), excess.end()) << " of a side's length";
  return out.str();
}

}  // namespace

SmoothingResult smooth_until_coverable(Patch& patch, const GeodesicOptions& geodesic,
                                       const CoverabilityOptions& options, const Progress& progress,
                                       std::optional<double> eta, bool recut_sides) {
  SmoothingResult result;
  // Positions of the surface the patch was cut from, for the displacement: vertices of the
  // input keep their index map; vertices a cut made are measured from where they were made.
  std::map<int, Vec3> input_of;  // input vertex -> position before smoothing
  for (int v = 0; v < patch.mesh.vertex_count(); ++v)
    if (patch.input_vertex[v] >= 0) input_of[patch.input_vertex[v]] = patch.mesh.vertices()[v];
  auto eta_of = [&]() {
    GeodesicSolver solver(patch.mesh, geodesic);
    return gap_factor(patch, solver, gaussian_curvature(patch.mesh), progress).eta;
  };
  auto fail = [&](const std::string& why) {
    std::ostringstream msg;
    msg << "smoothing: " << why << " after " << result.iterations << " iterations and "
        << result.recuts << " re-cuts (gap factor eta " << result.eta_after << ", eta_max "
        << options.eta_max << "; "
        << excess_text(boundary_geodesic_excess(patch, geodesic, progress, options.threads))
        << "): the patch cannot be covered by shortest geodesics (paper 3.3); choose corners "
           "closer together or a smoother surface";
    throw Infeasible("corners", msg.str());
  };
  // The caller usually measured eta on this very patch already (analyze_coverability): two
  // complete solves less (1.4 s of a 59k-vertex design that needs no smoothing).
  result.eta_before = result.eta_after = eta ? *eta : eta_of();
  bool smoothed = false;
  while (true) {
    // Smooth with the boundary fixed until eta <= eta_max.
    const MeshTopology& topology = patch.mesh.topology();
    std::vector<char> fixed(patch.mesh.vertex_count(), 0);
    for (int v = 0; v < patch.mesh.vertex_count(); ++v) fixed[v] = topology.is_boundary_vertex[v];
    while (result.eta_after > options.eta_max) {
      if (result.iterations >= options.max_smoothing_iterations)
        fail("gap factor eta is still above eta_max");
      progress.report("smoothing", std::min(1.0, static_cast<double>(result.iterations) /
                                                     options.max_smoothing_iterations));
      const double moved = laplacian_smoothing_step(patch.mesh, fixed, options.smoothing_step);
      result.max_displacement = std::max(result.max_displacement, moved);
      smoothed = true;
      ++result.iterations;
      result.eta_after = eta_of();
    }
    if (!smoothed) break;  // the surface is as it was cut: its sides are exact
    // The surface moved under the fixed boundary: is every side still a shortest geodesic?
    const std::array<double, 4> excess =
        boundary_geodesic_excess(patch, geodesic, progress, options.threads);
    if (*std::max_element(excess.begin(), excess.end()) <= kBoundaryGeodesicTolerance) break;
    if (!recut_sides)
      fail(
          "a side shared with a neighbouring patch is no longer a shortest geodesic of the "
          "smoothed patch, and a shared side is not re-cut");
    if (result.recuts >= kMaxRecuts) fail("the boundary is still not geodesic");
    progress.report("smoothing: re-cut along the boundary geodesics", 0.5);
    patch = recut(patch, geodesic, progress);
    ++result.recuts;
    smoothed = false;  // the re-cut keeps the surface: its new sides are exact on it
    result.eta_after = eta_of();
    if (result.eta_after <= options.eta_max) break;
  }
  for (int v = 0; v < patch.mesh.vertex_count(); ++v) {
    const auto it = input_of.find(patch.input_vertex[v]);
    if (patch.input_vertex[v] >= 0 && it != input_of.end())
      result.max_displacement =
          std::max(result.max_displacement, (patch.mesh.vertices()[v] - it->second).norm());
  }
  return result;
}

}  // namespace gridshell
