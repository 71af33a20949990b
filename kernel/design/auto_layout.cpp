// SPDX-License-Identifier: GPL-3.0-or-later
// Automatic layouts of a disk (see gridshell/design/layout.h, docs/multi-patch.md): the surface
// mapped onto a square by CGAL's mean value coordinates, a grid of patches on the square.
#define CGAL_EIGEN3_ENABLED 1  // CGAL's parameterization solves with Eigen
#include <CGAL/Simple_cartesian.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/Surface_mesh_parameterization/Error_code.h>
#include <CGAL/Surface_mesh_parameterization/Mean_value_coordinates_parameterizer_3.h>
#include <CGAL/Surface_mesh_parameterization/Square_border_parameterizer_3.h>
#include <CGAL/Surface_mesh_parameterization/parameterize.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <numbers>
#include <numeric>
#include <stdexcept>

#include "gridshell/design/layout.h"
#include "gridshell/foundation/errors.h"

namespace gridshell {
namespace {

using Kernel = CGAL::Simple_cartesian<double>;
using CgalMesh = CGAL::Surface_mesh<Kernel::Point_3>;
namespace SMP = CGAL::Surface_mesh_parameterization;

constexpr double kPi = std::numbers::pi;

/// Checks that the mesh is a disk: one piece, one boundary loop, Euler characteristic 1.
void check_disk(const TriangleMesh& mesh) {
  const auto& loops = mesh.topology().boundary_loops;
  std::vector<char> used(mesh.vertex_count(), 0);
  for (const Face& f : mesh.faces())
    for (int v : f) used[v] = 1;
  const long vertices = std::count(used.begin(), used.end(), 1);
  long boundary_edges = 0;
  for (const auto& loop : loops) boundary_edges += static_cast<long>(loop.size());
  const long faces = mesh.face_count();
  const long edges = (3 * faces + boundary_edges) / 2;
  const long euler = vertices - edges + faces;
  if (loops.empty())
    throw Infeasible(
        "layout",
        "the surface is closed: automatic layouts cover a surface with one boundary "
        "and no holes so far; cut it open or give a layout file (docs/multi-patch.md)");
  if (loops.size() > 1 || euler != 1)
    throw Infeasible("layout", "the surface has " + std::to_string(loops.size()) +
                                   " boundary loops and Euler characteristic " +
                                   std::to_string(euler) +
                                   " (a disk has 1 and 1): automatic layouts cover a surface with "
                                   "one boundary and no holes so far; give a layout file "
                                   "(docs/multi-patch.md)");
}

/// How much the boundary turns at each vertex of `loop`, seen in plan: on the plane of the
/// surface's two largest principal directions (where a roof's or a facade's corners are).
std::vector<double> turning(const TriangleMesh& mesh, const std::vector<int>& loop) {
  Vec3 centre = Vec3::Zero();
  for (const Vec3& p : mesh.vertices()) centre += p;
  centre /= std::max(1, mesh.vertex_count());
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  for (const Vec3& p : mesh.vertices()) covariance += (p - centre) * (p - centre).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(covariance);
  const Vec3 ex = eigen.eigenvectors().col(2), ey = eigen.eigenvectors().col(1);
  const int n = static_cast<int>(loop.size());
  std::vector<Vec2> plan;
  for (int v : loop) {
    const Vec3 d = mesh.vertices()[v] - centre;
    plan.emplace_back(d.dot(ex), d.dot(ey));
  }
  // Signed so that the loop turns by +2 pi in all (either orientation of the plan).
  std::vector<double> out(n, 0.0);
  double total = 0;
  for (int i = 0; i < n; ++i) {
    const Vec2 a = plan[i] - plan[(i + n - 1) % n], b = plan[(i + 1) % n] - plan[i];
    out[i] = std::atan2(a.x() * b.y() - a.y() * b.x(), a.dot(b));
    total += out[i];
  }
  if (total < 0)
    for (double& t : out) t = -t;
  return out;
}

/// The four boundary corners: positions in `loop`.
std::array<int, 4> square_corners(const TriangleMesh& mesh, const std::vector<int>& loop) {
  const std::vector<double> vertex_turn = turning(mesh, loop);
  const int n = static_cast<int>(loop.size());
  std::vector<double> arc(n + 1, 0.0);  // arc length from loop[0]
  for (int i = 0; i < n; ++i)
    arc[i + 1] = arc[i] + (mesh.vertices()[loop[(i + 1) % n]] - mesh.vertices()[loop[i]]).norm();
  const double perimeter = arc[n];
  // A rounded corner turns over several vertices: each vertex's turn is the boundary's turn
  // within a 32nd of the perimeter either side of it.
  const double reach = perimeter / 32;
  std::vector<double> turn(n, 0.0);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      double along = std::abs(arc[j] - arc[i]);
      along = std::min(along, perimeter - along);
      if (along <= reach) turn[i] += vertex_turn[j];
    }
  // A corner found by its window is then the vertex that turns most within that window: the
  // sharp corner where there is one.
  const auto sharpest_near = [&](int c) {
    int best = c;
    for (int j = 0; j < n; ++j) {
      double along = std::abs(arc[j] - arc[c]);
      along = std::min(along, perimeter - along);
      if (along <= reach && vertex_turn[j] > vertex_turn[best]) best = j;
    }
    return best;
  };
  const int start =
      sharpest_near(static_cast<int>(std::max_element(turn.begin(), turn.end()) - turn.begin()));
  std::array<int, 4> corners{start, 0, 0, 0};
  for (int q = 1; q < 4; ++q) {
    const double ideal = q * perimeter / 4;
    int nearest = -1, sharpest = -1;
    double nearest_offset = 1e300;
    for (int i = 0; i < n; ++i) {
      const int at = (start + i) % n;
      double along = arc[at] - arc[start];
      if (along < 0) along += perimeter;
      const double offset = std::abs(along - ideal);
      if (offset > perimeter / 8) continue;
      if (offset < nearest_offset) nearest_offset = offset, nearest = at;
      if (turn[at] > kPi / 6 && (sharpest < 0 || turn[at] > turn[sharpest])) sharpest = at;
    }
    corners[q] = sharpest >= 0 ? sharpest_near(sharpest) : nearest;
  }
  return corners;
}

/// The surface point at parameter `uv`: in the face whose barycentric coordinates of it are
/// least negative.
Vec3 point_at(const TriangleMesh& mesh, const std::vector<Vec2>& uv, const Vec2& target) {
  double best = -1e300;
  Vec3 point = Vec3::Zero();
  for (const Face& f : mesh.faces()) {
    const Vec2 &a = uv[f[0]], &b = uv[f[1]], &c = uv[f[2]];
    const double area = (b - a).x() * (c - a).y() - (b - a).y() * (c - a).x();
    if (std::abs(area) < 1e-300) continue;
    const auto cross = [](const Vec2& p, const Vec2& q, const Vec2& r) {
      return (q - p).x() * (r - p).y() - (q - p).y() * (r - p).x();
    };
    const double l0 = cross(target, b, c) / area, l1 = cross(a, target, c) / area, l2 = 1 - l0 - l1;
    const double worst = std::min({l0, l1, l2});
    if (worst > best) {
      best = worst;
      // Clamped to the face (a point just outside, by rounding, goes onto its edge).
      double w0 = std::max(0.0, l0), w1 = std::max(0.0, l1), w2 = std::max(0.0, l2);
      const double sum = w0 + w1 + w2;
      w0 /= sum, w1 /= sum, w2 /= sum;
      point = w0 * mesh.vertices()[f[0]] + w1 * mesh.vertices()[f[1]] + w2 * mesh.vertices()[f[2]];
    }
  }
  return point;
}

/// The mesh mapped onto the unit square with loop[corners[k]] at its corners in order.
std::vector<Vec2> square_map(const TriangleMesh& mesh, const std::vector<int>& loop,
                             const std::array<int, 4>& corners) {
  CgalMesh cgal;
  std::vector<CgalMesh::Vertex_index> handle;
  for (const Vec3& p : mesh.vertices()) handle.push_back(cgal.add_vertex({p.x(), p.y(), p.z()}));
  for (const Face& f : mesh.faces())
    if (cgal.add_face(handle[f[0]], handle[f[1]], handle[f[2]]) == CgalMesh::null_face())
      throw Infeasible("layout",
                       "the surface could not be mapped onto a square (a face is not "
                       "manifold for CGAL)");
  // A border halfedge of the loop; the corners run along the border in CGAL's direction.
  CgalMesh::Halfedge_index border;
  for (CgalMesh::Halfedge_index h : cgal.halfedges())
    if (cgal.is_border(h)) {
      border = h;
      break;
    }
  using Border = SMP::Square_border_arc_length_parameterizer_3<CgalMesh>;
  using Parameterizer = SMP::Mean_value_coordinates_parameterizer_3<CgalMesh, Border>;
  const Border border_map(handle[loop[corners[0]]], handle[loop[corners[1]]],
                          handle[loop[corners[2]]], handle[loop[corners[3]]]);
  auto uv_map = cgal.add_property_map<CgalMesh::Vertex_index, Kernel::Point_2>("v:uv").first;
  const SMP::Error_code status = SMP::parameterize(cgal, Parameterizer(border_map), border, uv_map);
  if (status != SMP::OK)
    throw Infeasible("layout", std::string("the surface could not be mapped onto a square: ") +
                                   SMP::get_error_message(status));
  std::vector<Vec2> uv(mesh.vertex_count(), Vec2::Zero());
  for (int v = 0; v < mesh.vertex_count(); ++v)
    uv[v] = Vec2(uv_map[handle[v]].x(), uv_map[handle[v]].y());
  return uv;
}

}  // namespace

AutoLayout auto_layout(const TriangleMesh& mesh, const TargetPatchOptions& patch_options,
                       const AutoLayoutOptions& options, const Progress& progress) {
  check_disk(mesh);
  progress.report("layout: square map", 0);
  const std::vector<int>& loop = mesh.topology().boundary_loops.front();
  std::array<int, 4> corners = square_corners(mesh, loop);
  // CGAL walks the border against the faces' orientation: corners in the order it meets them,
  // and each at the square's corner it was mapped to.
  std::swap(corners[1], corners[3]);
  const std::vector<Vec2> uv = square_map(mesh, loop, corners);
  AutoLayout out;
  const std::array<Vec2, 4> square{Vec2(0, 0), Vec2(1, 0), Vec2(1, 1), Vec2(0, 1)};
  for (int k = 0; k < 4; ++k) {
    int at = -1;
    for (int c : corners)
      if ((uv[loop[c]] - square[k]).norm() < 1e-9) at = loop[c];
    if (at < 0)
      throw std::logic_error("auto_layout: a corner of the square is not a chosen vertex");
    out.boundary_corners[k] = at;
  }
  // The square's sides u (corner 0 -> 1, 3 -> 2) and v (1 -> 2, 0 -> 3): their lengths on the
  // surface, averaged over opposite sides, give the patches' best shape.
  const auto arc_between = [&](int from, int to) {
    const int n = static_cast<int>(loop.size());
    double length = 0;
    for (int i = corners[from]; i != corners[to]; i = (i + 1) % n)
      length += (mesh.vertices()[loop[(i + 1) % n]] - mesh.vertices()[loop[i]]).norm();
    return length;
  };
  const double length_u = 0.5 * (arc_between(0, 1) + arc_between(2, 3));
  const double length_v = 0.5 * (arc_between(1, 2) + arc_between(3, 0));
  const double aspect = length_v > 0 ? length_u / length_v : 1.0;
  // For each patch count, the grid whose patches are closest to square (in side length).
  std::vector<std::pair<int, int>> grids;
  for (int n = 1; n <= options.max_patches; ++n) {
    std::pair<int, int> best{0, 0};
    double best_error = 1e300;
    for (int columns = 1; columns <= n; ++columns) {
      if (n % columns) continue;
      const int rows = n / columns;
      const double error = std::abs(std::log(aspect * rows / columns));
      if (error < best_error) best_error = error, best = {columns, rows};
    }
    // Patches at most twice as long one way as the other.
    if (best_error <= std::log(2.0) + 1e-12) grids.push_back(best);
  }
  if (grids.empty()) grids.push_back({1, 1});
  std::vector<PatchLayout> layouts;
  bool chosen = false;
  size_t checked = 0;
  const auto check = [&](size_t t) {
    AutoLayoutTrial& trial = out.trials[t];
    progress.report(
        "layout: check " + std::to_string(trial.columns) + " x " + std::to_string(trial.rows),
        0.5 + 0.5 * static_cast<double>(++checked) / out.trials.size());
    const auto start = std::chrono::steady_clock::now();
    LayoutResult result = cut_layout(mesh, layouts[t], patch_options, progress.checker());
    trial.checked = true;
    trial.coverage = result.coverage();
    for (const LayoutPatch& p : result.patches) {
      if (!p.problem && p.target) continue;
      if (trial.failing++ == 0)
        trial.first_problem = p.name + ": " + (p.problem ? p.problem->what() : "not cut");
    }
    trial.seconds +=
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const int patches = trial.columns * trial.rows;
    const bool better =
        !chosen || trial.coverage > out.result.coverage() + 1e-12 ||
        (trial.coverage > out.result.coverage() - 1e-12 && patches < out.columns * out.rows);
    if (better) {
      out.result = std::move(result);
      out.columns = trial.columns, out.rows = trial.rows;
      chosen = true;
    }
    return trial.coverage >= options.coverage_goal;
  };
  // Fewest patches first, each grid cut with its patches' corners checked only: an upper bound
  // of its coverage at a fraction of the full checks' cost (coverability and smoothing of every
  // patch). A grid whose bound reaches the goal is checked in full; the first that covers the
  // goal is kept.
  bool reached = false;
  for (size_t t = 0; t < grids.size() && !reached; ++t) {
    const auto [columns, rows] = grids[t];
    progress.report("layout: cut " + std::to_string(columns) + " x " + std::to_string(rows),
                    static_cast<double>(t) / grids.size());
    const auto start = std::chrono::steady_clock::now();
    PatchLayout layout;
    for (int j = 0; j <= rows; ++j)
      for (int i = 0; i <= columns; ++i) {
        LayoutCorner c;
        const bool corner = (i == 0 || i == columns) && (j == 0 || j == rows);
        if (corner) {
          const int k = i == 0 ? (j == 0 ? 0 : 3) : (j == 0 ? 1 : 2);
          c.vertex = out.boundary_corners[k];
        } else {
          c.point = point_at(mesh, uv,
                             Vec2(static_cast<double>(i) / columns, static_cast<double>(j) / rows));
        }
        layout.corners.push_back(c);
      }
    for (int j = 0; j < rows; ++j)
      for (int i = 0; i < columns; ++i) {
        const int a = j * (columns + 1) + i;
        layout.patches.push_back({"", {a, a + 1, a + columns + 2, a + columns + 1}});
      }
    const LayoutResult cut =
        cut_layout(mesh, layout, patch_options, progress.checker(), LayoutChecks::CutOnly);
    AutoLayoutTrial trial;
    trial.columns = columns, trial.rows = rows;
    trial.cut_coverage = cut.coverage();
    trial.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    out.trials.push_back(trial);
    layouts.push_back(std::move(layout));
    if (trial.cut_coverage >= options.coverage_goal) reached = check(t);
  }
  // No grid reached the goal: the largest bounds checked until none left is above the best
  // coverage found.
  if (!reached) {
    std::vector<size_t> order(out.trials.size());
    std::iota(order.begin(), order.end(), size_t{0});
    std::stable_sort(order.begin(), order.end(), [&](size_t x, size_t y) {
      return out.trials[x].cut_coverage > out.trials[y].cut_coverage;
    });
    for (size_t t : order) {
      if (out.trials[t].checked) continue;
      if (chosen && out.trials[t].cut_coverage <= out.result.coverage() + 1e-12) break;
      check(t);
    }
  }
  progress.report("layout", 1.0);
  return out;
}

}  // namespace gridshell
