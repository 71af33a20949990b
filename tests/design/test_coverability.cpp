// SPDX-License-Identifier: GPL-3.0-or-later
// Injectivity bound, gap factor eta and smoothing (paper 3.3). The discrete Gaussian curvature
// itself is tested in tests/mesh/test_curvature.cpp.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "gridshell/design/coverability.h"
#include "gridshell/foundation/errors.h"
#include "gridshell/mesh/curvature.h"
#include "gridshell/mesh/mesh_topology.h"
#include "support.h"

namespace gridshell {
namespace {

using testing::grid_mesh;

Patch whole_grid_patch(const TriangleMesh& mesh, int n) {
  const std::array<SurfacePoint, 4> corners{SurfacePoint::at_vertex(mesh, 0),
                                            SurfacePoint::at_vertex(mesh, n),
                                            SurfacePoint::at_vertex(mesh, (n + 1) * (n + 1) - 1),
                                            SurfacePoint::at_vertex(mesh, n * (n + 1))};
  return cut_patch(mesh, corners);
}

TriangleMesh sharp_bump(int n, double height) {
  return grid_mesh(n, n, [height](double u, double v) {
    const double x = 10 * u, y = 10 * v;
    return Vec3(x, y, height * std::exp(-((x - 5) * (x - 5) + (y - 5) * (y - 5)) / 1.5));
  });
}

TEST(Coverability, FlatPatchHasNoGapAndInfiniteInjectivityBound) {
  const int n = 16;
  const TriangleMesh mesh =
      grid_mesh(n, n, [](double u, double v) { return Vec3(10 * u, 6 * v, 0); });
  const Patch patch = whole_grid_patch(mesh, n);
  const CoverabilityReport report = analyze_coverability(patch);
  EXPECT_TRUE(report.injectivity_ok);
  EXPECT_GT(report.injectivity_bound, 1e6);
  EXPECT_NEAR(report.longest_member_distance, std::hypot(10.0, 6.0), 1e-9);
  EXPECT_GE(report.gap.eta, 1.0 - 1e-12);
  EXPECT_LT(report.gap.eta, 1.0 + 1e-3);
}

TEST(Coverability, InjectivityBoundIsPiOverSqrtKmax) {
  const int n = 24;
  const TriangleMesh mesh = sharp_bump(n, 1.0);
  const Patch patch = whole_grid_patch(mesh, n);
  const CoverabilityReport report = analyze_coverability(patch);
  const std::vector<double> k = gaussian_curvature(patch.mesh);
  EXPECT_DOUBLE_EQ(report.gaussian_curvature_max, k[report.gaussian_curvature_max_vertex]);
  EXPECT_DOUBLE_EQ(report.injectivity_bound,
                   std::numbers::pi / std::sqrt(report.gaussian_curvature_max));
}

// The longest member distance comes from sources solved in parallel: the same for any thread
// count, and bounded by the brute-force maximum over all pairs of opposite side vertices (the
// sources are a sample of one side's vertices).
TEST(Coverability, LongestMemberDistanceDoesNotDependOnThreads) {
  const int n = 24;
  const TriangleMesh mesh = sharp_bump(n, 1.0);
  const Patch patch = whole_grid_patch(mesh, n);
  std::vector<double> longest;
  for (int threads : {1, 2, 5}) {
    CoverabilityOptions options;
    options.threads = threads;
    longest.push_back(analyze_coverability(patch, {}, options).longest_member_distance);
  }
  EXPECT_EQ(longest[0], longest[1]);
  EXPECT_EQ(longest[0], longest[2]);
  const GeodesicSolver solver(patch.mesh);
  double all_pairs = 0, corner_to_corner = 0;
  for (int s = 0; s < 2; ++s)
    for (int v : patch.sides[s]) {
      const std::vector<double> d = solver.distances(SurfacePoint::at_vertex(patch.mesh, v));
      for (int q : patch.sides[s + 2]) all_pairs = std::max(all_pairs, d[q]);
      if (v == patch.sides[s].front())
        corner_to_corner = std::max(corner_to_corner, d[patch.sides[s + 2].back()]);
    }
  EXPECT_LE(longest[0], all_pairs);
  EXPECT_GE(longest[0], corner_to_corner);  // the sample includes each side's first vertex
  EXPECT_GT(longest[0], 0.9 * all_pairs);
}

TEST(Coverability, SharpBumpHasAGapThatSmoothingCloses) {
  const int n = 30;
  const TriangleMesh mesh = sharp_bump(n, 3.0);
  Patch patch = whole_grid_patch(mesh, n);
  const CoverabilityReport report = analyze_coverability(patch);
  EXPECT_FALSE(report.injectivity_ok);
  EXPECT_GT(report.gap.eta, 1.0015);
  // The peak is the top of the bump; q1 is on the side opposite p1.
  EXPECT_LT((patch.mesh.vertices()[report.gap.peak] - Vec3(5, 5, 3)).head<2>().norm(), 1.0);
  const std::vector<Vec3> before = patch.mesh.vertices();
  const SmoothingResult result = smooth_until_coverable(patch);
  EXPECT_NEAR(result.eta_before, report.gap.eta, 1e-12);
  EXPECT_GT(result.iterations, 0);
  EXPECT_LE(result.eta_after, 1.0015);
  EXPECT_GT(result.max_displacement, 0.0);
  const MeshTopology& topology = patch.mesh.topology();
  for (int v = 0; v < patch.mesh.vertex_count(); ++v)
    if (topology.is_boundary_vertex[v]) {
      EXPECT_EQ(patch.mesh.vertices()[v], before[v]) << v;
    }
}

TEST(Coverability, SmoothingCapIsInfeasible) {
  const int n = 30;
  Patch patch = whole_grid_patch(sharp_bump(n, 3.0), n);
  CoverabilityOptions options;
  options.max_smoothing_iterations = 1;
  try {
    smooth_until_coverable(patch, {}, options);
    FAIL() << "cap not enforced";
  } catch (const Infeasible& e) {
    EXPECT_NE(std::string(e.what()).find("eta"), std::string::npos) << e.what();
  }
}

TEST(LaplacianSmoothing, KeepsAPlaneFlatAndFixedVerticesFixed) {
  TriangleMesh mesh = grid_mesh(
      10, 10, [](double u, double v) { return Vec3(10 * u + 0.3 * std::sin(9 * v), 10 * v, 0); });
  const MeshTopology& topology = mesh.topology();
  std::vector<char> fixed(topology.is_boundary_vertex.begin(), topology.is_boundary_vertex.end());
  const std::vector<Vec3> before = mesh.vertices();
  const double moved = laplacian_smoothing_step(mesh, fixed, 0.5);
  EXPECT_GT(moved, 0.0);
  for (int v = 0; v < mesh.vertex_count(); ++v) {
    EXPECT_NEAR(mesh.vertices()[v].z(), 0.0, 1e-12);
    if (fixed[v]) {
      EXPECT_EQ(mesh.vertices()[v], before[v]);
    }
  }
}

TEST(LaplacianSmoothing, FlattensABump) {
  TriangleMesh mesh = sharp_bump(20, 3.0);
  const MeshTopology& topology = mesh.topology();
  std::vector<char> fixed(topology.is_boundary_vertex.begin(), topology.is_boundary_vertex.end());
  auto height = [&] {
    double h = 0;
    for (const Vec3& p : mesh.vertices()) h = std::max(h, p.z());
    return h;
  };
  const double h0 = height();
  laplacian_smoothing_step(mesh, fixed, 0.5);
  const double h1 = height();
  laplacian_smoothing_step(mesh, fixed, 0.5);
  EXPECT_LT(h1, h0);
  EXPECT_LT(height(), h1);
}

}  // namespace
}  // namespace gridshell
