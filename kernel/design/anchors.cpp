// SPDX-License-Identifier: GPL-3.0-or-later
#include "gridshell/design/anchors.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <tuple>

#include "gridshell/mesh/normals.h"
#include "gridshell/mesh/surface_distance.h"

namespace gridshell {
namespace {

// Point at arc length s along a polyline.
Vec3 at_arc_length(const std::vector<Vec3>& polyline, const std::vector<double>& cumulative,
                   double s) {
  const auto it = std::upper_bound(cumulative.begin(), cumulative.end(), s);
  const size_t k = std::clamp<size_t>(it - cumulative.begin(), 1, polyline.size() - 1);
  const double l = cumulative[k] - cumulative[k - 1];
  const double w = l > 0 ? std::clamp((s - cumulative[k - 1]) / l, 0.0, 1.0) : 0.0;
  return polyline[k - 1] + w * (polyline[k] - polyline[k - 1]);
}

// Topographic prominence of the local maximum at i: its height above the higher of the two
// lowest points separating it from a higher value on either side (or from the ends).
double prominence(const std::vector<double>& values, int i) {
  double left = values[i], right = values[i];
  for (int k = i - 1; k >= 0 && values[k] <= values[i]; --k) left = std::min(left, values[k]);
  for (size_t k = i + 1; k < values.size() && values[k] <= values[i]; ++k)
    right = std::min(right, values[k]);
  return values[i] - std::max(left, right);
}

std::vector<double> cumulative_lengths(const std::vector<Vec3>& polyline) {
  std::vector<double> cumulative{0.0};
  for (size_t k = 1; k < polyline.size(); ++k)
    cumulative.push_back(cumulative.back() + (polyline[k] - polyline[k - 1]).norm());
  return cumulative;
}

}  // namespace

std::vector<double> boundary_curvature(const std::vector<Vec3>& polyline, int samples,
                                       double window_fraction) {
  const std::vector<double> cumulative = cumulative_lengths(polyline);
  const double length = cumulative.back();
  std::vector<double> curvature(samples, 0.0);
  if (length <= 0 || samples < 3) return curvature;
  // The sides are polylines: curvature sits at their vertices. The three points must straddle
  // several vertices or the estimate oscillates with the sampling phase.
  double longest = 0;
  for (size_t k = 1; k < cumulative.size(); ++k)
    longest = std::max(longest, cumulative[k] - cumulative[k - 1]);
  const double h = std::max({window_fraction * length / 2, 2 * longest, 1e-12});
  for (int i = 0; i < samples; ++i) {
    const double s = length * i / (samples - 1);
    if (s - h < 0 || s + h > length) continue;  // the window must fit on the side
    // Curvature of the circle through three points h apart in arc length: 2 sin(angle)/chord.
    const Vec3 a = at_arc_length(polyline, cumulative, s - h);
    const Vec3 b = at_arc_length(polyline, cumulative, s);
    const Vec3 c = at_arc_length(polyline, cumulative, s + h);
    const double ab = (b - a).norm(), bc = (c - b).norm(), ca = (a - c).norm();
    const double area2 = (b - a).cross(c - a).norm();
    if (ab > 0 && bc > 0 && ca > 0) curvature[i] = 2 * area2 / (ab * bc * ca);
  }
  return curvature;
}

namespace {

/// Inner anchors (AnchorOptions::interior): strict local extrema of the height over the boundary's
/// least-squares plane among the grid's inner crossings, most prominent first.
void place_interior_anchors(const Patch& patch, const Grid& grid, const std::vector<Vec3>& normals,
                            const SurfaceDistance& surface, const AnchorOptions& options,
                            std::vector<Anchor>& anchors) {
  const TriangleMesh& mesh = patch.mesh;
  const int ng = static_cast<int>(grid.g.size()), nh = static_cast<int>(grid.h.size());
  if (ng < 3 || nh < 3 || static_cast<int>(grid.crossings.size()) != ng * nh) return;
  // Plane of the boundary: centroid and the direction of least spread of the side vertices,
  // oriented along the target's mean normal.
  std::vector<int> boundary;
  for (const auto& side : patch.sides) boundary.insert(boundary.end(), side.begin(), side.end());
  Vec3 centroid = Vec3::Zero();
  for (int v : boundary) centroid += mesh.vertices()[v];
  centroid /= static_cast<double>(boundary.size());
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  for (int v : boundary) {
    const Vec3 d = mesh.vertices()[v] - centroid;
    covariance += d * d.transpose();
  }
  Vec3 up = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(covariance).eigenvectors().col(0);
  Vec3 mean_normal = Vec3::Zero();
  for (const Vec3& n : normals) mean_normal += n;
  if (up.dot(mean_normal) < 0) up = -up;
  const double threshold = options.min_interior_prominence * bounding_box_size(mesh).norm();
  auto height = [&](int g, int h) {
    return (grid.crossings[static_cast<size_t>(g) * nh + h].surface_point - centroid).dot(up);
  };
  struct Candidate {
    double prominence;
    int g, h;
  };
  std::vector<Candidate> candidates;
  for (int g = 1; g + 1 < ng; ++g)
    for (int h = 1; h + 1 < nh; ++h) {
      const double z = height(g, h);
      double lowest = std::numeric_limits<double>::infinity(), highest = -lowest, sum = 0;
      for (int dg = -1; dg <= 1; ++dg)
        for (int dh = -1; dh <= 1; ++dh) {
          if (dg == 0 && dh == 0) continue;
          const double n = height(g + dg, h + dh);
          lowest = std::min(lowest, n);
          highest = std::max(highest, n);
          sum += n;
        }
      if (!(z > highest || z < lowest)) continue;
      const double prominence = std::abs(z - sum / 8);
      if (prominence >= threshold) candidates.push_back({prominence, g, h});
    }
  std::sort(candidates.begin(), candidates.end(), [](const Candidate& a, const Candidate& b) {
    return a.prominence != b.prominence ? a.prominence > b.prominence
                                        : std::tie(a.g, a.h) < std::tie(b.g, b.h);
  });
  if (static_cast<int>(candidates.size()) > options.interior) candidates.resize(options.interior);
  for (const Candidate& c : candidates) {
    Anchor a;
    a.g = c.g, a.h = c.h;
    a.side = -1;
    a.position = grid.crossings[static_cast<size_t>(c.g) * nh + c.h].surface_point;
    a.normal = surface.normal_at_closest(a.position);
    anchors.push_back(a);
  }
}

}  // namespace

std::vector<Anchor> place_anchors(const Patch& patch, const Grid& grid,
                                  const AnchorOptions& options) {
  const TriangleMesh& mesh = patch.mesh;
  const std::vector<Vec3> normals = vertex_normals(mesh);
  const int ng = static_cast<int>(grid.g.size()), nh = static_cast<int>(grid.h.size());
  // The normal at the crossing itself (the vertex normals interpolated over its face): a support
  // holds the lamellas' orientation there, and the simulation holds it rigidly, so the nearest
  // vertex's normal (up to 0.012 rad off on the sphere example) would tilt the grid.
  const SurfaceDistance surface(mesh);
  std::vector<Anchor> anchors;
  // Corners: c0 = g0 x h0, c1 = g_last x h0, c2 = g_last x h_last, c3 = g0 x h_last.
  const std::array<std::array<int, 2>, 4> corner_crossings{
      {{0, 0}, {ng - 1, 0}, {ng - 1, nh - 1}, {0, nh - 1}}};
  for (int i = 0; i < 4; ++i) {
    Anchor a;
    a.g = corner_crossings[i][0], a.h = corner_crossings[i][1];
    a.corner = true;
    a.side = i;
    a.position = mesh.vertices()[patch.corners[i]];
    a.normal = normals[patch.corners[i]];
    anchors.push_back(a);
  }
  // Boundary curvature of all four sides; small extrema are filtered relative to the largest
  // curvature on any side, and a side must bend by at least min_turning over the window.
  const int samples = 201;
  std::array<std::vector<double>, 4> curvatures;
  std::array<double, 4> lengths{};
  double kmax = 0;
  for (int side = 0; side < 4; ++side) {
    std::vector<Vec3> polyline;
    for (int v : patch.sides[side]) polyline.push_back(mesh.vertices()[v]);
    curvatures[side] = boundary_curvature(polyline, samples, options.curvature_window);
    lengths[side] = cumulative_lengths(polyline).back();
    kmax = std::max(kmax, *std::max_element(curvatures[side].begin(), curvatures[side].end()));
  }
  for (int side = 0; side < 4; ++side) {
    const std::vector<double>& kappa = curvatures[side];
    const double threshold =
        std::max(options.min_relative_curvature * kmax,
                 options.min_turning / (options.curvature_window * lengths[side]));
    // Local maxima above the threshold, strongest first, kept apart from corners and each other.
    std::vector<int> peaks;
    for (int i = 1; i + 1 < samples; ++i)
      if (kappa[i] >= kappa[i - 1] && kappa[i] > kappa[i + 1] && kappa[i] >= threshold &&
          prominence(kappa, i) >= options.min_relative_prominence * kmax)
        peaks.push_back(i);
    std::stable_sort(peaks.begin(), peaks.end(), [&](int a, int b) { return kappa[a] > kappa[b]; });
    std::vector<double> kept;  // arc-length fractions
    for (int i : peaks) {
      const double t = static_cast<double>(i) / (samples - 1);
      if (t < options.min_separation || t > 1 - options.min_separation) continue;
      bool close = false;
      for (double k : kept) close |= std::abs(k - t) < options.min_separation;
      if (!close) kept.push_back(t);
    }
    std::sort(kept.begin(), kept.end());
    // Inner boundary crossings on this side with their fraction along c_side -> c_side+1.
    struct Candidate {
      int g, h;
      double t;
      Vec3 p;
    };
    std::vector<Candidate> candidates;
    for (const Crossing& x : grid.crossings) {
      if (!x.on_boundary) continue;
      const bool g_boundary = x.g == 0 || x.g == ng - 1, h_boundary = x.h == 0 || x.h == nh - 1;
      if (g_boundary && h_boundary) continue;  // corners
      double t = -1;
      // side 0 = h0 reversed (c1 -> c0); side 1 = g_last (c1 -> c2); side 2 = h_last (c2 -> c3);
      // side 3 = g0 reversed (c0 -> c3).
      if (side == 0 && x.h == 0) t = 1 - x.s_h / grid.h.front().length;
      if (side == 1 && x.g == ng - 1) t = x.s_g / grid.g.back().length;
      if (side == 2 && x.h == nh - 1) t = x.s_h / grid.h.back().length;
      if (side == 3 && x.g == 0) t = 1 - x.s_g / grid.g.front().length;
      if (t >= 0) candidates.push_back({x.g, x.h, t, x.surface_point});
    }
    for (double t : kept) {
      const Candidate* best = nullptr;
      for (const Candidate& c : candidates)
        if (!best || std::abs(c.t - t) < std::abs(best->t - t)) best = &c;
      if (!best) continue;
      bool duplicate = false;
      for (const Anchor& a : anchors) duplicate |= a.g == best->g && a.h == best->h;
      if (duplicate) continue;
      Anchor a;
      a.g = best->g, a.h = best->h;
      a.side = side;
      a.position = best->p;
      a.normal = surface.normal_at_closest(best->p);
      a.boundary_curvature = kappa[static_cast<int>(std::lround(t * (samples - 1)))];
      anchors.push_back(a);
    }
  }
  if (options.interior > 0) place_interior_anchors(patch, grid, normals, surface, options, anchors);
  return anchors;
}

}  // namespace gridshell
