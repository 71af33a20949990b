// SPDX-License-Identifier: GPL-3.0-or-later
// Member placement (paper 4.4): features of C(s), the spacing rule, gap filling, counts,
// option validation, determinism.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <numbers>

#include "gridshell/design/cladding.h"
#include "gridshell/design/members.h"
#include "gridshell/design/patch.h"
#include "gridshell/design/target_patch.h"
#include "gridshell/example_surfaces.h"
#include "gridshell/foundation/errors.h"
#include "gridshell/geodesic/geodesic.h"
#include "gridshell/mesh/surface_distance.h"
#include "support.h"

namespace gridshell {
namespace {

using testing::grid_mesh;
using Reason = MemberPosition::Reason;

// A flat patch cut from [0,10]^2 with the given corners (ccw), and the congruent planar patch
// (c0 moved to the origin, c1 rotated onto the +x axis).
struct FlatSetup {
  Patch patch;
  PlanarPatch planar;
};

FlatSetup flat_setup(const std::array<Vec2, 4>& q) {
  const TriangleMesh mesh =
      grid_mesh(20, 20, [](double u, double v) { return Vec3(10 * u, 10 * v, 0); });
  std::array<SurfacePoint, 4> corners;
  for (int i = 0; i < 4; ++i) corners[i] = closest_surface_point(mesh, Vec3(q[i].x(), q[i].y(), 0));
  FlatSetup setup{cut_patch(mesh, corners), {}};
  const Vec2 e = (q[1] - q[0]).normalized();
  for (int i = 0; i < 4; ++i) {
    const Vec2 d = q[i] - q[0];
    setup.planar.corners[i] = Vec2(d.dot(e), e.x() * d.y() - e.y() * d.x());
    setup.planar.side_lengths[i] = (q[(i + 1) % 4] - q[i]).norm();
  }
  const Vec2 a = q[1] - q[0], b = q[3] - q[0];
  setup.planar.alpha_bar = std::atan2(a.x() * b.y() - a.y() * b.x(), a.dot(b));
  return setup;
}

FlatSetup square_setup() {
  return flat_setup({Vec2(0, 0), Vec2(10, 0), Vec2(10, 10), Vec2(0, 10)});
}
FlatSetup quad_setup() { return flat_setup({Vec2(1, 1), Vec2(9, 2), Vec2(8, 9), Vec2(2, 8)}); }

CladdingFunction cladding_from(Family family, const std::function<double(double)>& f,
                               int samples = 60) {
  CladdingFunction c;
  c.family = family;
  c.valid = true;
  for (int k = 0; k <= samples; ++k) {
    const double u = static_cast<double>(k) / samples;
    c.points.push_back(Vec2(u, f(u)));
  }
  return c;
}

CladdingFunction diagonal(Family family = Family::G) {
  return cladding_from(family, [](double u) { return u; });
}

// D(i,j) = g((u1 + u2) / 2): along the diagonal cladding curve, C(s) = g(s).
DistanceMap map_from(Family family, int r, const std::function<double(double)>& g) {
  DistanceMap d;
  d.family = family;
  d.distances.resize(r, r);
  for (int i = 0; i < r; ++i)
    for (int j = 0; j < r; ++j) d.distances(i, j) = g(0.5 * (i + j) / (r - 1.0));
  return d;
}

double bump(double s, double at, double width) {
  return std::exp(-0.5 * (s - at) * (s - at) / (width * width));
}

// Only the features: no filling.
MemberPlacementOptions features_only() {
  MemberPlacementOptions o;
  o.lamella_width = 0.05;
  o.min_members = 0;
  o.max_spacing = 1.0;
  return o;
}

std::vector<double> positions(const std::vector<MemberPosition>& members, Reason reason) {
  std::vector<double> s;
  for (const auto& m : members)
    if (m.reason == reason) s.push_back(m.s);
  return s;
}

// Independent planar geometry of a family (distance_map.h conventions).
struct FamilyGeometry {
  Vec2 p0, p1, q0, q1;  // first boundary p0 -> p1, second q0 -> q1
  Vec2 first(double t) const { return p0 + t * (p1 - p0); }
  Vec2 second(double t) const { return q0 + t * (q1 - q0); }
};

FamilyGeometry geometry(const PlanarPatch& planar, Family family) {
  const auto& c = planar.corners;
  if (family == Family::G) return {c[0], c[1], c[3], c[2]};
  return {c[1], c[2], c[0], c[3]};
}

double sine(const Vec2& a, const Vec2& b) {
  return std::abs(a.x() * b.y() - a.y() * b.x()) / (a.norm() * b.norm());
}

// Checks: strictly increasing inside (0,1), the spacing rule between neighbours (boundary
// members included) on both boundaries; returns the widest gap (parameter units).
double check_members(const std::vector<MemberPosition>& members, const PlanarPatch& planar,
                     Family family, const MemberPlacementOptions& o) {
  const FamilyGeometry g = geometry(planar, family);
  std::vector<std::array<double, 2>> t{{0.0, 0.0}};
  for (const auto& m : members) {
    EXPECT_GT(m.u1, 0);
    EXPECT_LT(m.u1, 1);
    EXPECT_GT(m.u2, 0);
    EXPECT_LT(m.u2, 1);
    t.push_back({m.u1, m.u2});
  }
  t.push_back({1.0, 1.0});
  const std::array<Vec2, 2> direction{g.p1 - g.p0, g.q1 - g.q0};
  const std::array<double, 2> length{direction[0].norm(), direction[1].norm()};
  auto sines = [&](const std::array<double, 2>& p) {
    const Vec2 m = g.second(p[1]) - g.first(p[0]);
    return std::array<double, 2>{sine(m, direction[0]), sine(m, direction[1])};
  };
  double widest = 0;
  for (size_t k = 0; k + 1 < t.size(); ++k) {
    const auto sa = sines(t[k]), sb = sines(t[k + 1]);
    for (int e = 0; e < 2; ++e) {
      EXPECT_GT(t[k + 1][e], t[k][e]) << "member " << k << " boundary " << e;
      const double needed =
          o.lamella_width * (1 + o.clearance) / std::min(sa[e], sb[e]) / length[e];
      EXPECT_GE(t[k + 1][e] - t[k][e], needed * (1 - 1e-9))
          << "members " << k << "," << k + 1 << " on boundary " << e;
      widest = std::max(widest, t[k + 1][e] - t[k][e]);
    }
  }
  return widest;
}

TEST(PlaceMembers, SingleMaximumOfLengthGetsAMember) {
  const FlatSetup setup = square_setup();
  const int r = 65;
  const auto map = map_from(Family::G, r, [](double s) { return 10 + 3 * bump(s, 0.3, 0.06); });
  const auto members = place_members(diagonal(), map, setup.patch, setup.planar, features_only());
  const auto length = positions(members, Reason::LengthExtremum);
  ASSERT_EQ(length.size(), 1u);
  EXPECT_NEAR(length[0], 0.3, 1.0 / (r - 1));
  for (const auto& m : members) {
    EXPECT_NEAR(m.u1, m.s, 1e-12);
    EXPECT_NEAR(m.u2, m.s, 1e-12);
  }
}

TEST(PlaceMembers, TwoMaximaAndAMinimumAreAllFound) {
  const FlatSetup setup = square_setup();
  const int r = 65;
  const auto map = map_from(Family::G, r, [](double s) {
    return 10 + 2 * bump(s, 0.25, 0.07) + 1.5 * bump(s, 0.72, 0.08);
  });
  const auto members = place_members(diagonal(), map, setup.patch, setup.planar, features_only());
  // Exact extrema of the analytic C, on a fine grid.
  std::vector<double> expected;
  const int fine = 20000;
  auto c = [](double s) { return 10 + 2 * bump(s, 0.25, 0.07) + 1.5 * bump(s, 0.72, 0.08); };
  for (int k = 1; k < fine; ++k) {
    const double a = c((k - 1.0) / fine), b = c(double(k) / fine), d = c((k + 1.0) / fine);
    if ((b > a && b > d) || (b < a && b < d)) expected.push_back(double(k) / fine);
  }
  ASSERT_EQ(expected.size(), 3u);
  const auto length = positions(members, Reason::LengthExtremum);
  ASSERT_EQ(length.size(), 3u);
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(length[i], expected[i], 1.0 / (r - 1)) << i;
}

TEST(PlaceMembers, CurvatureBumpGetsACurvatureMember) {
  const FlatSetup setup = square_setup();
  const int r = 65;
  // Convex and increasing (no extremum of C): a softplus ramp; its curvature peaks once.
  auto c = [](double s) { return 10 + 5 * 0.05 * std::log1p(std::exp((s - 0.6) / 0.05)); };
  const auto map = map_from(Family::G, r, c);
  const auto members = place_members(diagonal(), map, setup.patch, setup.planar, features_only());
  EXPECT_TRUE(positions(members, Reason::LengthExtremum).empty());
  // Peak of κ of C / L (L = 10, the boundary length), on a fine grid.
  double best = 0, at = 0;
  const double h = 1e-4;
  for (double s = h; s < 1 - h; s += h) {
    const double d1 = (c(s + h) - c(s - h)) / (2 * h) / 10;
    const double d2 = (c(s + h) - 2 * c(s) + c(s - h)) / (h * h) / 10;
    const double kappa = std::abs(d2) / std::pow(1 + d1 * d1, 1.5);
    if (kappa > best) best = kappa, at = s;
  }
  const auto curvature = positions(members, Reason::CurvatureExtremum);
  ASSERT_EQ(curvature.size(), 1u);
  EXPECT_NEAR(curvature[0], at, 1.0 / (r - 1));
}

// A monotone, non-diagonal cladding curve and a C with several features.
CladdingFunction wavy(Family family) {
  return cladding_from(family, [](double u) { return u + 0.15 * std::sin(std::numbers::pi * u); });
}
DistanceMap featured_map(Family family) {
  return map_from(family, 50, [](double s) {
    return 9 + 1.5 * bump(s, 0.2, 0.05) - bump(s, 0.45, 0.06) + 2 * bump(s, 0.8, 0.04) +
           0.3 * std::sin(25 * s);
  });
}

TEST(PlaceMembers, LargeLamellasKeepTheSpacingRule) {
  const FlatSetup setup = quad_setup();
  for (Family family : {Family::G, Family::H}) {
    for (double width : {0.3, 0.6, 0.9}) {
      SCOPED_TRACE("family " + std::to_string(int(family)) + " width " + std::to_string(width));
      MemberPlacementOptions o;
      o.lamella_width = width;
      o.min_members = 1;
      const auto members =
          place_members(wavy(family), featured_map(family), setup.patch, setup.planar, o);
      EXPECT_GE(members.size(), 1u);
      check_members(members, setup.planar, family, o);
    }
  }
}

TEST(PlaceMembers, SmallLamellasFillEveryGapBelowMaxSpacing) {
  const FlatSetup setup = quad_setup();
  for (Family family : {Family::G, Family::H}) {
    MemberPlacementOptions o;
    o.lamella_width = 0.02;
    o.max_spacing = 0.1;
    const auto members =
        place_members(wavy(family), featured_map(family), setup.patch, setup.planar, o);
    EXPECT_LE(check_members(members, setup.planar, family, o), 0.1 + 1e-12);
    EXPECT_GE(members.size(), 9u);
    EXPECT_LE(members.size(), 60u);
    // The features stay; gap fills exist.
    EXPECT_FALSE(positions(members, Reason::LengthExtremum).empty());
    EXPECT_FALSE(positions(members, Reason::GapFill).empty());
    for (size_t k = 1; k < members.size(); ++k) EXPECT_GT(members[k].s, members[k - 1].s);
  }
}

TEST(PlaceMembers, AddedMembersAreEvenBetweenFeatures) {
  const FlatSetup setup = square_setup();
  const auto map = map_from(Family::G, 65, [](double s) { return 10 + 3 * bump(s, 0.3, 0.06); });
  MemberPlacementOptions o = features_only();
  o.feature_threshold = 0.5;  // only the maximum of C is a feature
  o.count = 6;
  const auto members = place_members(diagonal(), map, setup.patch, setup.planar, o);
  ASSERT_EQ(members.size(), 6u);
  std::vector<double> fixed{0.0};
  for (const auto& m : members)
    if (m.reason != Reason::GapFill) fixed.push_back(m.s);
  fixed.push_back(1.0);
  ASSERT_EQ(fixed.size(), 3u);
  // Between fixed members, the added ones are evenly spaced in s.
  std::vector<double> all{0.0};
  for (const auto& m : members) all.push_back(m.s);
  all.push_back(1.0);
  size_t k = 0;
  for (size_t f = 0; f + 1 < fixed.size(); ++f) {
    while (all[k] != fixed[f]) ++k;
    size_t e = k + 1;
    while (all[e] != fixed[f + 1]) ++e;
    const double step = (all[e] - all[k]) / (e - k);
    for (size_t i = k; i < e; ++i) EXPECT_NEAR(all[i + 1] - all[i], step, 1e-12);
  }
}

TEST(PlaceMembers, ExplicitCountIsExact) {
  const FlatSetup setup = quad_setup();
  for (int count : {1, 2, 5, 13, 30}) {
    MemberPlacementOptions o;
    o.lamella_width = 0.05;
    o.count = count;
    const auto members =
        place_members(wavy(Family::G), featured_map(Family::G), setup.patch, setup.planar, o);
    EXPECT_EQ(static_cast<int>(members.size()), count);
    check_members(members, setup.planar, Family::G, o);
  }
  // One member: the highest-priority feature (a length extremum).
  MemberPlacementOptions o;
  o.count = 1;
  o.lamella_width = 0.05;
  const auto one =
      place_members(wavy(Family::G), featured_map(Family::G), setup.patch, setup.planar, o);
  ASSERT_EQ(one.size(), 1u);
  EXPECT_EQ(one[0].reason, Reason::LengthExtremum);
}

TEST(PlaceMembers, MinAndMaxMembersAreHonoured) {
  const FlatSetup setup = quad_setup();
  MemberPlacementOptions o;
  o.lamella_width = 0.05;
  o.max_spacing = 1.0;  // no spacing-driven fill
  o.min_members = 17;
  o.max_members = 20;
  auto members =
      place_members(wavy(Family::H), featured_map(Family::H), setup.patch, setup.planar, o);
  EXPECT_EQ(members.size(), 17u);
  check_members(members, setup.planar, Family::H, o);
  o.min_members = 0;
  o.max_members = 2;
  o.max_spacing = 0.05;
  members = place_members(wavy(Family::H), featured_map(Family::H), setup.patch, setup.planar, o);
  EXPECT_EQ(members.size(), 2u);
  for (const auto& m : members) EXPECT_EQ(m.reason, Reason::LengthExtremum);
}

void expect_invalid(const MemberPlacementOptions& o, const std::string& name,
                    Family family = Family::G) {
  const FlatSetup setup = square_setup();
  try {
    place_members(diagonal(family), map_from(family, 20, [](double) { return 10.0; }), setup.patch,
                  setup.planar, o);
    ADD_FAILURE() << "accepted; expected an error naming " << name;
  } catch (const InvalidInput& e) {
    EXPECT_EQ(e.field(), name) << e.what();
  }
}

TEST(PlaceMembers, InvalidOptionsNameTheOption) {
  MemberPlacementOptions o;
  o.lamella_width = -1;
  expect_invalid(o, "options.lamella_width");
  o = {};
  o.lamella_width = std::nan("");
  expect_invalid(o, "options.lamella_width");
  o = {};
  o.lamella_thickness = -1;
  expect_invalid(o, "options.lamella_thickness");
  o = {};
  o.max_spacing = 0;
  expect_invalid(o, "options.max_spacing");
  o.max_spacing = 1.5;
  expect_invalid(o, "options.max_spacing");
  o = {};
  o.min_members = -1;
  expect_invalid(o, "options.min_members");
  o = {};
  o.min_members = 5;
  o.max_members = 3;
  expect_invalid(o, "options.max_members");
  o = {};
  o.count = -2;
  expect_invalid(o, "options.members_u", Family::G);
  expect_invalid(o, "options.members_v", Family::H);
  o = {};
  o.clearance = -0.1;
  expect_invalid(o, "options.clearance");
}

TEST(LamellaSize, ZeroMeansOnePercentOfTheLongestSideAndATenthOfTheWidth) {
  const FlatSetup setup = square_setup();
  const std::array<double, 4> sides = side_lengths(setup.patch);
  const double longest = *std::max_element(sides.begin(), sides.end());
  MemberPlacementOptions o;  // both 0 by default: automatic
  LamellaSize size = lamella_size(setup.patch, o);
  EXPECT_DOUBLE_EQ(size.width, 0.01 * longest);
  EXPECT_DOUBLE_EQ(size.thickness, 0.001 * longest);
  o.lamella_width = 0.7;
  size = lamella_size(setup.patch, o);
  EXPECT_DOUBLE_EQ(size.width, 0.7);
  EXPECT_DOUBLE_EQ(size.thickness, 0.07);
  o.lamella_thickness = 0.05;
  EXPECT_DOUBLE_EQ(lamella_size(setup.patch, o).thickness, 0.05);
}

TEST(PlaceMembers, InvalidCladdingIsRejected) {
  const FlatSetup setup = square_setup();
  const auto map = map_from(Family::G, 20, [](double) { return 10.0; });
  CladdingFunction broken = diagonal();
  broken.valid = false;
  broken.problem = "slope 0.05 < k_min at (0.4, 0.3)";
  try {
    place_members(broken, map, setup.patch, setup.planar);
    ADD_FAILURE() << "accepted an invalid cladding function";
  } catch (const Infeasible& e) {
    EXPECT_NE(std::string(e.what()).find("k_min"), std::string::npos) << e.what();
  }
  CladdingFunction open = diagonal();
  open.points.pop_back();
  EXPECT_THROW(place_members(open, map, setup.patch, setup.planar), InvalidInput);
  EXPECT_THROW(place_members(diagonal(Family::H), map, setup.patch, setup.planar), InvalidInput);
}

TEST(PlaceMembers, ImpossibleWidthIsInfeasible) {
  const FlatSetup setup = square_setup();  // boundaries 10 long, members at right angles
  const auto map = map_from(Family::G, 30, [](double s) { return 10 + bump(s, 0.5, 0.1); });
  MemberPlacementOptions o;
  o.lamella_width = 2;  // needs 3 between members: two inner members fit, not three
  o.min_members = 3;
  try {
    place_members(diagonal(), map, setup.patch, setup.planar, o);
    ADD_FAILURE() << "accepted";
  } catch (const Infeasible& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("only 2 g-members fit with lamella width 2 (min 3)"), std::string::npos)
        << what;
  }
  o.min_members = 0;
  o.count = 3;
  EXPECT_THROW(place_members(diagonal(), map, setup.patch, setup.planar, o), Infeasible);
  // Two fit when placed evenly (3.33 apart); the feature at 0.5 is given up for them.
  o.count = 2;
  const auto members = place_members(diagonal(), map, setup.patch, setup.planar, o);
  ASSERT_EQ(members.size(), 2u);
  check_members(members, setup.planar, Family::G, o);
}

TEST(PlaceMembers, CollapsedPlanarPatchIsInfeasibleNamingTheAngle) {
  FlatSetup setup = square_setup();
  const double a = 1e-6;  // the rhombus at ᾱ -> 0: every member lies along the boundaries
  setup.planar.alpha_bar = a;
  setup.planar.corners = {Vec2(0, 0), Vec2(10, 0), Vec2(10 + 10 * std::cos(a), 10 * std::sin(a)),
                          Vec2(10 * std::cos(a), 10 * std::sin(a))};
  const auto map = map_from(Family::G, 30, [](double s) { return 10 + bump(s, 0.5, 0.1); });
  try {
    place_members(diagonal(), map, setup.patch, setup.planar);
    ADD_FAILURE() << "accepted";
  } catch (const Infeasible& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("only 0 g-members fit"), std::string::npos) << what;
    EXPECT_NE(what.find("angles down to 0.0 deg"), std::string::npos) << what;
  }
}

TEST(PlaceMembers, IsDeterministic) {
  const FlatSetup setup = quad_setup();
  MemberPlacementOptions o;
  o.lamella_width = 0.1;
  const auto a =
      place_members(wavy(Family::G), featured_map(Family::G), setup.patch, setup.planar, o);
  const auto b =
      place_members(wavy(Family::G), featured_map(Family::G), setup.patch, setup.planar, o);
  ASSERT_EQ(a.size(), b.size());
  for (size_t k = 0; k < a.size(); ++k) {
    EXPECT_EQ(a[k].u1, b[k].u1);
    EXPECT_EQ(a[k].u2, b[k].u2);
    EXPECT_EQ(a[k].s, b[k].s);
    EXPECT_EQ(a[k].reason, b[k].reason);
  }
}

// End to end on example surfaces: real distance maps and cladding functions at ᾱ_min.
TEST(PlaceMembers, ExampleSurfacesKeepTheInvariants) {
  for (const char* name : {"double-vault", "sphere", "waves"}) {
    SCOPED_TRACE(name);
    const ExampleSurface example = make_example(name, 0.5);
    std::array<SurfacePoint, 4> corners;
    for (int i = 0; i < 4; ++i)
      corners[i] = SurfacePoint::at_vertex(example.mesh, example.corners[i]);
    const Patch patch = cut_patch(example.mesh, corners);
    const GeodesicSolver solver(patch.mesh);
    DistanceMapOptions map_options;
    map_options.resolution = 64;
    const DistanceMaps maps = compute_distance_maps(patch, solver, map_options);
    const auto lengths = side_lengths(patch);
    // The middle of the feasible range: ᾱ_min is currently ~1e-6 rad on double-vault and sphere
    // (a planar patch collapsed onto a line, where no lamella fits).
    const AlphaRange range = feasible_alpha_range(maps, lengths);
    const double alpha = 0.5 * (range.min + range.max);
    const auto planar = make_planar_patch(lengths, alpha);
    ASSERT_TRUE(planar.has_value());
    const double width = 0.01 * std::max(lengths[0], lengths[1]);  // paper: 1 on 100
    for (Family family : {Family::G, Family::H}) {
      const DistanceMap& map = family == Family::G ? maps.g : maps.h;
      const CladdingFunction cladding =
          cladding_function(map.distances, planar_distance_map(*planar, family, 64), family, alpha);
      ASSERT_TRUE(cladding.valid) << cladding.problem;
      MemberPlacementOptions o;
      o.lamella_width = width;
      o.lamella_thickness = width / 10;
      const auto members = place_members(cladding, map, patch, *planar, o);
      const double widest = check_members(members, *planar, family, o);
      EXPECT_LE(widest, o.max_spacing + 1e-12);
      EXPECT_GE(static_cast<int>(members.size()), o.min_members);
      EXPECT_LE(static_cast<int>(members.size()), o.max_members);
      int counts[3] = {0, 0, 0};
      for (const auto& m : members) ++counts[static_cast<int>(m.reason)];
      std::printf(
          "  %-12s %s: %2zu inner members at alpha %.3f (%d length extrema, %d curvature extrema, "
          "%d gap fills), "
          "widest gap %.3f\n",
          name, family == Family::G ? "g" : "h", members.size(), alpha, counts[0], counts[1],
          counts[2], widest);
      // A larger width never breaks the spacing rule either.
      o.lamella_width = 4 * width;
      o.min_members = 1;
      check_members(place_members(cladding, map, patch, *planar, o), *planar, family, o);
    }
  }
}

}  // namespace
}  // namespace gridshell
