// SPDX-License-Identifier: GPL-3.0-or-later
// The patch stage (gridshell/design/target_patch.h): make_target_patch resolves the corner spec
// (vertices, points snapped to the surface, automatic), cuts, analyses and smooths; its report
// (stage timings, corner angles, side lengths, area, coverability) must agree with the patch it
// returns, and bad corners are InvalidInput naming "corners.vertices[i]" / "corners.points[i]".
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <numbers>
#include <set>
#include <string>
#include <vector>

#include "gridshell/design/target_patch.h"
#include "gridshell/example_surfaces.h"
#include "gridshell/foundation/errors.h"
#include "gridshell/mesh/curvature.h"
#include "gridshell/mesh/normals.h"
#include "gridshell/mesh/surface_distance.h"
#include "support.h"

namespace gridshell {
namespace {

using testing::grid_mesh;

/// The field of the InvalidInput make_target_patch throws for `spec` ("" and a failure if none).
std::string corner_error(const TriangleMesh& mesh, const CornerSpec& spec) {
  try {
    make_target_patch(mesh, spec);
  } catch (const InvalidInput& e) {
    EXPECT_FALSE(e.message().empty());
    return e.field();
  } catch (const std::exception& e) {
    ADD_FAILURE() << "expected InvalidInput, got: " << e.what();
    return "";
  }
  ADD_FAILURE() << "no exception";
  return "";
}

double polyline_length(const TriangleMesh& mesh, const std::vector<int>& chain) {
  double length = 0;
  for (std::size_t k = 1; k < chain.size(); ++k)
    length += (mesh.vertices()[chain[k]] - mesh.vertices()[chain[k - 1]]).norm();
  return length;
}

/// Everything in the report that can be recomputed from the returned patch.
void expect_consistent_report(const TriangleMesh& input, const TargetPatch& result) {
  const Patch& patch = result.patch;
  // Stage timings: the three stages, finite and non-negative.
  std::set<std::string> stages;
  for (const auto& [stage, seconds] : result.stage_seconds) {
    stages.insert(stage);
    EXPECT_TRUE(std::isfinite(seconds)) << stage;
    EXPECT_GE(seconds, 0.0) << stage;
  }
  stages.erase("auto_corners");  // with automatic corners: the search
  EXPECT_EQ(stages, (std::set<std::string>{"boundary_check", "coverability", "cut", "smoothing"}));
  // Corner angles and side lengths of the returned patch, recomputed independently.
  const std::vector<double> angle_sums = vertex_angle_sums(patch.mesh);
  for (int i = 0; i < 4; ++i) {
    EXPECT_NEAR(result.corner_angles[i], angle_sums[patch.corners[i]], 1e-12) << "corner " << i;
    EXPECT_LT(result.corner_angles[i], std::numbers::pi);
    EXPECT_GT(result.corner_angles[i], 0.0);
    const double length = polyline_length(patch.mesh, patch.sides[i]);
    EXPECT_NEAR(result.boundary_lengths[i], length, 1e-12 * length) << "side " << i;
    EXPECT_EQ(patch.sides[i].front(), patch.corners[i]);
    EXPECT_EQ(patch.sides[i].back(), patch.corners[(i + 1) % 4]);
  }
  EXPECT_NEAR(result.area, surface_area(patch.mesh), 1e-12 * result.area);
  EXPECT_GT(result.area, 0.0);
  EXPECT_LE(result.area, surface_area(input) * (1 + 1e-12));
  // The patch's corners are the input corners (reversed when they were given clockwise).
  for (int i = 0; i < 4; ++i) {
    const int j = patch.corners_reversed ? (4 - i) % 4 : i;
    EXPECT_LT(
        (patch.mesh.vertices()[patch.corners[i]] - result.input_corners[j].position(input)).norm(),
        1e-9 * bounding_box_size(input).norm())
        << "corner " << i;
  }
  // The smoothing report agrees with the coverability report.
  EXPECT_EQ(result.smoothing.eta_before, result.coverability.gap.eta);
  if (result.coverability.injectivity_ok) {
    EXPECT_EQ(result.smoothing.iterations, 0);
    EXPECT_EQ(result.smoothing.eta_after, result.smoothing.eta_before);
  }
}

TEST(MakeTargetPatch, ReportAgreesWithThePatchOnEveryKindOfSurface) {
  for (const std::string name : {"double-vault", "hypar", "cylinder"}) {
    SCOPED_TRACE(name);
    const ExampleSurface example = make_example(name, 0.5);
    const auto start = std::chrono::steady_clock::now();
    const TargetPatch result =
        make_target_patch(example.mesh, CornerSpec::at_vertices(example.corners));
    const double wall =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    expect_consistent_report(example.mesh, result);
    double stages = 0;
    for (const auto& [stage, seconds] : result.stage_seconds) stages += seconds;
    EXPECT_LE(stages, wall);
    // Vertex corners: the input corners are those vertices, and the patch keeps them.
    for (int i = 0; i < 4; ++i) {
      EXPECT_EQ(result.input_corners[i].vertex(example.mesh), example.corners[i]);
      EXPECT_EQ(result.patch.input_vertex[result.patch.corners[i]], example.corners[i]);
    }
  }
}

TEST(MakeTargetPatch, CornersAsPointsSnapToTheClosestSurfacePoint) {
  const ExampleSurface example = make_example("double-vault", 0.5);
  const TriangleMesh& mesh = example.mesh;
  const std::vector<Vec3> normals = vertex_normals(mesh);
  const double size = bounding_box_size(mesh).norm();
  CornerSpec spec;
  spec.kind = CornerSpec::Kind::Points;
  // Above the suggested corners, moved a little inwards along the boundary.
  for (int i = 0; i < 4; ++i) {
    const Vec3 corner = mesh.vertices()[example.corners[i]];
    const Vec3 next = mesh.vertices()[example.corners[(i + 1) % 4]];
    spec.points[i] = corner + 0.02 * (next - corner) + 0.01 * size * normals[example.corners[i]];
  }
  const TargetPatch result = make_target_patch(mesh, spec);
  expect_consistent_report(mesh, result);
  const SurfaceDistance surface(mesh);
  for (int i = 0; i < 4; ++i) {
    const Vec3 snapped = result.input_corners[i].position(mesh);
    EXPECT_LT((snapped - surface.closest(spec.points[i]).position(mesh)).norm(), 1e-12 * size);
    EXPECT_NEAR((snapped - spec.points[i]).norm(), surface.distance(spec.points[i]), 1e-12 * size);
    EXPECT_LT(surface.distance(snapped), 1e-12 * size);  // on the surface
  }
}

TEST(MakeTargetPatch, AutomaticCornersAreAutoCorners) {
  const ExampleSurface example = make_example("hypar", 0.5);
  const std::array<int, 4> expected = auto_corners(example.mesh);
  const TargetPatch result = make_target_patch(example.mesh, CornerSpec{});
  expect_consistent_report(example.mesh, result);
  for (int i = 0; i < 4; ++i) EXPECT_EQ(result.input_corners[i].vertex(example.mesh), expected[i]);
}

// A sharp bump whose longest member exceeds the injectivity bound: smoothed by default, left as
// it is with smooth = false (the report then says eta_after = eta_before).
TEST(MakeTargetPatch, SmoothingOnlyWhenAskedAndNeeded) {
  const int n = 30;
  const TriangleMesh mesh = grid_mesh(n, n, [](double u, double v) {
    const double x = 10 * u, y = 10 * v;
    return Vec3(x, y, 3.0 * std::exp(-((x - 5) * (x - 5) + (y - 5) * (y - 5)) / 1.5));
  });
  const CornerSpec corners = CornerSpec::at_vertices({0, n, (n + 1) * (n + 1) - 1, n * (n + 1)});
  TargetPatchOptions options;
  const TargetPatch smoothed = make_target_patch(mesh, corners, options);
  expect_consistent_report(mesh, smoothed);
  EXPECT_FALSE(smoothed.coverability.injectivity_ok);
  EXPECT_GT(smoothed.smoothing.iterations, 0);
  EXPECT_GT(smoothed.smoothing.eta_before, options.coverability.eta_max);
  EXPECT_LE(smoothed.smoothing.eta_after, options.coverability.eta_max);
  EXPECT_LT(smoothed.area, surface_area(mesh));  // the bump is flattened
  options.smooth = false;
  const TargetPatch raw = make_target_patch(mesh, corners, options);
  expect_consistent_report(mesh, raw);
  EXPECT_EQ(raw.smoothing.iterations, 0);
  EXPECT_EQ(raw.smoothing.eta_after, raw.coverability.gap.eta);
  EXPECT_NEAR(raw.area, surface_area(mesh), 1e-9 * raw.area);  // the whole grid, unsmoothed
}

TEST(MakeTargetPatch, BadPointCornersNameThePoint) {
  const ExampleSurface example = make_example("hypar", 0.5);
  CornerSpec spec;
  spec.kind = CornerSpec::Kind::Points;
  for (int i = 0; i < 4; ++i) spec.points[i] = example.mesh.vertices()[example.corners[i]];
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  CornerSpec bad = spec;
  bad.points[2].y() = nan;
  EXPECT_EQ(corner_error(example.mesh, bad), "corners.points[2]");
  bad = spec;
  bad.points[0].x() = -inf;
  EXPECT_EQ(corner_error(example.mesh, bad), "corners.points[0]");
  bad = spec;
  bad.points[3].z() = 2e15;  // beyond kMaxCoordinate
  EXPECT_EQ(corner_error(example.mesh, bad), "corners.points[3]");
  bad = spec;
  bad.points[1] = Vec3(nan, nan, nan);
  bad.points[3] = Vec3(nan, 0, 0);
  EXPECT_EQ(corner_error(example.mesh, bad), "corners.points[1]");  // the first bad one
}

TEST(MakeTargetPatch, BadVertexCornersNameTheVertex) {
  const ExampleSurface example = make_example("hypar", 0.5);
  const TriangleMesh& mesh = example.mesh;
  std::array<int, 4> v = example.corners;
  v[1] = -1;
  EXPECT_EQ(corner_error(mesh, CornerSpec::at_vertices(v)), "corners.vertices[1]");
  v = example.corners;
  v[3] = mesh.vertex_count();
  EXPECT_EQ(corner_error(mesh, CornerSpec::at_vertices(v)), "corners.vertices[3]");
  // An isolated vertex names no face.
  std::vector<Vec3> vertices = mesh.vertices();
  vertices.push_back(Vec3(0, 0, 100));
  const TriangleMesh with_isolated(vertices, mesh.faces());
  v = example.corners;
  v[0] = mesh.vertex_count();
  EXPECT_EQ(corner_error(with_isolated, CornerSpec::at_vertices(v)), "corners.vertices[0]");
}

// Moved unchanged from tests/design/test_patch.cpp.
TEST(TargetPatch, PointCornersInsideFacesBecomeVertices) {
  const ExampleSurface sphere = make_example("sphere");
  CornerSpec spec;
  spec.kind = CornerSpec::Kind::Points;
  // Points above the surface near the middle of four faces: snapped to the closest surface point.
  for (int i = 0; i < 4; ++i) {
    const Face& f = sphere.mesh.faces()[(i + 1) * sphere.mesh.face_count() / 5];
    spec.points[i] = (sphere.mesh.vertices()[f[0]] + sphere.mesh.vertices()[f[1]] +
                      sphere.mesh.vertices()[f[2]]) /
                     3;
  }
  // Order them counter-clockwise around their centroid (seen from above).
  Vec3 center = Vec3::Zero();
  for (const Vec3& p : spec.points) center += p / 4;
  std::sort(spec.points.begin(), spec.points.end(), [&](const Vec3& a, const Vec3& b) {
    return std::atan2(a.y() - center.y(), a.x() - center.x()) <
           std::atan2(b.y() - center.y(), b.x() - center.x());
  });
  const TargetPatch result = make_target_patch(sphere.mesh, spec);
  for (int i = 0; i < 4; ++i) {
    const Vec3& corner = result.patch.mesh.vertices()[result.patch.corners[i]];
    EXPECT_LT((corner - result.input_corners[i].position(sphere.mesh)).norm(), 1e-9);
    EXPECT_EQ(result.patch.input_vertex[result.patch.corners[i]], -1);  // a new vertex
    EXPECT_LT(result.corner_angles[i], std::numbers::pi);
  }
  EXPECT_EQ(result.smoothing.iterations, 0);
}

}  // namespace
}  // namespace gridshell
