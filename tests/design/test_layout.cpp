// SPDX-License-Identifier: GPL-3.0-or-later
// Patch layouts (kernel/design/layout.cpp): surfaces with known answers cut into several patches
// that share corners. Coverage is the input's area (closed form for the barrel vault), every
// shared seam is the same curve on both sides (to 1e-9 of the size), and malformed or overlapping
// layouts are refused naming the patch.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "gridshell/design/layout.h"
#include "gridshell/foundation/errors.h"
#include "support.h"

namespace gridshell {
namespace {

constexpr double kPi = std::numbers::pi;

/// A barrel vault: a quarter of a circular cylinder (radius 10) along x, 60 long, on an
/// nu x nv grid. Developable: eta = 1, area 60 * 10 * pi/2.
TriangleMesh barrel(int nu, int nv) {
  return testing::grid_mesh(nu, nv, [](double u, double v) {
    const double phi = kPi / 4 + v * kPi / 2;
    return Vec3(60 * u, 10 * std::cos(phi), 10 * std::sin(phi));
  });
}

/// Corner (i, j) of an nu x nv grid_mesh as a layout corner.
LayoutCorner at(int nu, int i, int j) {
  LayoutCorner c;
  c.vertex = j * (nu + 1) + i;
  return c;
}

TEST(Layout, ABarrelVaultInThreePatchesIsCoveredWithTwoSharedSeams) {
  const int nu = 60, nv = 12;
  const TriangleMesh mesh = barrel(nu, nv);
  PatchLayout layout;
  for (int j : {0, nv})
    for (int i : {0, 20, 40, 60}) layout.corners.push_back(at(nu, i, j));
  // Corners 0..3 along v = 0, 4..7 along v = 1; each patch counter-clockwise in (u, v).
  for (int p = 0; p < 3; ++p) layout.patches.push_back({"", {p, p + 1, p + 5, p + 4}});
  const LayoutResult r = cut_layout(mesh, layout);
  ASSERT_EQ(r.patches.size(), 3u);
  for (const LayoutPatch& p : r.patches) {
    EXPECT_TRUE(p.target.has_value()) << p.name;
    EXPECT_FALSE(p.problem.has_value()) << p.name << ": " << (p.problem ? p.problem->what() : "");
  }
  EXPECT_EQ(r.layout.patches[1].name, "P2");
  const double area = 60 * 10 * kPi / 2;
  EXPECT_NEAR(r.input_area, area, 0.01 * area);  // the grid's chords
  EXPECT_NEAR(r.coverage(), 1.0, 1e-9);
  int shared = 0;
  for (const LayoutSeam& seam : r.seams) {
    if (!seam.shared()) continue;
    ++shared;
    // The seam at u = 20 or 40 is a straight line (a ruling) of length 10 * pi/2 ... as chords.
    EXPECT_NEAR(seam.length, 10 * kPi / 2, 0.01 * seam.length);
    EXPECT_LE(seam.mismatch, 1e-9 * 60) << seam.corners[0] << "-" << seam.corners[1];
  }
  EXPECT_EQ(shared, 2);
  EXPECT_EQ(r.seams.size(), 10u);  // 3 x 4 sides, 2 of them shared
}

TEST(Layout, ADomeInTwoByTwoPatchesSharesFourSeams) {
  const int n = 24;
  // A shallow dome over [0, 40]^2 (height 3): curved both ways.
  const TriangleMesh mesh = testing::grid_mesh(n, n, [](double u, double v) {
    return Vec3(40 * u, 40 * v,
                3 * (1 - (2 * u - 1) * (2 * u - 1)) * (1 - (2 * v - 1) * (2 * v - 1)));
  });
  PatchLayout layout;
  for (int j : {0, n / 2, n})
    for (int i : {0, n / 2, n}) layout.corners.push_back(at(n, i, j));
  layout.patches = {
      {"SW", {0, 1, 4, 3}}, {"SE", {1, 2, 5, 4}}, {"NW", {3, 4, 7, 6}}, {"NE", {4, 5, 8, 7}}};
  const LayoutResult r = cut_layout(mesh, layout);
  double patch_areas = 0;
  for (const LayoutPatch& p : r.patches) {
    ASSERT_TRUE(p.target.has_value()) << p.name;
    patch_areas += p.target->area;
  }
  // The four patches tile the dome: their areas add up to the input's.
  EXPECT_NEAR(patch_areas, r.input_area, 1e-9 * r.input_area);
  int shared = 0;
  for (const LayoutSeam& seam : r.seams)
    if (seam.shared()) {
      ++shared;
      EXPECT_LE(seam.mismatch, 1e-9 * 40);
      EXPECT_GT(seam.length, 20.0);
    }
  EXPECT_EQ(shared, 4);
  // Coverage counts the patches that meet the checks; any that does not says why.
  double covered = 0;
  for (const LayoutPatch& p : r.patches)
    if (!p.problem)
      covered += p.target->area;
    else
      EXPECT_NE(std::string(p.problem->message()).find("eta"), std::string::npos);
  EXPECT_NEAR(r.covered_area, covered, 1e-12 * covered + 1e-12);
}

TEST(Layout, CornersGivenAsPointsInsideFacesAreInsertedOnceForAllPatches) {
  const int nu = 30, nv = 6;
  const TriangleMesh mesh = barrel(nu, nv);
  // The middle corners inside faces (u = 29.3 of 60 is not a grid line), the others at vertices.
  const auto point = [](double x, double v) {
    LayoutCorner c;
    const double phi = kPi / 4 + v * kPi / 2;
    c.point = Vec3(x, 10 * std::cos(phi), 10 * std::sin(phi));
    return c;
  };
  PatchLayout layout;
  layout.corners = {at(nu, 0, 0),  point(29.3, 0), at(nu, 30, 0),
                    at(nu, 0, nv), point(29.3, 1), at(nu, 30, nv)};
  layout.patches = {{"A", {0, 1, 4, 3}}, {"B", {1, 2, 5, 4}}};
  const LayoutResult r = cut_layout(mesh, layout);
  for (const LayoutPatch& p : r.patches) {
    ASSERT_TRUE(p.target.has_value()) << p.name;
    EXPECT_FALSE(p.problem.has_value()) << p.problem->what();
  }
  EXPECT_NEAR(r.patches[0].target->area / r.input_area, 29.3 / 60, 1e-3);
  EXPECT_NEAR(r.coverage(), 1.0, 1e-9);
  for (const LayoutSeam& seam : r.seams) {
    if (seam.shared()) {
      EXPECT_LE(seam.mismatch, 1e-9 * 60);
    }
  }
}

/// A flat annulus, radii 5 and 10, as a closed ring of quads (nu around, nv across).
TriangleMesh annulus(int nu, int nv) {
  std::vector<Vec3> vertices;
  std::vector<Face> faces;
  for (int j = 0; j <= nv; ++j)
    for (int i = 0; i < nu; ++i) {
      const double r = 5 + 5.0 * j / nv, phi = 2 * kPi * i / nu;
      vertices.emplace_back(r * std::cos(phi), r * std::sin(phi), 0);
    }
  const auto at = [&](int i, int j) { return j * nu + (i % nu); };
  for (int j = 0; j < nv; ++j)
    for (int i = 0; i < nu; ++i) {
      faces.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
      faces.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
    }
  return TriangleMesh(std::move(vertices), std::move(faces));
}

// An annulus in four patches between radial seams: the outer sides are chords (a flat surface's
// geodesics), the inner ones follow the hole's edge. The covered area is the ring's minus four
// circular segments of the outer circle, R^2/2 (pi/2 - 1) each (as the polygons, closely).
// Such quarter rings are cut and meet the geometric checks, but no grid fits them: no planar
// angle is feasible, so none counts as covered (the automatic layout takes 14 narrower ones,
// tests/design/test_auto_layout.cpp).
TEST(Layout, AnAnnulusInFourPatchesCoversTheRingButTheOuterSegments) {
  const int nu = 96, nv = 8;
  const TriangleMesh mesh = annulus(nu, nv);
  PatchLayout layout;
  for (int q = 0; q < 4; ++q) layout.corners.push_back({nv * nu + q * nu / 4, Vec3::Zero()});
  for (int q = 0; q < 4; ++q) layout.corners.push_back({q * nu / 4, Vec3::Zero()});
  // Outer corners 0..3, inner 4..7, counter-clockwise seen from +z: outer q -> outer q+1 ->
  // inner q+1 -> inner q.
  for (int q = 0; q < 4; ++q)
    layout.patches.push_back({"", {q, (q + 1) % 4, 4 + (q + 1) % 4, 4 + q}});
  const LayoutResult r = cut_layout(mesh, layout);
  double covered = 0;
  for (size_t j = 0; j < r.patches.size(); ++j) {
    const LayoutPatch& p = r.patches[j];
    ASSERT_TRUE(p.target.has_value()) << p.name;
    ASSERT_TRUE(p.problem.has_value()) << p.name;
    EXPECT_EQ(p.problem->field(), "layout.patches[" + std::to_string(j) + "].corners")
        << p.problem->what();
    EXPECT_NE(std::string(p.problem->message()).find("no feasible planar angle"), std::string::npos)
        << p.problem->what();
    EXPECT_FALSE(p.alpha_range);
    covered += p.target->area;
  }
  // The ring and the outer segments as the mesh's polygons: n-gon areas.
  const double ring = nu / 2.0 * std::sin(2 * kPi / nu) * (100 - 25);
  const double segments = 4 * (nu / 4 / 2.0 * std::sin(2 * kPi / nu) * 100 - 100 / 2.0);
  EXPECT_NEAR(r.input_area, ring, 1e-9 * ring);
  EXPECT_NEAR(covered, ring - segments, 1e-6 * ring);
  EXPECT_EQ(r.coverage(), 0);
  int shared = 0;
  for (const LayoutSeam& seam : r.seams)
    if (seam.shared()) {
      ++shared;
      EXPECT_NEAR(seam.length, 5, 1e-9);  // radial: from r = 5 to 10
      EXPECT_LE(seam.mismatch, 1e-9 * 20);
    }
  EXPECT_EQ(shared, 4);
}

TEST(Layout, MalformedAndOverlappingLayoutsAreRefusedNamingThePatch) {
  const int nu = 30, nv = 6;
  const TriangleMesh mesh = barrel(nu, nv);
  PatchLayout base;
  for (int j : {0, nv})
    for (int i : {0, 15, 30}) base.corners.push_back(at(nu, i, j));
  base.patches = {{"A", {0, 1, 4, 3}}, {"B", {1, 2, 5, 4}}};
  EXPECT_NO_THROW(cut_layout(mesh, base));
  const auto field_of = [&](const PatchLayout& layout) {
    try {
      cut_layout(mesh, layout);
    } catch (const Error& e) {
      return std::string(e.field()) + (e.code() == ErrorCode::Infeasible ? " (infeasible)" : "");
    }
    return std::string("accepted");
  };
  PatchLayout bad = base;
  bad.patches[1].corners[2] = 9;
  EXPECT_EQ(field_of(bad), "layout.patches[1].corners[2]");
  bad = base;
  bad.patches[1].corners[3] = 1;
  EXPECT_EQ(field_of(bad), "layout.patches[1].corners[3]");
  bad = base;
  bad.patches[1].name = "A";
  EXPECT_EQ(field_of(bad), "layout.patches[1].name");
  bad = base;
  bad.corners[2].vertex = 100000;
  EXPECT_EQ(field_of(bad), "layout.corners[2]");
  // B given the other way round: it would lie on A's side of their seam.
  bad = base;
  bad.patches[1].corners = {4, 5, 2, 1};
  EXPECT_EQ(field_of(bad), "layout.patches[1] (infeasible)");
  // A third patch on the same seam.
  bad = base;
  bad.patches.push_back({"C", {1, 4, 3, 0}});
  EXPECT_EQ(field_of(bad), "layout.patches[2]");
  bad.patches.clear();
  EXPECT_EQ(field_of(bad), "layout.patches");
}

TEST(Layout, APatchThatCannotBeCutIsReportedWithItsReasonAndNotCovered) {
  const int nu = 30, nv = 6;
  const TriangleMesh mesh = barrel(nu, nv);
  PatchLayout layout;
  for (int j : {0, nv})
    for (int i : {0, 15, 30}) layout.corners.push_back(at(nu, i, j));
  // B's corners in a bow-tie order: its boundary geodesics cross (criterion iv). Its side 4 -> 1
  // is A's 1 -> 4 the other way round, so the layout itself is well formed.
  layout.patches = {{"A", {0, 1, 4, 3}}, {"B", {1, 5, 2, 4}}};
  const LayoutResult r = cut_layout(mesh, layout);
  ASSERT_EQ(r.patches.size(), 2u);
  EXPECT_FALSE(r.patches[0].problem.has_value());
  ASSERT_TRUE(r.patches[1].problem.has_value());
  EXPECT_EQ(r.patches[1].problem->field().rfind("layout.patches[1]", 0), 0u)
      << r.patches[1].problem->field();
  EXPECT_NEAR(r.covered_area, r.patches[0].target->area, 1e-12);
  EXPECT_LT(r.coverage(), 0.6);
}

}  // namespace
}  // namespace gridshell
