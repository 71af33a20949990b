// SPDX-License-Identifier: GPL-3.0-or-later
// Automatic corners (gridshell/design/auto_corners.h, issue 18 item 2): the search finds an
// acceptable patch on surfaces whose sharpest boundary vertices give none (a helicoid, a closed
// sphere, an annulus), every accepted patch satisfies the criteria (corner angles in range,
// eta <= eta_max, exact boundary geodesics, a feasible planar angle range), the report records
// every candidate with a reason, and on the built-in examples and the shared meshes the chosen
// patch is at least as large as the former rule's (the four sharpest boundary vertices).
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <string>

#include "gridshell/design/design.h"
#include "gridshell/example_surfaces.h"
#include "gridshell/foundation/errors.h"
#include "gridshell/mesh/mesh_io.h"
#include "support.h"

namespace gridshell {
namespace {

constexpr double kPi = std::numbers::pi;

/// Everything the search promises about its choice.
void expect_acceptable(const TargetPatch& target, const TargetPatchOptions& options = {}) {
  ASSERT_TRUE(target.auto_corners.has_value());
  const AutoCornerReport& report = *target.auto_corners;
  ASSERT_GE(report.chosen, 0);
  ASSERT_LT(report.chosen, static_cast<int>(report.candidates.size()));
  const AutoCornerCandidate& chosen = report.candidates[report.chosen];
  EXPECT_TRUE(chosen.accepted);
  EXPECT_TRUE(chosen.alpha_range.has_value());
  for (double a : target.corner_angles) {
    EXPECT_GE(a, options.auto_corners.min_corner_angle);
    EXPECT_LE(a, options.auto_corners.max_corner_angle);
  }
  EXPECT_LE(target.smoothing.eta_after, options.coverability.eta_max);
  for (double e : target.boundary_excess) EXPECT_LE(e, kBoundaryGeodesicTolerance);
  // Every candidate has a reason; only the chosen one is accepted; no candidate evaluated before
  // it (a larger one) was accepted.
  int accepted = 0;
  for (const AutoCornerCandidate& c : report.candidates) {
    EXPECT_FALSE(c.reason.empty());
    accepted += c.accepted;
    if (c.kind == chosen.kind && c.area > chosen.area * (1 + 1e-12) && c.eta > 0) {
      EXPECT_FALSE(c.accepted);
    }
  }
  EXPECT_EQ(accepted, 1);
  EXPECT_LE(report.cuts, options.auto_corners.max_cuts);
  EXPECT_LE(report.evaluations, options.auto_corners.max_evaluations);
  EXPECT_GT(report.seconds, 0.0);
  // The maps it computed are handed on.
  ASSERT_TRUE(target.maps);
  EXPECT_EQ(target.maps->g.resolution(), options.auto_corners.maps.resolution);
}

/// A helicoid strip: (r cos t, r sin t, 3 t), r in [-5, 5], t in [0, pi]. Its helical boundaries
/// are not geodesics, so the boundary geodesics between its four grid corners cut deep into it
/// and leave sharp corners.
TriangleMesh helicoid() {
  return testing::grid_mesh(24, 36, [](double u, double v) {
    const double r = -5 + 10 * u, t = kPi * v;
    return Vec3(r * std::cos(t), r * std::sin(t), 3 * t);
  });
}

TEST(AutoCorners, HelicoidFindsAPatchWithSaneAngles) {
  const TriangleMesh mesh = helicoid();
  const TargetPatch target = make_target_patch(mesh, CornerSpec{});
  expect_acceptable(target);
  // The former rule (the four sharpest boundary vertices) is the first candidate, and it fails.
  const AutoCornerReport& report = *target.auto_corners;
  EXPECT_EQ(report.candidates.front().vertices, auto_corners(mesh));
  EXPECT_FALSE(report.candidates.front().accepted);
}

TEST(AutoCorners, ClosedSphereGetsAnInnerPatch) {
  const TargetPatch target = make_target_patch(testing::icosphere(3, 10), CornerSpec{});
  expect_acceptable(target);
  EXPECT_EQ(target.auto_corners->candidates[target.auto_corners->chosen].kind, "inner");
  EXPECT_EQ(target.patch.mesh.topology().boundary_loops.size(), 1u);
}

// The candidates are cut on several threads: the report and the choice are those of one thread,
// candidate by candidate (the helicoid's several boundary candidates, the sphere's inner ones).
TEST(AutoCorners, TheSearchDoesNotDependOnTheThreadCount) {
  for (const TriangleMesh& mesh : {helicoid(), testing::icosphere(3, 10)}) {
    TargetPatchOptions one, three;
    one.auto_corners.maps.threads = 1;
    three.auto_corners.maps.threads = 3;
    const TargetPatch a = make_target_patch(mesh, CornerSpec{}, one);
    const TargetPatch b = make_target_patch(mesh, CornerSpec{}, three);
    const AutoCornerReport &ra = *a.auto_corners, &rb = *b.auto_corners;
    ASSERT_GT(ra.cuts, 1);
    EXPECT_EQ(ra.cuts, rb.cuts);
    EXPECT_EQ(ra.evaluations, rb.evaluations);
    EXPECT_EQ(ra.chosen, rb.chosen);
    ASSERT_EQ(ra.candidates.size(), rb.candidates.size());
    for (size_t i = 0; i < ra.candidates.size(); ++i) {
      EXPECT_EQ(ra.candidates[i].vertices, rb.candidates[i].vertices) << i;
      EXPECT_EQ(ra.candidates[i].reason, rb.candidates[i].reason) << i;
      EXPECT_EQ(ra.candidates[i].area, rb.candidates[i].area) << i;
      EXPECT_EQ(ra.candidates[i].corner_angles, rb.candidates[i].corner_angles) << i;
    }
    EXPECT_EQ(a.corner_angles, b.corner_angles);
  }
}

TEST(AutoCorners, ASimplifiedCopyRanksTheCandidatesTheChosenPatchIsExact) {
  // Searched on a copy simplified to a third of the vertices, the helicoid and the sphere get
  // the same corners as searched on the input, and the chosen patch is the same exact patch: its
  // area, corner angles and mesh. The copy's areas are within the reported error.
  for (const TriangleMesh& mesh : {helicoid(), testing::icosphere(3, 10)}) {
    TargetPatchOptions exact, coarse;
    exact.auto_corners.simplify_above = 1 << 30;
    coarse.auto_corners.simplify_above = 300;
    coarse.auto_corners.simplify_to = mesh.vertex_count() / 3;
    const TargetPatch a = make_target_patch(mesh, CornerSpec{}, exact);
    const TargetPatch b = make_target_patch(mesh, CornerSpec{}, coarse);
    const AutoCornerReport &ra = *a.auto_corners, &rb = *b.auto_corners;
    EXPECT_EQ(ra.simplified_vertices, 0);
    EXPECT_GT(rb.simplified_vertices, 0);
    EXPECT_LE(rb.simplified_vertices, mesh.vertex_count() / 3 + 1);
    ASSERT_GE(rb.chosen, 0);
    EXPECT_EQ(ra.candidates[ra.chosen].vertices, rb.candidates[rb.chosen].vertices);
    EXPECT_EQ(ra.candidates[ra.chosen].area, rb.candidates[rb.chosen].area);
    EXPECT_EQ(a.corner_angles, b.corner_angles);
    EXPECT_EQ(a.patch.mesh.vertices(), b.patch.mesh.vertices());
    // Every candidate cut on both: the copy's area within the reported relative error of the
    // input's, and that error small.
    int both = 0;
    for (const AutoCornerCandidate& c : rb.candidates)
      if (c.area > 0 && c.coarse_area > 0) {
        ++both;
        EXPECT_LE(std::abs(c.coarse_area - c.area), rb.area_error * c.area * (1 + 1e-12));
      }
    EXPECT_GE(both, 1);
    EXPECT_LT(rb.area_error, 0.02);
  }
}

TEST(AutoCorners, AnnulusGetsADiskPatch) {
  const TargetPatch target = make_target_patch(testing::annulus(2, 6, 10, 64), CornerSpec{});
  expect_acceptable(target);
  EXPECT_EQ(target.patch.mesh.topology().boundary_loops.size(), 1u);
}

TEST(AutoCorners, CornerAngleRangeIsAnOption) {
  // A range no candidate can meet: Infeasible naming the corners, with the candidates' reasons.
  TargetPatchOptions options;
  options.auto_corners.min_corner_angle = 170 * kPi / 180;
  options.auto_corners.max_corner_angle = 175 * kPi / 180;
  try {
    make_target_patch(make_example("plane").mesh, CornerSpec{}, options);
    FAIL() << "no exception";
  } catch (const Infeasible& e) {
    EXPECT_EQ(e.field(), "corners");
    EXPECT_NE(e.message().find("corner angles"), std::string::npos) << e.message();
  }
}

/// The former rule's patch area, or 0 where it gave none with corner angles in the range.
double former_area(const TriangleMesh& mesh) {
  try {
    const TargetPatch former = make_target_patch(mesh, CornerSpec::at_vertices(auto_corners(mesh)));
    const AutoCornerOptions range;
    for (double a : former.corner_angles)
      if (a < range.min_corner_angle || a > range.max_corner_angle) return 0;
    return former.area;
  } catch (const Infeasible&) {
    return 0;
  }
}

TEST(AutoCorners, ExamplesAreAtLeastAsLargeAsTheFormerRule) {
  for (const std::string& name : example_names()) {
    SCOPED_TRACE(name);
    const TriangleMesh mesh = make_example(name, 0.5).mesh;  // a quarter of the vertices
    const TargetPatch target = make_target_patch(mesh, CornerSpec{});
    expect_acceptable(target);
    EXPECT_GE(target.area, former_area(mesh) * (1 - 1e-12));
  }
}

TEST(AutoCorners, SharedMeshes) {
  for (const std::string& path : testing::test_mesh_paths()) {
    SCOPED_TRACE(path);
    const TriangleMesh mesh = load_mesh(path);
    const TargetPatch target = make_target_patch(mesh, CornerSpec{});
    expect_acceptable(target);
    EXPECT_GE(target.area, former_area(mesh) * (1 - 1e-12));
  }
}

}  // namespace
}  // namespace gridshell
