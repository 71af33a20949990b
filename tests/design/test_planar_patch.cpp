// SPDX-License-Identifier: GPL-3.0-or-later
// Planar patch P̄(ᾱ): four-bar closure, convexity interval, boundary points, planar maps.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "gridshell/design/planar_patch.h"
#include "gridshell/foundation/errors.h"

namespace gridshell {
namespace {

constexpr double kPi = std::numbers::pi;

double cross(const Vec2& a, const Vec2& b) { return a.x() * b.y() - a.y() * b.x(); }

// Random side lengths of some convex quadrilateral: sample a random convex quadrilateral.
std::array<double, 4> random_lengths(std::mt19937& rng) {
  std::uniform_real_distribution<double> angle(0, 2 * kPi), radius(0.3, 3.0);
  for (;;) {
    std::array<double, 4> phi;
    for (double& p : phi) p = angle(rng);
    std::sort(phi.begin(), phi.end());
    std::array<Vec2, 4> c;
    const double r = radius(rng);
    const double sx = radius(rng), sy = radius(rng);
    for (int i = 0; i < 4; ++i) c[i] = Vec2(sx * r * std::cos(phi[i]), sy * std::sin(phi[i]));
    std::array<double, 4> L;
    bool ok = true;
    for (int i = 0; i < 4; ++i) {
      L[i] = (c[(i + 1) % 4] - c[i]).norm();
      if (L[i] < 1e-3) ok = false;
    }
    if (ok) return L;
  }
}

TEST(PlanarPatch, ReproducesSideLengthsAndAngleForRandomQuads) {
  std::mt19937 rng(12345);
  int checked = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const auto L = random_lengths(rng);
    const auto interval = convex_alpha_interval(L);
    ASSERT_LT(interval[0], interval[1]) << "a convex quad with these lengths exists";
    for (int s = 1; s < 10; ++s) {
      const double alpha = interval[0] + (interval[1] - interval[0]) * s / 10.0;
      const auto planar = make_planar_patch(L, alpha);
      ASSERT_TRUE(planar.has_value()) << "alpha " << alpha;
      const auto& c = planar->corners;
      EXPECT_EQ(c[0], Vec2(0, 0));
      EXPECT_EQ(c[1], Vec2(L[0], 0));
      for (int i = 0; i < 4; ++i) {
        EXPECT_NEAR((c[(i + 1) % 4] - c[i]).norm(), L[i], 1e-12 * (1 + L[i])) << "side " << i;
      }
      const auto angles = planar_corner_angles(*planar);
      EXPECT_NEAR(angles[0], alpha, 1e-12);
      double sum = 0;
      for (int i = 0; i < 4; ++i) {
        EXPECT_GT(angles[i], 0);
        EXPECT_LT(angles[i], kPi);
        EXPECT_GT(cross(c[i] - c[(i + 3) % 4], c[(i + 1) % 4] - c[i]), 0) << "ccw turn " << i;
        sum += angles[i];
      }
      EXPECT_NEAR(sum, 2 * kPi, 1e-12);
      ++checked;
    }
  }
  EXPECT_EQ(checked, 300 * 9);
}

TEST(PlanarPatch, IntervalEndsAreSharpAndMatchSampling) {
  std::mt19937 rng(777);
  for (int trial = 0; trial < 200; ++trial) {
    const auto L = random_lengths(rng);
    const auto [lo, hi] = convex_alpha_interval(L);
    ASSERT_LT(lo, hi);
    // Just inside both ends: a configuration; outside (by more than the 1e-12 tolerance): none.
    EXPECT_TRUE(make_planar_patch(L, lo + 1e-12).has_value()) << lo;
    EXPECT_TRUE(make_planar_patch(L, hi - 1e-12).has_value()) << hi;
    EXPECT_FALSE(make_planar_patch(L, lo - 1e-12).has_value()) << lo;
    EXPECT_FALSE(make_planar_patch(L, hi + 1e-12).has_value()) << hi;
    EXPECT_FALSE(make_planar_patch(L, lo - 1e-3).has_value());
    EXPECT_FALSE(make_planar_patch(L, hi + 1e-3).has_value());
    // Brute-force sampling agrees: feasible exactly inside (lo, hi).
    for (int s = 0; s <= 400; ++s) {
      const double alpha = kPi * s / 400.0;
      if (std::abs(alpha - lo) < 1e-9 || std::abs(alpha - hi) < 1e-9) continue;
      EXPECT_EQ(make_planar_patch(L, alpha).has_value(), alpha > lo && alpha < hi)
          << "alpha " << alpha << " interval " << lo << " " << hi;
    }
  }
}

TEST(PlanarPatch, SquareAndRhombi) {
  const std::array<double, 4> L{1, 1, 1, 1};
  const auto [lo, hi] = convex_alpha_interval(L);
  EXPECT_NEAR(lo, 0, 1e-12);
  EXPECT_NEAR(hi, kPi, 1e-12);
  const auto square = make_planar_patch(L, kPi / 2);
  ASSERT_TRUE(square.has_value());
  EXPECT_NEAR((square->corners[2] - Vec2(1, 1)).norm(), 0, 1e-15);
  EXPECT_NEAR((square->corners[3] - Vec2(0, 1)).norm(), 0, 1e-15);
  for (double a : planar_corner_angles(*square)) EXPECT_NEAR(a, kPi / 2, 1e-15);
  // A rhombus at any angle: c2 = c1 + c3.
  for (double alpha : {1e-6, 0.3, 2.0, kPi - 1e-6}) {
    const auto rhombus = make_planar_patch(L, alpha);
    ASSERT_TRUE(rhombus.has_value()) << alpha;
    EXPECT_NEAR((rhombus->corners[2] - (rhombus->corners[1] + rhombus->corners[3])).norm(), 0,
                1e-12);
  }
}

TEST(PlanarPatch, KnownIntervalOfAKite) {
  // Kite L = (1, 1, 2, 2) (c0-c1 = c1-c2 = 1, c2-c3 = c3-c0 = 2): the convex configurations
  // end where the angle at c1 reaches pi (c0,c1,c2 collinear, |c0c2| = 2, so the triangle
  // c0c2c3 is equilateral and ᾱ = pi/3) and where the angle at c0 reaches pi... the linkage
  // closes for all ᾱ, and β1 < pi needs |c0c2| < 2 i.e. ᾱ > pi/3 (the kite is symmetric about
  // c1c3, angle at c0 = angle at c2 and β1 decreases with ᾱ).
  const std::array<double, 4> L{1, 1, 2, 2};
  const auto [lo, hi] = convex_alpha_interval(L);
  EXPECT_NEAR(lo, kPi / 3, 1e-12);
  EXPECT_NEAR(hi, kPi, 1e-12);
}

TEST(PlanarPatch, NoConvexQuadrilateral) {
  // One side longer than the other three together: the linkage never closes.
  EXPECT_EQ(convex_alpha_interval({1, 1, 1, 3.5}), (std::array<double, 2>{0, 0}));
  EXPECT_FALSE(make_planar_patch({1, 1, 1, 3.5}, 1.0).has_value());
  // Outside (0, pi) is never convex.
  EXPECT_FALSE(make_planar_patch({1, 1, 1, 1}, 0.0).has_value());
  EXPECT_FALSE(make_planar_patch({1, 1, 1, 1}, kPi).has_value());
  EXPECT_FALSE(make_planar_patch({1, 1, 1, 1}, -1.0).has_value());
  EXPECT_FALSE(make_planar_patch({1, 1, 1, 1}, std::nan("")).has_value());
  EXPECT_THROW(make_planar_patch({1, 0, 1, 1}, 1.0), InvalidInput);
  EXPECT_THROW(convex_alpha_interval({1, 1, -1, 1}), InvalidInput);
}

TEST(PlanarPatch, BoundaryPointConventions) {
  const std::array<double, 4> L{3, 2.5, 2, 2.2};
  const auto planar = make_planar_patch(L, 1.4);
  ASSERT_TRUE(planar.has_value());
  const auto& c = planar->corners;
  EXPECT_EQ(planar_boundary_point(*planar, Family::G, 0, 0), c[0]);
  EXPECT_EQ(planar_boundary_point(*planar, Family::G, 0, 1), c[1]);
  EXPECT_EQ(planar_boundary_point(*planar, Family::G, 1, 0), c[3]);
  EXPECT_EQ(planar_boundary_point(*planar, Family::G, 1, 1), c[2]);
  EXPECT_EQ(planar_boundary_point(*planar, Family::H, 0, 0), c[1]);
  EXPECT_EQ(planar_boundary_point(*planar, Family::H, 0, 1), c[2]);
  EXPECT_EQ(planar_boundary_point(*planar, Family::H, 1, 0), c[0]);
  EXPECT_EQ(planar_boundary_point(*planar, Family::H, 1, 1), c[3]);
  // t is the fraction of length from the first-named corner.
  const Vec2 p = planar_boundary_point(*planar, Family::H, 0, 0.25);
  EXPECT_NEAR((p - c[1]).norm(), 0.25 * L[1], 1e-14);
  EXPECT_NEAR((p - c[2]).norm(), 0.75 * L[1], 1e-14);
  EXPECT_THROW(planar_boundary_point(*planar, Family::G, 0, 1.5), InvalidInput);
  EXPECT_THROW(planar_boundary_point(*planar, Family::G, 2, 0.5), InvalidInput);
}

TEST(PlanarPatch, DistanceMapCornersAreSidesAndDiagonals) {
  const std::array<double, 4> L{3, 2.5, 2, 2.2};
  const auto planar = make_planar_patch(L, 1.4);
  ASSERT_TRUE(planar.has_value());
  const auto& c = planar->corners;
  const double e = (c[2] - c[0]).norm(), f = (c[3] - c[1]).norm();
  const int R = 37;
  const Eigen::MatrixXd G = planar_distance_map(*planar, Family::G, R);
  const Eigen::MatrixXd H = planar_distance_map(*planar, Family::H, R);
  ASSERT_EQ(G.rows(), R);
  ASSERT_EQ(G.cols(), R);
  EXPECT_NEAR(G(0, 0), L[3], 1e-14);
  EXPECT_NEAR(G(R - 1, R - 1), L[1], 1e-14);
  EXPECT_NEAR(G(0, R - 1), e, 1e-14);  // c0 to c2
  EXPECT_NEAR(G(R - 1, 0), f, 1e-14);  // c1 to c3
  EXPECT_NEAR(H(0, 0), L[0], 1e-14);
  EXPECT_NEAR(H(R - 1, R - 1), L[2], 1e-14);
  EXPECT_NEAR(H(0, R - 1), f, 1e-14);  // c1 to c3
  EXPECT_NEAR(H(R - 1, 0), e, 1e-14);  // c2 to c0
  // Interior entries: distance between the boundary points at u1 = i/(R-1), u2 = j/(R-1).
  for (int i = 0; i < R; i += 5) {
    for (int j = 0; j < R; j += 7) {
      const double u1 = double(i) / (R - 1), u2 = double(j) / (R - 1);
      const Vec2 p = c[0] + u1 * (c[1] - c[0]), q = c[3] + u2 * (c[2] - c[3]);
      EXPECT_NEAR(G(i, j), (p - q).norm(), 1e-13);
    }
  }
  EXPECT_THROW(planar_distance_map(*planar, Family::G, 1), InvalidInput);
}

}  // namespace
}  // namespace gridshell
