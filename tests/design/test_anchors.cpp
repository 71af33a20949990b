// SPDX-License-Identifier: GPL-3.0-or-later
// Anchors (gridshell/design/anchors.h, paper 4.6): boundary_curvature on analytic curves (circle,
// straight line, ellipse), and place_anchors on a designed grid: corners first, the other
// anchors grid crossings on the boundary side they name, unit normals matching the surface,
// deterministic, and inner anchors (when asked) at strict height extrema of the crossings.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <memory>
#include <numbers>
#include <string>
#include <vector>

#include "gridshell/design/anchors.h"
#include "gridshell/design/design.h"
#include "gridshell/example_surfaces.h"
#include "gridshell/mesh/normals.h"
#include "gridshell/mesh/surface_distance.h"
#include "support.h"

namespace gridshell {
namespace {

constexpr double kPi = std::numbers::pi;

// ---------------------------------------------------------------------------------------------
// boundary_curvature

std::vector<Vec3> sample_curve(int n, double t0, double t1,
                               const std::function<Vec3(double)>& curve) {
  std::vector<Vec3> out;
  for (int k = 0; k <= n; ++k) out.push_back(curve(t0 + (t1 - t0) * k / n));
  return out;
}

/// Samples of boundary_curvature whose window fits on the curve (the others are 0 by contract).
std::vector<int> measured(const std::vector<double>& curvature) {
  std::vector<int> out;
  for (int i = 0; i < static_cast<int>(curvature.size()); ++i)
    if (curvature[i] != 0.0) out.push_back(i);
  return out;
}

TEST(BoundaryCurvature, CircleOfRadiusRIsOneOverR) {
  for (double r : {0.5, 3.0, 40.0}) {
    // A 120 degree arc in a tilted plane, 600 segments.
    const Vec3 e1 = Vec3(1, 1, 0).normalized(), e2 = Vec3(-1, 1, 2).normalized();
    const std::vector<Vec3> arc = sample_curve(600, 0, 2 * kPi / 3, [&](double t) -> Vec3 {
      return Vec3(5, -2, 1) + r * (std::cos(t) * e1 + std::sin(t) * e2);
    });
    const std::vector<double> k = boundary_curvature(arc, 201, 0.04);
    ASSERT_EQ(k.size(), 201u);
    const std::vector<int> inside = measured(k);
    EXPECT_GT(inside.size(), 190u);
    for (int i : inside) EXPECT_NEAR(k[i] * r, 1.0, 1e-4) << "r " << r << " sample " << i;
    // The window must fit on the curve: the end samples are not measured.
    EXPECT_EQ(k.front(), 0.0);
    EXPECT_EQ(k.back(), 0.0);
  }
}

TEST(BoundaryCurvature, StraightLineIsZero) {
  // Uneven vertices along a straight segment.
  std::vector<Vec3> line;
  double s = 0;
  for (int k = 0; k <= 80; ++k) {
    line.push_back(Vec3(1, 2, 3) + s * Vec3(2, -1, 0.5).normalized());
    s += 0.05 + 0.04 * std::sin(k);
  }
  for (double k : boundary_curvature(line, 101, 0.04)) EXPECT_NEAR(k, 0.0, 1e-9);
}

TEST(BoundaryCurvature, EllipseExtremesAtTheAxisEnds) {
  // x = a cos t, y = b sin t over t in [-3 pi/4, 3 pi/4]: curvature a/b^2 at the end of the
  // major axis (t = 0) and b/a^2 at the ends of the minor axis (t = +-pi/2).
  const double a = 3.0, b = 2.0;
  const std::vector<Vec3> ellipse = sample_curve(3000, -0.75 * kPi, 0.75 * kPi, [&](double t) {
    return Vec3(a * std::cos(t), b * std::sin(t), 0);
  });
  const int samples = 401;
  const std::vector<double> k = boundary_curvature(ellipse, samples, 0.01);
  // Arc-length fractions of the axis ends.
  std::vector<double> cumulative{0};
  for (std::size_t i = 1; i < ellipse.size(); ++i)
    cumulative.push_back(cumulative.back() + (ellipse[i] - ellipse[i - 1]).norm());
  const auto fraction_at = [&](const Vec3& p) {
    std::size_t best = 0;
    for (std::size_t i = 0; i < ellipse.size(); ++i)
      if ((ellipse[i] - p).norm() < (ellipse[best] - p).norm()) best = i;
    return cumulative[best] / cumulative.back();
  };
  const std::vector<int> inside = measured(k);
  ASSERT_GT(inside.size(), 380u);
  int argmax = inside.front(), argmin = inside.front();
  for (int i : inside) {
    if (k[i] > k[argmax]) argmax = i;
    if (k[i] < k[argmin]) argmin = i;
  }
  EXPECT_NEAR(k[argmax], a / (b * b), 2e-3 * a / (b * b));
  EXPECT_NEAR(static_cast<double>(argmax) / (samples - 1), fraction_at(Vec3(a, 0, 0)), 0.005);
  EXPECT_NEAR(k[argmin], b / (a * a), 2e-3 * b / (a * a));
  const double minor_lo = fraction_at(Vec3(0, -b, 0)), minor_hi = fraction_at(Vec3(0, b, 0));
  const double at = static_cast<double>(argmin) / (samples - 1);
  EXPECT_LT(std::min(std::abs(at - minor_lo), std::abs(at - minor_hi)), 0.005);
  // The value at the minor axis ends: b/a^2 on both.
  for (double f : {minor_lo, minor_hi})
    EXPECT_NEAR(k[static_cast<int>(std::lround(f * (samples - 1)))], b / (a * a),
                5e-3 * b / (a * a));
}

TEST(BoundaryCurvature, DegenerateInputsGiveZeros) {
  EXPECT_EQ(boundary_curvature({Vec3(1, 1, 1), Vec3(1, 1, 1)}, 5, 0.04),
            std::vector<double>(5, 0.0));
  const std::vector<Vec3> arc =
      sample_curve(50, 0, 1, [](double t) { return Vec3(std::cos(t), std::sin(t), 0); });
  EXPECT_EQ(boundary_curvature(arc, 2, 0.04), std::vector<double>(2, 0.0));
}

// ---------------------------------------------------------------------------------------------
// place_anchors on a designed grid

/// One design of the double vault (maps at resolution 48), shared by the tests of this file.
const Design& double_vault() {
  static const std::unique_ptr<const Design> design = [] {
    const ExampleSurface example = make_example("double-vault");
    DesignOptions options;
    options.maps.resolution = 48;
    return std::make_unique<const Design>(
        make_design(example.mesh, CornerSpec::at_vertices(example.corners), options));
  }();
  return *design;
}

const Crossing& crossing_of(const Grid& grid, int g, int h) {
  return grid.crossings.at(static_cast<std::size_t>(g) * grid.h.size() + h);
}

TEST(PlaceAnchors, CornersFirstThenBoundaryCrossingsOnTheirSide) {
  const Design& d = double_vault();
  const Patch& patch = d.target.patch;
  const Grid& grid = d.grid;
  const int ng = static_cast<int>(grid.g.size()), nh = static_cast<int>(grid.h.size());
  const std::vector<Anchor> anchors = place_anchors(patch, grid);
  ASSERT_GE(anchors.size(), 4u);
  const std::array<std::array<int, 2>, 4> corner_crossings{
      {{0, 0}, {ng - 1, 0}, {ng - 1, nh - 1}, {0, nh - 1}}};
  for (int i = 0; i < 4; ++i) {
    const Anchor& a = anchors[i];
    EXPECT_TRUE(a.corner) << i;
    EXPECT_EQ(a.side, i);
    EXPECT_EQ(a.g, corner_crossings[i][0]);
    EXPECT_EQ(a.h, corner_crossings[i][1]);
    EXPECT_EQ(a.position, patch.mesh.vertices()[patch.corners[i]]);
    EXPECT_EQ(a.boundary_curvature, 0.0);
    // The corner crossing is at the corner.
    EXPECT_LT((crossing_of(grid, a.g, a.h).surface_point - a.position).norm(),
              1e-9 * grid.g[0].length);
  }
  int previous_side = 0;
  for (std::size_t k = 4; k < anchors.size(); ++k) {
    const Anchor& a = anchors[k];
    SCOPED_TRACE("anchor " + std::to_string(k));
    EXPECT_FALSE(a.corner);
    ASSERT_GE(a.side, 0);  // boundary only by default
    ASSERT_LT(a.side, 4);
    EXPECT_GE(a.side, previous_side);  // by side
    previous_side = a.side;
    const Crossing& x = crossing_of(grid, a.g, a.h);
    EXPECT_TRUE(x.on_boundary);
    EXPECT_EQ(a.position, x.surface_point);
    // On the side it names, and not a corner crossing.
    if (a.side == 0) {
      EXPECT_EQ(a.h, 0);
    }
    if (a.side == 1) {
      EXPECT_EQ(a.g, ng - 1);
    }
    if (a.side == 2) {
      EXPECT_EQ(a.h, nh - 1);
    }
    if (a.side == 3) {
      EXPECT_EQ(a.g, 0);
    }
    EXPECT_FALSE((a.g == 0 || a.g == ng - 1) && (a.h == 0 || a.h == nh - 1));
    EXPECT_GT(a.boundary_curvature, 0.0);
    // The side polyline passes through the anchor.
    double nearest = std::numeric_limits<double>::infinity();
    const std::vector<int>& side = patch.sides[a.side];
    for (std::size_t v = 0; v + 1 < side.size(); ++v) {
      const Vec3 p = patch.mesh.vertices()[side[v]], q = patch.mesh.vertices()[side[v + 1]];
      const double t = std::clamp((a.position - p).dot(q - p) / (q - p).squaredNorm(), 0.0, 1.0);
      nearest = std::min(nearest, (p + t * (q - p) - a.position).norm());
    }
    EXPECT_LT(nearest, 1e-9 * grid.g[0].length);
  }
  // No crossing is anchored twice.
  for (std::size_t i = 0; i < anchors.size(); ++i)
    for (std::size_t j = i + 1; j < anchors.size(); ++j)
      EXPECT_FALSE(anchors[i].g == anchors[j].g && anchors[i].h == anchors[j].h) << i << " " << j;
  // The design's own anchors are these.
  ASSERT_EQ(d.anchors.size(), anchors.size());
  for (std::size_t k = 0; k < anchors.size(); ++k) {
    EXPECT_EQ(d.anchors[k].g, anchors[k].g);
    EXPECT_EQ(d.anchors[k].h, anchors[k].h);
  }
}

// The double vault's boundary geodesics bend at the vaults: there are curvature anchors, and
// each stands above the filter threshold (min_relative_curvature x the largest curvature of any
// side, measured as place_anchors measures it).
TEST(PlaceAnchors, CurvatureAnchorsPassTheThreshold) {
  const Design& d = double_vault();
  const Patch& patch = d.target.patch;
  const AnchorOptions options;
  double kmax = 0;
  for (int side = 0; side < 4; ++side) {
    std::vector<Vec3> polyline;
    for (int v : patch.sides[side]) polyline.push_back(patch.mesh.vertices()[v]);
    const std::vector<double> k = boundary_curvature(polyline, 201, options.curvature_window);
    kmax = std::max(kmax, *std::max_element(k.begin(), k.end()));
  }
  const std::vector<Anchor> anchors = place_anchors(patch, d.grid, options);
  ASSERT_GT(anchors.size(), 4u);
  for (std::size_t k = 4; k < anchors.size(); ++k)
    EXPECT_GE(anchors[k].boundary_curvature, options.min_relative_curvature * kmax) << k;
  // A stricter filter keeps a subset.
  AnchorOptions strict = options;
  strict.min_relative_curvature = 0.9;
  EXPECT_LE(place_anchors(patch, d.grid, strict).size(), anchors.size());
}

TEST(PlaceAnchors, NormalsAreUnitAndMatchTheSurface) {
  const Design& d = double_vault();
  const Patch& patch = d.target.patch;
  const SurfaceDistance surface(patch.mesh);
  AnchorOptions options;
  options.interior = 4;
  const std::vector<Anchor> anchors = place_anchors(patch, d.grid, options);
  const double size = bounding_box_size(patch.mesh).norm();
  for (std::size_t k = 0; k < anchors.size(); ++k) {
    const Anchor& a = anchors[k];
    EXPECT_NEAR(a.normal.norm(), 1.0, 1e-12) << k;
    // On the surface, with the surface's normal there.
    EXPECT_LT(surface.distance(a.position), 1e-9 * size) << k;
    EXPECT_GT(a.normal.dot(surface.normal_at_closest(a.position)), 0.99) << k;
    // The face normal of the closest face agrees in orientation too.
    const SurfacePoint p = surface.closest(a.position);
    const Face& f = patch.mesh.faces()[p.face];
    const Vec3 n = (patch.mesh.vertices()[f[1]] - patch.mesh.vertices()[f[0]])
                       .cross(patch.mesh.vertices()[f[2]] - patch.mesh.vertices()[f[0]])
                       .normalized();
    EXPECT_GT(a.normal.dot(n), 0.95) << k;
  }
}

// The supports hold the lamellas' orientation rigidly in the simulation, whose rods start
// framed by the surface's normal interpolated over its faces (SurfaceDistance::normal_at_closest):
// an anchor's normal is that same normal at the crossing itself, not a nearby vertex's, so that
// the supports do not twist the grid out of its start state.
TEST(PlaceAnchors, NormalsAreTheSurfaceNormalAtTheCrossing) {
  const ExampleSurface example = make_example("sphere");
  DesignOptions design_options;
  design_options.maps.resolution = 48;
  design_options.anchors.interior = 4;
  const Design d =
      make_design(example.mesh, CornerSpec::at_vertices(example.corners), design_options);
  const SurfaceDistance surface(d.target.patch.mesh);
  ASSERT_GE(d.anchors.size(), 5u);
  for (std::size_t k = 0; k < d.anchors.size(); ++k) {
    const Anchor& a = d.anchors[k];
    EXPECT_LT((a.normal - surface.normal_at_closest(a.position)).norm(), 1e-9)
        << "anchor " << k << " at (" << a.g << ", " << a.h << ")";
  }
}

TEST(PlaceAnchors, Deterministic) {
  const Design& d = double_vault();
  AnchorOptions options;
  options.interior = 5;
  const std::vector<Anchor> a = place_anchors(d.target.patch, d.grid, options);
  const std::vector<Anchor> b = place_anchors(d.target.patch, d.grid, options);
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t k = 0; k < a.size(); ++k) {
    EXPECT_EQ(a[k].g, b[k].g);
    EXPECT_EQ(a[k].h, b[k].h);
    EXPECT_EQ(a[k].side, b[k].side);
    EXPECT_EQ(a[k].corner, b[k].corner);
    EXPECT_EQ(a[k].position, b[k].position);
    EXPECT_EQ(a[k].normal, b[k].normal);
    EXPECT_EQ(a[k].boundary_curvature, b[k].boundary_curvature);
  }
}

// Inner anchors sit at strict local extrema (among the 8 neighbouring crossings) of the height
// over the least-squares plane of the boundary, recomputed here from the patch sides.
TEST(PlaceAnchors, InteriorAnchorsAreStrictHeightExtrema) {
  const Design& d = double_vault();
  const Patch& patch = d.target.patch;
  const Grid& grid = d.grid;
  const int ng = static_cast<int>(grid.g.size()), nh = static_cast<int>(grid.h.size());
  std::vector<Vec3> boundary;
  for (const auto& side : patch.sides)
    for (int v : side) boundary.push_back(patch.mesh.vertices()[v]);
  Vec3 centroid = Vec3::Zero();
  for (const Vec3& p : boundary) centroid += p / static_cast<double>(boundary.size());
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  for (const Vec3& p : boundary) covariance += (p - centroid) * (p - centroid).transpose();
  const Vec3 up = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(covariance).eigenvectors().col(0);
  const auto height = [&](int g, int h) {
    return (crossing_of(grid, g, h).surface_point - centroid).dot(up);
  };
  AnchorOptions options;
  options.interior = 10;
  int inner = 0;
  for (const Anchor& a : place_anchors(patch, grid, options)) {
    if (a.side >= 0) continue;
    ++inner;
    EXPECT_FALSE(a.corner);
    ASSERT_TRUE(a.g > 0 && a.g < ng - 1 && a.h > 0 && a.h < nh - 1);
    EXPECT_EQ(a.position, crossing_of(grid, a.g, a.h).surface_point);
    EXPECT_EQ(a.boundary_curvature, 0.0);
    const double z = height(a.g, a.h);
    int above = 0, below = 0;
    for (int dg = -1; dg <= 1; ++dg)
      for (int dh = -1; dh <= 1; ++dh) {
        if (dg == 0 && dh == 0) continue;
        const double n = height(a.g + dg, a.h + dh);
        above += z > n;
        below += z < n;
      }
    EXPECT_TRUE(above == 8 || below == 8)
        << "g" << a.g << " h" << a.h << ": above " << above << ", below " << below;
  }
  EXPECT_EQ(inner, 2);  // the two crowns
}

// Moved from tests/design/test_design.cpp (Design.InteriorAnchorsAtCrownsAndNoneOnASaddle),
// unchanged but for the suite name.
//
// Inner anchors (AnchorOptions::interior): strict local extrema of the height over the
// boundary's plane. A spherical cap has one (its crown, where the normal is the plane's normal),
// the double vault two (its crowns, the higher first), a hyperbolic paraboloid none (a saddle
// has no extremum); the boundary anchors stay as they were.
TEST(PlaceAnchors, InteriorAnchorsAtCrownsAndNoneOnASaddle) {
  auto design = [](const std::string& name) {
    const ExampleSurface example = make_example(name);
    const CornerSpec corners = CornerSpec::at_vertices(example.corners);
    DesignOptions options;
    options.maps.resolution = 48;
    return make_design(example.mesh, corners, options);
  };
  auto inner = [](const std::vector<Anchor>& anchors) {
    std::vector<Anchor> out;
    for (const Anchor& a : anchors)
      if (a.side < 0) out.push_back(a);
    return out;
  };
  auto crossing = [](const Grid& grid, const Anchor& a) {
    return grid.crossings[static_cast<size_t>(a.g) * grid.h.size() + a.h];
  };
  AnchorOptions options;
  options.interior = 10;
  {
    const Design d = design("sphere");
    EXPECT_TRUE(inner(d.anchors).empty());  // the default is the paper's: boundary only
    const std::vector<Anchor> all = place_anchors(d.target.patch, d.grid, options);
    ASSERT_EQ(all.size(), d.anchors.size() + 1);
    for (size_t k = 0; k < d.anchors.size(); ++k) {
      EXPECT_EQ(all[k].g, d.anchors[k].g);
      EXPECT_EQ(all[k].h, d.anchors[k].h);
    }
    const Anchor crown = all.back();
    EXPECT_EQ(crown.side, -1);
    EXPECT_FALSE(crown.corner);
    const Crossing& x = crossing(d.grid, crown);
    EXPECT_FALSE(x.on_boundary);
    EXPECT_EQ(crown.position, x.surface_point);
    for (const Crossing& other : d.grid.crossings)  // the highest crossing of the cap
      EXPECT_LE(other.surface_point.z(), x.surface_point.z() + 1e-12);
    EXPECT_NEAR(crown.normal.norm(), 1.0, 1e-9);
    EXPECT_GT(crown.normal.z(), 0.99);
  }
  {
    const Design d = design("double-vault");
    const std::vector<Anchor> two = inner(place_anchors(d.target.patch, d.grid, options));
    ASSERT_EQ(two.size(), 2u);
    EXPECT_GE(crossing(d.grid, two[0]).surface_point.z(),
              crossing(d.grid, two[1]).surface_point.z());
    options.interior = 1;  // the limit is respected, the most prominent kept
    const std::vector<Anchor> one = inner(place_anchors(d.target.patch, d.grid, options));
    ASSERT_EQ(one.size(), 1u);
    EXPECT_EQ(one[0].g, two[0].g);
    EXPECT_EQ(one[0].h, two[0].h);
    options.interior = 10;
  }
  {
    const Design d = design("hypar");
    EXPECT_TRUE(inner(place_anchors(d.target.patch, d.grid, options)).empty());
  }
}

}  // namespace
}  // namespace gridshell
