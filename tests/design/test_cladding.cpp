// SPDX-License-Identifier: GPL-3.0-or-later
// Cladding functions and the feasible planar angle (paper Section 4.3): zero-set extraction on
// synthetic maps with analytically known zero sets (graph accuracy, slope bounds, leaving the
// square, branching, corners), the diagonal condition on flat patches, the feasible range on
// flat patches and on the paper's seven examples, and the Infeasible diagnostics.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <numbers>
#include <regex>
#include <string>
#include <vector>

#include "gridshell/design/cladding.h"
#include "gridshell/design/patch.h"
#include "gridshell/design/planar_patch.h"
#include "gridshell/example_surfaces.h"
#include "gridshell/foundation/errors.h"
#include "gridshell/geodesic/geodesic.h"
#include "support.h"

namespace gridshell {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kBase = 10.0;  // D̄ ≡ kBase in the synthetic tests, D = kBase + Δ

using Field = std::function<double(double u1, double u2)>;

Eigen::MatrixXd sample(int R, const Field& f) {
  Eigen::MatrixXd m(R, R);
  for (int i = 0; i < R; ++i)
    for (int j = 0; j < R; ++j)
      m(i, j) = f(static_cast<double>(i) / (R - 1), static_cast<double>(j) / (R - 1));
  return m;
}

/// F for the synthetic difference Δ: D = kBase + Δ against D̄ = kBase.
CladdingFunction synthetic(int R, const Field& delta, Family family = Family::G,
                           const CladdingOptions& options = {}) {
  const Eigen::MatrixXd surface =
      sample(R, [&](double a, double b) { return kBase + delta(a, b); });
  const Eigen::MatrixXd planar = Eigen::MatrixXd::Constant(R, R, kBase);
  return cladding_function(surface, planar, family, 1.0, options);
}

/// The first "(x,y)=(a,b)" location in a problem string.
Vec2 location(const std::string& problem) {
  static const std::regex pattern(R"(\)=\((-?[0-9.]+),(-?[0-9.]+)\))");
  std::smatch match;
  if (!std::regex_search(problem, match, pattern)) {
    ADD_FAILURE() << "no location in: " << problem;
    return Vec2::Constant(NAN);
  }
  return Vec2(std::stod(match[1]), std::stod(match[2]));
}

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

// g(u) = (e^{2u} - 1)/(e^2 - 1): monotone, g(0)=0, g(1)=1, slopes in [0.31, 2.31].
double g_exp(double u) { return std::expm1(2 * u) / std::expm1(2.0); }
constexpr double kGExpSecond = 4 * 7.38905609893065 / 6.38905609893065;  // max |g''| = 4e^2/(e^2-1)

// g(u) = u - a/(2π) [sin(2π(u - 0.3)) - sin(-0.6π)]: g(0)=0, g(1)=1, g' = 1 - a cos(2π(u-0.3)),
// minimal slope 1-a at u = 0.3, maximal 1+a at u = 0.8.
double g_dip(double u, double a) {
  return u - a / (2 * kPi) * (std::sin(2 * kPi * (u - 0.3)) - std::sin(-0.6 * kPi));
}

// ---------------------------------------------------------------------------------------------
// Zero-set extraction on synthetic maps.

TEST(CladdingFunction, MonotoneZeroSetMatchesTheGraphToGridAccuracy) {
  for (const int R : {9, 33, 100, 161}) {
    const double h = 1.0 / (R - 1);
    const CladdingFunction F = synthetic(R, [](double a, double b) { return 3 * (b - g_exp(a)); });
    ASSERT_TRUE(F.valid) << R << ": " << F.problem;
    EXPECT_TRUE(F.problem.empty());
    EXPECT_EQ(F.family, Family::G);
    ASSERT_GE(F.points.size(), static_cast<size_t>(R));
    EXPECT_EQ(F.points.front(), Vec2(0, 0));
    EXPECT_EQ(F.points.back(), Vec2(1, 1));
    // Linear interpolation along a cell edge: |u2 - g(u1)| <= h^2 max|g''| / 8 at every point.
    double worst = 0;
    for (size_t k = 0; k < F.points.size(); ++k) {
      const Vec2& p = F.points[k];
      worst = std::max(worst, std::abs(p.y() - g_exp(p.x())));
      if (k > 0) {
        EXPECT_GT(p.x(), F.points[k - 1].x()) << k;
        EXPECT_GT(p.y(), F.points[k - 1].y()) << k;
      }
    }
    EXPECT_LE(worst, h * h * kGExpSecond / 8 + 1e-14) << "R " << R;
    EXPECT_GT(worst, 0.01 * h * h * kGExpSecond / 8) << "the bound is not vacuous";
  }
}

TEST(CladdingFunction, ZeroSetThroughGridVerticesIsTheExactDiagonal) {
  // Δ = u2 - u1 vanishes exactly at the vertices (i,i): zeros count as positive, the path runs
  // through the vertices without repeated points.
  const int R = 41;
  const CladdingFunction F = synthetic(R, [](double a, double b) { return 5 * (b - a); });
  ASSERT_TRUE(F.valid) << F.problem;
  ASSERT_EQ(F.points.size(), static_cast<size_t>(R));
  for (int k = 0; k < R; ++k) {
    EXPECT_EQ(F.points[k],
              Vec2(static_cast<double>(k) / (R - 1), static_cast<double>(k) / (R - 1)));
  }
}

TEST(CladdingFunction, RoundingNoiseAlongAZeroDiagonalIsIgnored) {
  // Like a rectangle against a parallelogram: Δ = 0 on the diagonal up to rounding noise.
  const int R = 50;
  const CladdingFunction F = synthetic(R, [](double a, double b) {
    const double noise = 3e-15 * std::sin(1e4 * a + 7e3 * b);
    return 2 * (b - a) + noise;
  });
  ASSERT_TRUE(F.valid) << F.problem;
  for (const Vec2& p : F.points) EXPECT_NEAR(p.y(), p.x(), 1e-12);
}

TEST(CladdingFunction, ShallowSlopeIsInvalidWhereItHappens) {
  const double a = 0.97;  // minimal slope 0.03 at u1 = 0.3
  const CladdingFunction F =
      synthetic(100, [a](double u1, double u2) { return 4 * (u2 - g_dip(u1, a)); });
  EXPECT_FALSE(F.valid);
  EXPECT_TRUE(contains(F.problem, "F_u slope ")) << F.problem;
  EXPECT_TRUE(contains(F.problem, "< k_min 0.1 at (u1,u2)=")) << F.problem;
  const Vec2 at = location(F.problem);
  EXPECT_NEAR(at.x(), 0.3, 0.03) << F.problem;
  EXPECT_NEAR(at.y(), g_dip(0.3, a), 0.03) << F.problem;
  // The curve itself still connects the corners.
  ASSERT_FALSE(F.points.empty());
  EXPECT_EQ(F.points.back(), Vec2(1, 1));

  // The same curve with a looser bound is fine.
  const CladdingFunction loose =
      synthetic(100, [a](double u1, double u2) { return 4 * (u2 - g_dip(u1, a)); }, Family::G,
                {.k_min = 0.01});
  EXPECT_TRUE(loose.valid) << loose.problem;
}

TEST(CladdingFunction, SteepSlopeIsInvalidWhereItHappens) {
  // Family H, v1 = g(v2): slope dv2/dv1 = 1/g' up to 1/0.04 = 25 at v2 = 0.3.
  const double a = 0.96;
  const CladdingFunction F = synthetic(
      100, [a](double v1, double v2) { return 2 * (g_dip(v2, a) - v1); }, Family::H);
  EXPECT_FALSE(F.valid);
  EXPECT_EQ(F.family, Family::H);
  EXPECT_TRUE(contains(F.problem, "F_v slope ")) << F.problem;
  EXPECT_TRUE(contains(F.problem, "> k_max 10 at (v1,v2)=")) << F.problem;
  const Vec2 at = location(F.problem);
  EXPECT_NEAR(at.x(), g_dip(0.3, a), 0.03) << F.problem;
  EXPECT_NEAR(at.y(), 0.3, 0.03) << F.problem;
}

TEST(CladdingFunction, DecreasingAndBackwardsCurvesAreInvalid) {
  // u2 = u1 + 0.3 sin(2π u1) decreases for u1 in about (0.32, 0.68).
  const CladdingFunction down =
      synthetic(80, [](double u1, double u2) { return u2 - u1 - 0.3 * std::sin(2 * kPi * u1); });
  EXPECT_FALSE(down.valid);
  EXPECT_TRUE(contains(down.problem, "F_u slope -")) << down.problem;
  const Vec2 at = location(down.problem);
  EXPECT_GT(at.x(), 0.3);
  EXPECT_LT(at.x(), 0.7);

  // u1 = u2 + 0.3 sin(2π u2): the curve turns back in u1.
  const CladdingFunction back =
      synthetic(80, [](double u1, double u2) { return u1 - u2 - 0.3 * std::sin(2 * kPi * u2); });
  EXPECT_FALSE(back.valid);
  EXPECT_TRUE(contains(back.problem, "F_u runs backwards (u1 decreases)")) << back.problem;
  EXPECT_GT(location(back.problem).y(), 0.3);
  EXPECT_LT(location(back.problem).y(), 0.7);
}

TEST(CladdingFunction, ZeroSetLeavingThroughASideIsInvalid) {
  // Zero set: the line u2 = 0.43 u1 (leaves through u1 = 1 at u2 = 0.43) and the isolated corner
  // (1,1) of u1 + u2 = 2.
  const CladdingFunction F =
      synthetic(101, [](double u1, double u2) { return (u2 - 0.43 * u1) * (u1 + u2 - 2); });
  EXPECT_FALSE(F.valid);
  EXPECT_TRUE(F.points.empty());
  EXPECT_TRUE(contains(F.problem, "F_u leaves the domain at (u1,u2)=(1.00,0.43)")) << F.problem;

  // Through the top side u2 = 1 at u1 = 0.5 (the zero curve u2 = 2 u1).
  const CladdingFunction top = synthetic(
      64, [](double u1, double u2) { return (u2 - 2 * u1) * (u1 + u2 - 2); }, Family::H);
  EXPECT_FALSE(top.valid);
  EXPECT_TRUE(contains(top.problem, "F_v leaves the domain at (v1,v2)=(0.50,1.00)")) << top.problem;
}

TEST(CladdingFunction, CrossingZeroCurvesAreABranch) {
  // u2 = a u1 through (0,0) and u2 = 1 + b (u1 - 1) through (1,1) cross at (0.635, 0.275),
  // the centre of a grid cell: a monotone path exists either way, but the zero set branches.
  const double a = 0.275 / 0.635, b = 0.725 / 0.365;
  const CladdingFunction F = synthetic(
      101, [a, b](double u1, double u2) { return (u2 - a * u1) * (u2 - 1 - b * (u1 - 1)); });
  EXPECT_FALSE(F.valid);
  EXPECT_TRUE(contains(F.problem, "F_u branches at (u1,u2)=")) << F.problem;
  const Vec2 at = location(F.problem);
  // The two lines stay within a cell of each other for a few cells around the crossing.
  EXPECT_NEAR(at.x(), 0.635, 0.025) << F.problem;
  EXPECT_NEAR(at.y(), 0.275, 0.025) << F.problem;
}

TEST(CladdingFunction, NoCurveEntersWhenTheDifferenceKeepsItsSign) {
  // Δ = (u2 - u1)^2 >= 0 touches zero on the diagonal without changing sign.
  const CladdingFunction F =
      synthetic(30, [](double u1, double u2) { return (u2 - u1) * (u2 - u1); });
  EXPECT_FALSE(F.valid);
  EXPECT_TRUE(F.points.empty());
  EXPECT_TRUE(contains(F.problem, "F_u does not enter the square at (u1,u2)=(0.00,0.00)"))
      << F.problem;
  // Same with Δ <= 0.
  const CladdingFunction G =
      synthetic(30, [](double u1, double u2) { return -(u2 - u1) * (u2 - u1); });
  EXPECT_FALSE(G.valid);
  EXPECT_TRUE(contains(G.problem, "does not enter")) << G.problem;
}

TEST(CladdingFunction, CornersAreZerosUpToRounding) {
  const int R = 60;
  const auto delta = [](double a, double b) { return 3 * (b - g_exp(a)); };
  const CladdingFunction exact = synthetic(R, delta);
  ASSERT_TRUE(exact.valid) << exact.problem;
  for (const double eps : {1e-13, -1e-12, 1e-10}) {
    Eigen::MatrixXd surface = sample(R, [&](double a, double b) { return kBase + delta(a, b); });
    surface(0, 0) += eps * kBase;
    surface(R - 1, R - 1) -= eps * kBase;
    const CladdingFunction F =
        cladding_function(surface, Eigen::MatrixXd::Constant(R, R, kBase), Family::G, 1.0);
    ASSERT_TRUE(F.valid) << eps << ": " << F.problem;
    ASSERT_EQ(F.points.size(), exact.points.size());
    EXPECT_EQ(F.points.front(), Vec2(0, 0));
    EXPECT_EQ(F.points.back(), Vec2(1, 1));
    for (size_t k = 0; k < F.points.size(); ++k) EXPECT_EQ(F.points[k], exact.points[k]);
  }
  // A real length difference at a corner is not rounding.
  Eigen::MatrixXd surface = sample(R, [&](double a, double b) { return kBase + delta(a, b); });
  surface(R - 1, R - 1) += 1e-3 * kBase;
  const CladdingFunction F =
      cladding_function(surface, Eigen::MatrixXd::Constant(R, R, kBase), Family::G, 1.0);
  EXPECT_FALSE(F.valid);
  EXPECT_TRUE(contains(F.problem, "at (u1,u2)=(1.00,1.00) is not zero")) << F.problem;
}

TEST(CladdingFunction, VerticalSegmentsGetThePapersSlope) {
  // Zero set u1 = H(u2) with a vertical piece u1 = 0.5 for u2 in [0.25, 0.75] running along grid
  // vertices (R = 101, h = 0.01). Its segments are one cell long: slope c·Δu2 = 1000 · 0.01 = 10,
  // which is not < k_max = 10.
  const auto H = [](double v) { return v < 0.25 ? 2 * v : v < 0.75 ? 0.5 : 0.5 + 2 * (v - 0.75); };
  const auto delta = [&](double u1, double u2) { return u1 - H(u2); };
  const CladdingFunction F = synthetic(101, delta);
  EXPECT_FALSE(F.valid);
  // Δu2 = 0.01 up to rounding, so the slope is 10 or a rounding step above ("=" or ">").
  EXPECT_TRUE(contains(F.problem, "F_u slope 10 (vertical segment) ")) << F.problem;
  EXPECT_TRUE(contains(F.problem, " k_max 10 at (u1,u2)=")) << F.problem;
  EXPECT_NEAR(location(F.problem).x(), 0.5, 1e-9);
  ASSERT_FALSE(F.points.empty());
  EXPECT_EQ(F.points.back(), Vec2(1, 1));
  // With c = 500 the same segments have slope 5: valid (the paper's rule).
  EXPECT_TRUE(synthetic(101, delta, Family::G, {.vertical_c = 500}).valid);
}

TEST(CladdingFunction, RejectsMalformedInput) {
  const Eigen::MatrixXd a = Eigen::MatrixXd::Constant(10, 10, 1.0);
  EXPECT_THROW(cladding_function(a, Eigen::MatrixXd::Constant(9, 9, 1.0), Family::G, 1),
               InvalidInput);
  EXPECT_THROW(cladding_function(Eigen::MatrixXd::Constant(1, 1, 1.0),
                                 Eigen::MatrixXd::Constant(1, 1, 1.0), Family::G, 1),
               InvalidInput);
  EXPECT_THROW(cladding_function(Eigen::MatrixXd::Constant(10, 9, 1.0),
                                 Eigen::MatrixXd::Constant(10, 9, 1.0), Family::G, 1),
               InvalidInput);
  Eigen::MatrixXd nan = a;
  nan(3, 4) = NAN;
  EXPECT_THROW(cladding_function(nan, a, Family::G, 1), InvalidInput);
  EXPECT_THROW(cladding_function(a, a, Family::G, 1, {.k_min = 2, .k_max = 1}), InvalidInput);
  EXPECT_THROW(cladding_function(a, a, Family::G, 1, {.k_min = 0}), InvalidInput);
  EXPECT_THROW(cladding_function(a, a, Family::G, 1, {.vertical_c = -1}), InvalidInput);
}

// ---------------------------------------------------------------------------------------------
// Flat patches: the surface maps are the Euclidean maps of a convex planar quadrilateral Q.

const std::array<double, 4> kFlatLengths{10.0, 7.0, 8.5, 6.0};
constexpr double kFlatAlpha = 1.3;

DistanceMaps flat_maps(int R, const std::array<double, 4>& lengths = kFlatLengths,
                       double alpha = kFlatAlpha) {
  const auto Q = make_planar_patch(lengths, alpha);
  EXPECT_TRUE(Q.has_value());
  DistanceMaps maps;
  maps.g = {Family::G, planar_distance_map(*Q, Family::G, R)};
  maps.h = {Family::H, planar_distance_map(*Q, Family::H, R)};
  return maps;
}

TEST(DiagonalCondition, OnAFlatPatchHoldsForEveryAngleButItsOwn) {
  // In the four-bar linkage with fixed sides, opening ᾱ lengthens f̄ = |c1c3| and shortens
  // ē = |c0c2| (the angles at c1 and c3 decrease). With e, f the diagonals of Q (ᾱ = α0), the
  // factors e - ē and f - f̄ therefore have opposite signs for every ᾱ != α0, and the product is
  // exactly 0 at α0.
  const DistanceMaps maps = flat_maps(20);
  const auto Q = make_planar_patch(kFlatLengths, kFlatAlpha);
  EXPECT_FALSE(diagonal_condition(maps, *Q));
  const int n = 19;
  const double e = maps.g.distances(0, n), f = maps.g.distances(n, 0);
  EXPECT_NEAR(e, (Q->corners[2] - Q->corners[0]).norm(), 1e-12);
  EXPECT_NEAR(f, (Q->corners[3] - Q->corners[1]).norm(), 1e-12);
  const auto interval = convex_alpha_interval(kFlatLengths);
  int checked = 0;
  for (int k = 1; k < 100; ++k) {
    const double alpha = interval[0] + (interval[1] - interval[0]) * k / 100;
    if (std::abs(alpha - kFlatAlpha) < 1e-9) continue;
    const auto P = make_planar_patch(kFlatLengths, alpha);
    ASSERT_TRUE(P.has_value());
    const double e_bar = (P->corners[2] - P->corners[0]).norm();
    const double f_bar = (P->corners[3] - P->corners[1]).norm();
    if (alpha > kFlatAlpha) {
      EXPECT_GT(e, e_bar) << alpha;
      EXPECT_LT(f, f_bar) << alpha;
    } else {
      EXPECT_LT(e, e_bar) << alpha;
      EXPECT_GT(f, f_bar) << alpha;
    }
    EXPECT_TRUE(diagonal_condition(maps, *P)) << alpha;
    ++checked;
  }
  EXPECT_EQ(checked, 99);
}

TEST(DiagonalCondition, FailsWhenBothSurfaceDiagonalsAreLonger) {
  DistanceMaps maps = flat_maps(20);
  maps.g.distances(0, 19) = 100;  // e
  maps.g.distances(19, 0) = 100;  // f
  const auto interval = convex_alpha_interval(kFlatLengths);
  for (int k = 1; k < 20; ++k) {
    const auto P =
        make_planar_patch(kFlatLengths, interval[0] + (interval[1] - interval[0]) * k / 20);
    EXPECT_FALSE(diagonal_condition(maps, *P));
  }
}

TEST(FeasibleAlphaRange, FlatPatch) {
  const int R = 60;
  const DistanceMaps maps = flat_maps(R);
  // At α0 itself D = D̄ everywhere: no zero curve, no diagonal condition.
  const auto Q = make_planar_patch(kFlatLengths, kFlatAlpha);
  EXPECT_FALSE(cladding_function(maps.g.distances, planar_distance_map(*Q, Family::G, R), Family::G,
                                 kFlatAlpha)
                   .valid);
  const auto interval = convex_alpha_interval(kFlatLengths);
  const AlphaRange range = feasible_alpha_range(maps, kFlatLengths);
  EXPECT_GT(range.min, interval[0]);
  EXPECT_LT(range.max, interval[1]);
  EXPECT_LT(range.min, range.max);
  // Near α0 the zero set tends to that of ∂D̄/∂ᾱ: F exists on both sides of the flat angle.
  EXPECT_LT(range.min, kFlatAlpha - 0.05);
  EXPECT_GT(range.max, kFlatAlpha + 0.05);
  for (const double alpha : {range.min, 0.5 * (range.min + range.max), range.max, kFlatAlpha - 0.01,
                             kFlatAlpha + 0.01}) {
    const auto P = make_planar_patch(kFlatLengths, alpha);
    ASSERT_TRUE(P.has_value());
    EXPECT_TRUE(diagonal_condition(maps, *P)) << alpha;
    for (const Family family : {Family::G, Family::H}) {
      const DistanceMap& map = family == Family::G ? maps.g : maps.h;
      const CladdingFunction F =
          cladding_function(map.distances, planar_distance_map(*P, family, R), family, alpha);
      EXPECT_TRUE(F.valid) << alpha << ": " << F.problem;
      EXPECT_EQ(F.alpha_bar, alpha);
    }
  }
  RecordProperty("range", std::to_string(range.min) + " " + std::to_string(range.max));
}

TEST(FeasibleAlphaRange, RectangleAgainstParallelograms) {
  // A rectangle: for every ᾱ the planar patch is a parallelogram and the members with u1 = u2
  // are translates of a side, so F_u and F_v are the diagonal u2 = u1 (up to rounding) for every
  // ᾱ but π/2, where D = D̄ and nothing is feasible. With the paper's bare convexity bound the
  // feasible set is (0, π/2) ∪ (π/2, π); π/2 is a sample, so there are two equally long runs
  // and the tie goes to the smaller ᾱ.
  const std::array<double, 4> lengths{10, 6, 10, 6};
  const DistanceMaps maps = flat_maps(40, lengths, kPi / 2);
  const AlphaRange range = feasible_alpha_range(maps, lengths, {.min_planar_angle = 0});
  EXPECT_LT(range.min, 1e-5);
  EXPECT_LT(range.max, kPi / 2);
  EXPECT_GT(range.max, kPi / 2 - 1e-5);
  for (const double alpha : {1.0, 2.0}) {
    const auto P = make_planar_patch(lengths, alpha);
    const CladdingFunction F = cladding_function(
        maps.g.distances, planar_distance_map(*P, Family::G, 40), Family::G, alpha);
    ASSERT_TRUE(F.valid) << F.problem;
    for (const Vec2& p : F.points) EXPECT_NEAR(p.x(), p.y(), 1e-9);
  }
}

TEST(FeasibleAlphaRange, PlanarAngleBoundKeepsTheLinkageOpen) {
  // The same rectangle with the default bound: every planar angle in [30°, 150°], so for the
  // parallelogram ᾱ in [π/6, 5π/6]; the cladding criteria hold right up to the bound.
  const std::array<double, 4> lengths{10, 6, 10, 6};
  const DistanceMaps maps = flat_maps(40, lengths, kPi / 2);
  const CladdingOptions options;
  EXPECT_NEAR(options.min_planar_angle, kPi / 6, 1e-15);
  const AlphaRange range = feasible_alpha_range(maps, lengths, options);
  EXPECT_NEAR(range.min, kPi / 6, 1e-9);
  EXPECT_GT(range.max, kPi / 2 - 1e-5);
  const auto P = make_planar_patch(lengths, range.min);
  ASSERT_TRUE(P.has_value());
  for (const double angle : planar_corner_angles(*P)) {
    EXPECT_GE(angle, kPi / 6 - 1e-9);
    EXPECT_LE(angle, 5 * kPi / 6 + 1e-9);
  }
  // A tighter bound narrows the range; an impossible one is Infeasible naming the option.
  const AlphaRange tight = feasible_alpha_range(maps, lengths, {.min_planar_angle = 1.2});
  EXPECT_NEAR(tight.min, 1.2, 1e-9);
  EXPECT_LT(tight.max, kPi / 2);
  const std::array<double, 4> trapezoid{10, 4, 5, 4};
  try {
    feasible_alpha_range(flat_maps(20, trapezoid, 0.9), trapezoid, {.min_planar_angle = 1.4});
    FAIL() << "expected Infeasible";
  } catch (const Infeasible& error) {
    EXPECT_TRUE(contains(error.what(), "min_planar_angle")) << error.what();
  }
}

TEST(FeasibleAlphaRange, InfeasibleDiagonalsNameTheCondition) {
  DistanceMaps maps = flat_maps(30);
  maps.g.distances(0, 29) = 100;
  maps.g.distances(29, 0) = 100;
  try {
    feasible_alpha_range(maps, kFlatLengths);
    FAIL() << "expected Infeasible";
  } catch (const Infeasible& error) {
    const std::string message = error.what();
    EXPECT_TRUE(contains(message, "diagonal condition")) << message;
    EXPECT_TRUE(contains(message, "fails for every")) << message;
    EXPECT_TRUE(contains(message, "e = d(c0,c2) = 100")) << message;
  }
}

TEST(FeasibleAlphaRange, InfeasibleCladdingNamesTheFunction) {
  // A high ridge along the diagonal of D_u (zero on the square's boundary, so e, f and the corners
  // are unchanged) pushes the zero set of D_u - D̄_u against the boundary for every ᾱ.
  const int R = 40;
  DistanceMaps maps = flat_maps(R);
  for (int i = 0; i < R; ++i)
    for (int j = 0; j < R; ++j) {
      const double u1 = static_cast<double>(i) / (R - 1), u2 = static_cast<double>(j) / (R - 1);
      maps.g.distances(i, j) += 50 * std::sin(kPi * u1) * std::sin(kPi * u2);
    }
  try {
    feasible_alpha_range(maps, kFlatLengths);
    FAIL() << "expected Infeasible";
  } catch (const Infeasible& error) {
    const std::string message = error.what();
    EXPECT_TRUE(contains(message, "no feasible planar angle")) << message;
    EXPECT_TRUE(contains(message, "closest at ᾱ =")) << message;
    EXPECT_TRUE(contains(message, "F_u ")) << message;
    EXPECT_FALSE(contains(message, "F_v ")) << message;
  }
}

TEST(FeasibleAlphaRange, NoConvexQuadrilateral) {
  const std::array<double, 4> lengths{10, 1, 1, 1};
  const DistanceMaps maps = flat_maps(10);  // any maps
  try {
    feasible_alpha_range(maps, lengths);
    FAIL() << "expected Infeasible";
  } catch (const Infeasible& error) {
    EXPECT_TRUE(contains(error.what(), "no convex planar quadrilateral")) << error.what();
  }
}

TEST(FeasibleAlphaRange, ReportsProgressAndCancels) {
  const DistanceMaps maps = flat_maps(30);
  std::vector<double> fractions;
  const Progress progress([&](std::string_view stage, double fraction) {
    EXPECT_EQ(stage, "cladding: feasible angle");
    fractions.push_back(fraction);
  });
  feasible_alpha_range(maps, kFlatLengths, {}, progress);
  ASSERT_GE(fractions.size(), 3u);
  EXPECT_EQ(fractions.front(), 0.0);
  EXPECT_EQ(fractions.back(), 1.0);
  for (size_t k = 1; k < fractions.size(); ++k) EXPECT_GE(fractions[k], fractions[k - 1]);

  std::atomic<bool> cancel{false};
  int calls = 0;
  const Progress cancelling(
      [&](std::string_view, double) {
        if (++calls == 3) cancel = true;
      },
      &cancel);
  EXPECT_THROW(feasible_alpha_range(maps, kFlatLengths, {}, cancelling), Cancelled);
}

TEST(FeasibleAlphaRange, RejectsMalformedInput) {
  DistanceMaps maps = flat_maps(10);
  EXPECT_THROW(feasible_alpha_range(maps, kFlatLengths, {.k_min = -1}), InvalidInput);
  EXPECT_THROW(feasible_alpha_range(maps, kFlatLengths, {.min_planar_angle = -0.1}), InvalidInput);
  EXPECT_THROW(feasible_alpha_range(maps, kFlatLengths, {.min_planar_angle = kPi / 2}),
               InvalidInput);
  EXPECT_THROW(feasible_alpha_range(maps, {10, 7, -1, 6}), InvalidInput);
  maps.h.distances.resize(1, 1);
  EXPECT_THROW(feasible_alpha_range(maps, kFlatLengths), InvalidInput);
}

// ---------------------------------------------------------------------------------------------
// The paper's seven examples with surface maps from exact geodesics. Coarse meshes and maps keep
// the binary fast; the ranges and timings at the default settings are in the final report.

struct ExampleMaps {
  Patch patch;
  DistanceMaps maps;
  int R = 0;
};

ExampleMaps maps_of(const TriangleMesh& mesh, const std::array<int, 4>& corner_vertices, int R) {
  std::array<SurfacePoint, 4> corners;
  for (int i = 0; i < 4; ++i) corners[i] = SurfacePoint::at_vertex(mesh, corner_vertices[i]);
  ExampleMaps result;
  result.patch = cut_patch(mesh, corners);
  const GeodesicSolver solver(result.patch.mesh);
  result.maps = compute_distance_maps(result.patch, solver, {.resolution = R});
  result.R = R;
  return result;
}

ExampleMaps example_maps(const std::string& name, int R) {
  const ExampleSurface example = make_example(name, 0.5);
  std::array<SurfacePoint, 4> corners;
  for (int i = 0; i < 4; ++i)
    corners[i] = SurfacePoint::at_vertex(example.mesh, example.corners[i]);
  ExampleMaps result;
  result.patch = cut_patch(example.mesh, corners);
  const GeodesicSolver solver(result.patch.mesh);
  result.maps = compute_distance_maps(result.patch, solver, {.resolution = R});
  result.R = R;
  return result;
}

class PaperExample : public ::testing::TestWithParam<std::string> {};

TEST_P(PaperExample, HasAFeasibleRangeWithValidCladding) {
  const int R = 40;
  const ExampleMaps example = example_maps(GetParam(), R);
  const DistanceMaps& maps = example.maps;
  const auto lengths = side_lengths(example.patch);
  const auto interval = convex_alpha_interval(lengths);

  const auto start = std::chrono::steady_clock::now();
  const AlphaRange range = feasible_alpha_range(maps, lengths);
  const double ms =
      1e3 * std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_LT(range.min, range.max);
  EXPECT_GT(range.min, interval[0]);
  EXPECT_LT(range.max, interval[1]);
  for (const double alpha : {range.min, 0.5 * (range.min + range.max), range.max}) {
    const auto P = make_planar_patch(lengths, alpha);
    ASSERT_TRUE(P.has_value()) << alpha;
    EXPECT_TRUE(diagonal_condition(maps, *P)) << alpha;
    for (const double angle : planar_corner_angles(*P)) EXPECT_GE(angle, kPi / 6 - 1e-9);
    for (const Family family : {Family::G, Family::H}) {
      const DistanceMap& map = family == Family::G ? maps.g : maps.h;
      const CladdingFunction F =
          cladding_function(map.distances, planar_distance_map(*P, family, R), family, alpha);
      EXPECT_TRUE(F.valid) << GetParam() << " at " << alpha << ": " << F.problem;
    }
  }
  char text[160];
  std::snprintf(text, sizeof text, "alpha %.4f convex (%.4f, %.4f) range [%.4f, %.4f] %.2f ms",
                corner_angles(example.patch)[0], interval[0], interval[1], range.min, range.max,
                ms);
  RecordProperty("range", text);
}

INSTANTIATE_TEST_SUITE_P(Examples, PaperExample,
                         ::testing::Values("torus-wide", "waves-bump", "sphere", "double-vault",
                                           "waves", "archway", "triple-vault"),
                         [](const auto& info) {
                           std::string name = info.param;
                           for (char& c : name)
                             if (c == '-') c = '_';
                           return name;
                         });

// A tight torus strip (major radius 2.25, tube radius 1, theta in [-0.58, 0.58], phi in
// [0.1, pi - 0.1]): the first torus-wide generator, whose design is genuinely infeasible.
TEST(TightTorusStrip, IsInfeasibleBecauseOfItsCornerAngles) {
  // Near the corner (0,0) of F_u, D - D̄ ≈ u1 L0 (cos ᾱ0 - cos α0) + u2 L2 (cos ᾱ3 - cos α3) (ᾱk,
  // αk the planar and surface angles at ck), so F_u can only enter the square if ᾱ0 - α0 and
  // ᾱ3 - α3 have opposite signs; likewise F_u at (1,1) for c1, c2 and F_v at its corners for
  // (c1, c0) and (c2, c3). The torus-wide patch (inner side 41, outer side 106, meridians 86) has
  // surface angles of about 90° at the inner corners c0, c1 and 84° at the outer corners c2, c3,
  // but the planar angles at c2 and c3 never exceed 82° for any ᾱ: both are always smaller
  // than on the surface, F_v cannot reach (1,1), no ᾱ can work, and feasible_alpha_range must
  // say so.
  const int R = 40;
  const int nu = 23, nv = 25;
  const TriangleMesh torus = testing::grid_mesh(nu - 1, nv - 1, [](double u, double v) {
    const double theta = -0.58 + 1.16 * u, phi = (kPi - 0.1) - v * (kPi - 0.2);
    const double rho = 2.25 + std::cos(phi);
    return Vec3(rho * std::sin(theta), rho * std::cos(theta), std::sin(phi));
  });
  const ExampleMaps example = maps_of(torus, {0, nu - 1, nu * nv - 1, nu * (nv - 1)}, R);
  const auto lengths = side_lengths(example.patch);
  const auto surface = corner_angles(example.patch);
  const auto interval = convex_alpha_interval(lengths);
  for (int k = 1; k < 200; ++k) {
    const auto P = make_planar_patch(lengths, interval[0] + (interval[1] - interval[0]) * k / 200);
    ASSERT_TRUE(P.has_value());
    const auto angles = planar_corner_angles(*P);
    EXPECT_LT(angles[2], surface[2] - 0.02);
    EXPECT_LT(angles[3], surface[3] - 0.02);
  }
  for (const double bound : {0.0, kPi / 6}) {
    try {
      feasible_alpha_range(example.maps, lengths, {.min_planar_angle = bound});
      ADD_FAILURE() << "expected Infeasible";
    } catch (const Infeasible& error) {
      const std::string message = error.what();
      EXPECT_TRUE(contains(message, "closest at ᾱ =")) << message;
      EXPECT_TRUE(contains(message, "F_u ") || contains(message, "F_v ")) << message;
    }
  }
}

}  // namespace
}  // namespace gridshell
