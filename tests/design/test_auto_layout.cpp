// SPDX-License-Identifier: GPL-3.0-or-later
// Automatic layouts (kernel/design/auto_layout.cpp) against closed forms: a flat disk is covered
// by the polygon of the layout's boundary corners (a regular 12-gon for 3 x 3 patches, the first
// grid to reach 95 %), a four-sided surface by one patch, and surfaces that are not disks are
// refused saying why.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "gridshell/design/layout.h"
#include "gridshell/foundation/errors.h"
#include "support.h"

namespace gridshell {
namespace {

constexpr double kPi = std::numbers::pi;

/// A flat disk of radius 10: a centre vertex and `rings` rings of `sectors` vertices.
TriangleMesh disk(int rings, int sectors) {
  std::vector<Vec3> vertices{Vec3::Zero()};
  std::vector<Face> faces;
  for (int r = 1; r <= rings; ++r)
    for (int s = 0; s < sectors; ++s) {
      const double phi = 2 * kPi * s / sectors, radius = 10.0 * r / rings;
      vertices.emplace_back(radius * std::cos(phi), radius * std::sin(phi), 0);
    }
  const auto at = [&](int r, int s) { return r == 0 ? 0 : 1 + (r - 1) * sectors + s % sectors; };
  for (int s = 0; s < sectors; ++s) faces.push_back({0, at(1, s), at(1, s + 1)});
  for (int r = 1; r < rings; ++r)
    for (int s = 0; s < sectors; ++s) {
      faces.push_back({at(r, s), at(r + 1, s), at(r + 1, s + 1)});
      faces.push_back({at(r, s), at(r + 1, s + 1), at(r, s + 1)});
    }
  return TriangleMesh(vertices, faces);
}

TEST(AutoLayout, AFlatDiskIsCoveredByTheTwelveGonOfAThreeByThreeLayout) {
  const int sectors = 96;
  const TriangleMesh mesh = disk(12, sectors);
  const AutoLayout a = auto_layout(mesh);
  // The mesh's area is that of its 96-gon; n equally spaced boundary corners cover an n-gon.
  const auto polygon = [](int n) { return n / 2.0 * std::sin(2 * kPi / n); };
  EXPECT_NEAR(a.result.input_area, 100 * polygon(sectors), 1e-9 * a.result.input_area);
  // Tried by patch count, patches at most twice as long as wide: 1, 2, 4, 6, 8, 9, ... each cut
  // (an upper bound of its coverage); the first whose bound reaches 95 % is checked in full and
  // kept: 3 x 3, whose 12 boundary corners are every 30 degrees.
  ASSERT_GE(a.trials.size(), 6u);
  EXPECT_EQ(a.trials[0].columns * a.trials[0].rows, 1);
  EXPECT_NEAR(a.trials[0].cut_coverage, polygon(4) / polygon(sectors), 1e-6);
  EXPECT_EQ(a.columns, 3);
  EXPECT_EQ(a.rows, 3);
  EXPECT_NEAR(a.result.coverage(), polygon(12) / polygon(sectors), 1e-6);
  EXPECT_GE(a.result.coverage(), 0.95);
  int checked = 0;
  for (size_t t = 0; t < a.trials.size(); ++t) {
    const AutoLayoutTrial& trial = a.trials[t];
    if (t > 0) {
      EXPECT_GE(trial.columns * trial.rows, a.trials[t - 1].columns * a.trials[t - 1].rows);
    }
    const bool chosen = trial.columns == 3 && trial.rows == 3;
    EXPECT_EQ(trial.checked, chosen) << trial.columns << " x " << trial.rows;
    checked += trial.checked;
    if (chosen) {
      EXPECT_EQ(trial.failing, 0);
      EXPECT_NEAR(trial.coverage, a.result.coverage(), 1e-12);
      EXPECT_GE(trial.cut_coverage, trial.coverage - 1e-12);
    } else if (trial.columns * trial.rows < 9) {
      EXPECT_LT(trial.cut_coverage, 0.95);  // never checked: its bound misses the goal
    }
  }
  EXPECT_EQ(checked, 1);
  ASSERT_EQ(a.result.patches.size(), 9u);
  for (const LayoutPatch& p : a.result.patches) {
    ASSERT_TRUE(p.target.has_value()) << p.name;
    EXPECT_FALSE(p.problem.has_value()) << p.name;
  }
  // 12 inner seams (2 x 3 each way), each shared to 1e-9.
  int shared = 0;
  for (const LayoutSeam& seam : a.result.seams)
    if (seam.shared()) {
      ++shared;
      EXPECT_LE(seam.mismatch, 1e-9 * 20);
    }
  EXPECT_EQ(shared, 12);
  // The square's corners are boundary vertices a quarter of the way round from each other.
  for (int k = 0; k < 4; ++k) {
    const Vec3& p = mesh.vertices()[a.boundary_corners[k]];
    const Vec3& q = mesh.vertices()[a.boundary_corners[(k + 1) % 4]];
    EXPECT_NEAR(p.norm(), 10, 1e-12);
    EXPECT_NEAR(std::acos(std::clamp(p.dot(q) / 100, -1.0, 1.0)), kPi / 2, 1e-9);
  }
}

TEST(AutoLayout, AFourSidedSurfaceIsOnePatchAtItsCorners) {
  const int n = 16;
  const TriangleMesh mesh = testing::grid_mesh(n, n, [](double u, double v) {
    return Vec3(40 * u, 30 * v,
                3 * (1 - (2 * u - 1) * (2 * u - 1)) * (1 - (2 * v - 1) * (2 * v - 1)));
  });
  const AutoLayout a = auto_layout(mesh);
  EXPECT_TRUE(a.trials.front().checked);
  EXPECT_EQ(a.columns * a.rows, 1);
  EXPECT_NEAR(a.result.coverage(), 1.0, 1e-9);
  std::vector<int> corners(a.boundary_corners.begin(), a.boundary_corners.end());
  std::sort(corners.begin(), corners.end());
  EXPECT_EQ(corners, (std::vector<int>{0, n, n * (n + 1), n * (n + 1) + n}));
}

TEST(AutoLayout, SurfacesThatAreNotDisksAreRefusedSayingWhy) {
  try {
    auto_layout(testing::annulus(5, 10, 4, 48));
    FAIL() << "an annulus was laid out";
  } catch (const Infeasible& e) {
    EXPECT_EQ(e.field(), "layout");
    EXPECT_NE(std::string(e.message()).find("2 boundary loops"), std::string::npos) << e.what();
  }
  try {
    auto_layout(testing::icosphere(2, 10));
    FAIL() << "a sphere was laid out";
  } catch (const Infeasible& e) {
    EXPECT_NE(std::string(e.message()).find("closed"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace gridshell
