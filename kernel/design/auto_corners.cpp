// SPDX-License-Identifier: GPL-3.0-or-later
// Automatic corners: candidates and the bounded search for the largest acceptable patch
// (auto_corners.h; issue 18 item 2).
#include "gridshell/design/auto_corners.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iomanip>
#include <numbers>
#include <optional>
#include <queue>
#include <set>
#include <sstream>

#include "gridshell/design/distance_map_copy.h"
#include "gridshell/design/target_patch.h"
#include "gridshell/foundation/errors.h"
#include "gridshell/foundation/parallel.h"
#include "gridshell/mesh/curvature.h"
#include "gridshell/mesh/mesh_topology.h"
#include "gridshell/mesh/normals.h"

namespace gridshell {
namespace {

constexpr double kPi = std::numbers::pi;
/// A boundary vertex turning less than this is no corner candidate.
constexpr double kMinTurning = 10 * kPi / 180;
/// Corner candidates per boundary loop (local turning maxima, sharpest first).
constexpr int kPeaksPerLoop = 7;

double degrees(double radians) { return radians * 180 / kPi; }

std::string fixed(double value, int digits) {
  std::ostringstream out;
  out << std::fixed << std::setprecision(digits) << value;
  return out.str();
}

}  // namespace

std::vector<std::array<int, 4>> boundary_corner_candidates(const TriangleMesh& mesh) {
  const MeshTopology& topology = mesh.topology();
  std::vector<std::array<int, 4>> out;
  if (topology.boundary_loops.empty()) return out;
  const std::vector<double> sums = vertex_angle_sums(mesh);
  auto add = [&](const std::array<int, 4>& q) {
    if (std::find(out.begin(), out.end(), q) == out.end()) out.push_back(q);
  };
  // The former rule first: the four sharpest vertices of the longest loop, in loop order.
  {
    const auto longest =
        std::max_element(topology.boundary_loops.begin(), topology.boundary_loops.end(),
                         [](const auto& a, const auto& b) { return a.size() < b.size(); });
    if (longest->size() >= 4) add(auto_corners(mesh));
  }
  struct Scored {
    double turning;
    std::array<int, 4> corners;
  };
  std::vector<Scored> scored;
  for (const std::vector<int>& loop : topology.boundary_loops) {
    const int n = static_cast<int>(loop.size());
    if (n < 4) continue;
    std::vector<double> turning(n);
    for (int i = 0; i < n; ++i) turning[i] = kPi - sums[loop[i]];
    // Local maxima over a window of a few vertices (strict against earlier ties: one per peak).
    const int window = std::max(1, n / 40);
    std::vector<int> peaks;
    for (int i = 0; i < n; ++i) {
      if (turning[i] < kMinTurning) continue;
      bool peak = true;
      for (int k = -window; k <= window && peak; ++k) {
        if (k == 0) continue;
        const int j = ((i + k) % n + n) % n;
        if (turning[j] > turning[i] || (turning[j] == turning[i] && j < i)) peak = false;
      }
      if (peak) peaks.push_back(i);
    }
    std::stable_sort(peaks.begin(), peaks.end(),
                     [&](int a, int b) { return turning[a] > turning[b]; });
    if (peaks.size() > static_cast<size_t>(kPeaksPerLoop)) peaks.resize(kPeaksPerLoop);
    std::sort(peaks.begin(), peaks.end());  // loop order
    const int m = static_cast<int>(peaks.size());
    for (int a = 0; a < m; ++a)
      for (int b = a + 1; b < m; ++b)
        for (int c = b + 1; c < m; ++c)
          for (int d = c + 1; d < m; ++d) {
            const double t =
                turning[peaks[a]] + turning[peaks[b]] + turning[peaks[c]] + turning[peaks[d]];
            scored.push_back({t, {loop[peaks[a]], loop[peaks[b]], loop[peaks[c]], loop[peaks[d]]}});
          }
  }
  std::stable_sort(scored.begin(), scored.end(),
                   [](const Scored& a, const Scored& b) { return a.turning > b.turning; });
  for (const Scored& s : scored) add(s.corners);
  return out;
}

std::vector<std::array<int, 4>> inner_corner_candidates(const TriangleMesh& mesh) {
  const MeshTopology& topology = mesh.topology();
  const int n = mesh.vertex_count();
  const std::vector<Vec3>& x = mesh.vertices();
  // The innermost vertex: farthest from the boundary along edges (Dijkstra from every boundary
  // vertex). On a closed mesh: the vertex nearest the centroid of the vertices.
  std::vector<double> depth(n, std::numeric_limits<double>::infinity());
  using Entry = std::pair<double, int>;
  std::priority_queue<Entry, std::vector<Entry>, std::greater<>> queue;
  for (int v = 0; v < n; ++v)
    if (topology.is_boundary_vertex[v]) {
      depth[v] = 0;
      queue.push({0.0, v});
    }
  std::vector<std::vector<int>> neighbours(n);
  for (const Face& f : mesh.faces())
    for (int i = 0; i < 3; ++i) neighbours[f[i]].push_back(f[(i + 1) % 3]);
  while (!queue.empty()) {
    const auto [d, v] = queue.top();
    queue.pop();
    if (d > depth[v]) continue;
    for (int w : neighbours[v]) {
      const double e = d + (x[w] - x[v]).norm();
      if (e < depth[w]) {
        depth[w] = e;
        queue.push({e, w});
      }
    }
  }
  int centre = -1;
  if (!topology.boundary_loops.empty()) {
    for (int v = 0; v < n; ++v)
      if (!topology.vertex_faces[v].empty() && std::isfinite(depth[v]) &&
          (centre < 0 || depth[v] > depth[centre]))
        centre = v;
  } else {
    Vec3 mean = Vec3::Zero();
    int used = 0;
    for (int v = 0; v < n; ++v)
      if (!topology.vertex_faces[v].empty()) mean += x[v], ++used;
    mean /= std::max(used, 1);
    for (int v = 0; v < n; ++v)
      if (!topology.vertex_faces[v].empty() &&
          (centre < 0 || (x[v] - mean).squaredNorm() < (x[centre] - mean).squaredNorm()))
        centre = v;
  }
  std::vector<std::array<int, 4>> out;
  if (centre < 0) return out;
  // Exact distances from the centre; polar angles from the projection onto its tangent plane.
  const GeodesicSolver solver(mesh);
  const std::vector<double> d = solver.distances(SurfacePoint::at_vertex(mesh, centre));
  const Vec3 normal = vertex_normals(mesh)[centre];
  // First axis: towards the nearest boundary vertex (a patch aligned with the boundary), else
  // along the first neighbour.
  Vec3 axis = Vec3::Zero();
  {
    int nearest = -1;
    for (int v = 0; v < n; ++v)
      if (topology.is_boundary_vertex[v] && std::isfinite(d[v]) &&
          (nearest < 0 || d[v] < d[nearest]))
        nearest = v;
    const int toward = nearest >= 0 ? nearest : neighbours[centre].front();
    axis = x[toward] - x[centre];
    axis -= axis.dot(normal) * normal;
    if (axis.norm() == 0) axis = normal.unitOrthogonal();
    axis.normalize();
  }
  const Vec3 axis2 = normal.cross(axis);
  std::vector<double> angle(n, 0.0);
  double reach = 0;  // the largest finite distance from the centre
  for (int v = 0; v < n; ++v) {
    const Vec3 p = x[v] - x[centre];
    angle[v] = std::atan2(p.dot(axis2), p.dot(axis));
    if (std::isfinite(d[v])) reach = std::max(reach, d[v]);
  }
  const bool closed = topology.boundary_loops.empty();
  // The vertex at about distance r in direction theta: within 12 degrees of theta, the one whose
  // distance is nearest r; -1 if none.
  auto vertex_at = [&](double r, double theta) {
    int best = -1;
    double best_error = std::numeric_limits<double>::infinity();
    for (int v = 0; v < n; ++v) {
      if (v == centre || !std::isfinite(d[v]) || topology.vertex_faces[v].empty()) continue;
      double diff = std::remainder(angle[v] - theta, 2 * kPi);
      if (std::abs(diff) > 12 * kPi / 180) continue;
      const double error = std::abs(d[v] - r) + 0.05 * r * std::abs(diff);
      if (error < best_error) best_error = error, best = v;
    }
    return best;
  };
  // How far the surface reaches from the centre in direction theta (to its boundary).
  auto extent = [&](double theta) {
    double e = 0;
    for (int v = 0; v < n; ++v) {
      if (!std::isfinite(d[v])) continue;
      if (std::abs(std::remainder(angle[v] - theta, 2 * kPi)) <= 12 * kPi / 180)
        e = std::max(e, d[v]);
    }
    return closed ? std::min(e, 0.5 * reach) : e;
  };
  struct Shape {
    double rotation, aspect;
  };
  const Shape shapes[] = {{0, 1}, {kPi / 4, 1}, {0, 2}, {kPi / 2, 2}};
  const double scales[] = {0.9, 0.75, 0.6, 0.45, 0.3};
  for (double scale : scales)
    for (const Shape& shape : shapes) {
      const double half = std::atan(1 / shape.aspect);  // corner direction off the long axis
      const std::array<double, 4> theta{shape.rotation - half, shape.rotation + half,
                                        shape.rotation + kPi - half, shape.rotation + kPi + half};
      double r = std::numeric_limits<double>::infinity();
      for (double t : theta) r = std::min(r, extent(t));
      r *= scale;
      if (!(r > 0)) continue;
      std::array<int, 4> q{};
      bool ok = true;
      for (int k = 0; k < 4 && ok; ++k) {
        q[k] = vertex_at(r, theta[k]);
        ok = q[k] >= 0;
      }
      std::set<int> distinct(q.begin(), q.end());
      if (ok && distinct.size() == 4 && std::find(out.begin(), out.end(), q) == out.end())
        out.push_back(q);
    }
  return out;
}

TargetPatch search_auto_corners(const TriangleMesh& mesh, const TargetPatchOptions& options,
                                const Progress& progress) {
  const auto start = std::chrono::steady_clock::now();
  const AutoCornerOptions& o = options.auto_corners;
  AutoCornerReport report;
  report.min_corner_angle = o.min_corner_angle;
  report.max_corner_angle = o.max_corner_angle;
  report.rule =
      "the largest patch (area of the cut patch) among the candidates whose corner angles lie "
      "in [" +
      fixed(degrees(o.min_corner_angle), 1) + ", " + fixed(degrees(o.max_corner_angle), 1) +
      "] degrees, whose gap factor after smoothing is at most eta_max with exact boundary "
      "geodesics, and that has a feasible planar angle range; boundary turning points first, "
      "inner points only if no boundary candidate passes";
  TargetPatch chosen;
  bool found = false;

  struct Cut {
    int candidate;
    std::optional<Patch> patch;  // empty: cut on the simplified copy only
    std::array<SurfacePoint, 4> corners;
    double seconds;  // the cut's
  };
  // On a large mesh the candidates are cut and ranked on a simplified copy that keeps their
  // corner vertices; each candidate evaluated is then cut again on the input. A corner angle
  // is only rejected on the copy if it is outside the range by more than this.
  constexpr double kCoarseAngleMargin = 2 * kPi / 180;
  auto run_kind = [&](const std::vector<std::array<int, 4>>& quads, const char* kind) {
    // The cuts are independent (each its own exact geodesics on the mesh or its copy): they run on
    // the maps' threads, each into its own slot, and are reported in candidate order, so the
    // outcome does not depend on the thread count. pillow_1 subdivided twice (21k vertices, 21
    // cuts), 2 cores: the search 5.97 -> 3.50 s, the design 6.80 -> 4.02 s wall (medians of 3),
    // peak memory 148 -> 252 MiB (two cuts in flight).
    const size_t count =
        std::min(quads.size(), static_cast<size_t>(std::max(0, o.max_cuts - report.cuts)));
    std::optional<SimplifiedMesh> copy;
    if (count > 1 && mesh.vertex_count() > o.simplify_above) {
      std::vector<int> keep;
      for (size_t k = 0; k < count; ++k) keep.insert(keep.end(), quads[k].begin(), quads[k].end());
      try {
        copy = simplify_mesh(mesh, o.simplify_to, keep, progress);
        report.simplified_vertices = copy->mesh.vertex_count();
      } catch (const InvalidInput&) {
        // A surface CGAL cannot simplify is searched on itself, as a small one is.
      }
    }
    const TriangleMesh& cut_mesh = copy ? copy->mesh : mesh;
    struct Slot {
      AutoCornerCandidate candidate;
      std::optional<Cut> cut;
    };
    std::vector<Slot> slots(count);
    const int first = static_cast<int>(report.candidates.size());
    parallel_for(
        count,
        [&](std::size_t k, const Progress& inner) {
          AutoCornerCandidate& c = slots[k].candidate;
          c.vertices = quads[k];
          c.kind = kind;
          std::array<SurfacePoint, 4> corners, cut_corners;
          for (int i = 0; i < 4; ++i) {
            corners[i] = SurfacePoint::at_vertex(mesh, quads[k][i]);
            cut_corners[i] =
                copy ? SurfacePoint::at_vertex(cut_mesh, copy->of_input[quads[k][i]]) : corners[i];
          }
          const auto cut_start = std::chrono::steady_clock::now();
          try {
            Patch patch =
                cut_patch(cut_mesh, cut_corners, options.geodesic, options.cut, inner.checker());
            (copy ? c.coarse_area : c.area) = surface_area(patch.mesh);
            c.corner_angles = corner_angles(patch);
            const auto [lo, hi] =
                std::minmax_element(c.corner_angles.begin(), c.corner_angles.end());
            const double margin = copy ? kCoarseAngleMargin : 0;
            if (*lo < o.min_corner_angle - margin || *hi > o.max_corner_angle + margin) {
              c.reason = "corner angles " + fixed(degrees(*lo), 1) + ".." + fixed(degrees(*hi), 1) +
                         " degrees outside the range" + (copy ? " (on the simplified copy)" : "");
            } else {
              c.reason = "cut; not evaluated";
              std::optional<Patch> exact;
              if (!copy) exact = std::move(patch);
              slots[k].cut =
                  Cut{first + static_cast<int>(k), std::move(exact), corners,
                      std::chrono::duration<double>(std::chrono::steady_clock::now() - cut_start)
                          .count()};
            }
          } catch (const Cancelled&) {
            throw;
          } catch (const Error& e) {
            c.reason = "cut: " + e.message();
          }
        },
        progress, {o.maps.threads, "patch: automatic corners", 0, 0.5});
    std::vector<Cut> cuts;
    for (Slot& slot : slots) {
      ++report.cuts;
      report.candidates.push_back(std::move(slot.candidate));
      if (slot.cut) cuts.push_back(std::move(*slot.cut));
    }
    const auto ranked_area = [&](const Cut& cut) {
      const AutoCornerCandidate& c = report.candidates[cut.candidate];
      return copy ? c.coarse_area : c.area;
    };
    std::stable_sort(cuts.begin(), cuts.end(),
                     [&](const Cut& a, const Cut& b) { return ranked_area(a) > ranked_area(b); });
    for (Cut& cut : cuts) {
      AutoCornerCandidate& c = report.candidates[cut.candidate];
      if (report.evaluations >= o.max_evaluations) {
        c.reason = "cut; not evaluated (evaluation budget used)";
        continue;
      }
      if (!cut.patch) {
        // Cut again on the input: the exact patch, its area and corner angles.
        progress.check();
        const auto cut_start = std::chrono::steady_clock::now();
        try {
          cut.patch =
              cut_patch(mesh, cut.corners, options.geodesic, options.cut, progress.checker());
        } catch (const Cancelled&) {
          throw;
        } catch (const Error& e) {
          c.reason = "cut on the input: " + e.message();
          continue;
        }
        cut.seconds =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - cut_start).count();
        c.area = surface_area(cut.patch->mesh);
        c.corner_angles = corner_angles(*cut.patch);
        if (c.area > 0)
          report.area_error =
              std::max(report.area_error, std::abs(c.coarse_area - c.area) / c.area);
        const auto [lo, hi] = std::minmax_element(c.corner_angles.begin(), c.corner_angles.end());
        if (*lo < o.min_corner_angle || *hi > o.max_corner_angle) {
          c.reason = "corner angles " + fixed(degrees(*lo), 1) + ".." + fixed(degrees(*hi), 1) +
                     " degrees outside the range";
          continue;
        }
      }
      progress.check();
      progress.report("patch: automatic corners",
                      0.5 + 0.5 * report.evaluations / std::max(1, o.max_evaluations));
      ++report.evaluations;
      try {
        TargetPatch target =
            target_patch_from_cut(std::move(*cut.patch), cut.corners, options, progress.checker());
        c.eta = target.smoothing.eta_after;
        c.corner_angles = target.corner_angles;
        const auto [lo, hi] = std::minmax_element(c.corner_angles.begin(), c.corner_angles.end());
        if (*lo < o.min_corner_angle || *hi > o.max_corner_angle) {
          c.reason = "corner angles after smoothing " + fixed(degrees(*lo), 1) + ".." +
                     fixed(degrees(*hi), 1) + " degrees outside the range";
          continue;
        }
        if (c.eta > options.coverability.eta_max) {
          c.reason = "gap factor eta " + fixed(c.eta, 5) + " > eta_max";
          continue;
        }
        const double excess =
            *std::max_element(target.boundary_excess.begin(), target.boundary_excess.end());
        if (excess > kBoundaryGeodesicTolerance) {
          c.reason =
              "a side is not a shortest geodesic of the patch (excess " + fixed(excess, 12) + ")";
          continue;
        }
        // The maps are the design's own if this candidate wins: their progress is the
        // design's "distance maps" stage (clients wait for it, e.g. to offer Cancel).
        const GeodesicSolver solver(target.patch.mesh, options.geodesic);
        auto maps = std::make_shared<DistanceMaps>(
            compute_distance_maps(target.patch, solver, o.maps, progress));
        const AlphaRange range =
            feasible_alpha_range(*maps, side_lengths(target.patch), o.cladding, progress.checker());
        c.alpha_range = std::array<double, 2>{range.min, range.max};
        c.accepted = true;
        c.reason = "accepted: the largest candidate that passes every criterion (area " +
                   fixed(c.area, 4) + ", planar angle range " + fixed(degrees(range.min), 2) +
                   ".." + fixed(degrees(range.max), 2) + " degrees)";
        target.maps = std::move(maps);
        target.maps_options = o.maps;
        target.stage_seconds["cut"] = cut.seconds;
        chosen = std::move(target);
        report.chosen = cut.candidate;
        found = true;
        return;
      } catch (const Cancelled&) {
        throw;
      } catch (const Error& e) {
        c.reason = e.message();
      }
    }
  };
  run_kind(boundary_corner_candidates(mesh), "boundary");
  if (!found) run_kind(inner_corner_candidates(mesh), "inner");
  report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (!found) {
    std::ostringstream msg;
    msg << "auto: none of " << report.candidates.size() << " candidate corner quadruples ("
        << report.cuts << " cut, " << report.evaluations << " evaluated) gives an acceptable patch";
    int shown = 0;
    for (const AutoCornerCandidate& c : report.candidates) {
      if (shown == 3) break;
      msg << (shown == 0 ? ": " : "; ") << c.kind << " " << c.vertices[0] << "," << c.vertices[1]
          << "," << c.vertices[2] << "," << c.vertices[3] << ": " << c.reason;
      ++shown;
    }
    msg << " (name the corners instead)";
    throw Infeasible("corners", msg.str());
  }
  chosen.auto_corners = std::move(report);
  chosen.stage_seconds["auto_corners"] = chosen.auto_corners->seconds;
  progress.report("patch: automatic corners", 1.0);
  return chosen;
}

}  // namespace gridshell
