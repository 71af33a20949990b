// SPDX-License-Identifier: GPL-3.0-or-later
// Any manifold surface as target (issue 18 item 1) and exact boundaries after smoothing (item
// 3): patches cut out of meshes with holes, closed meshes and meshes with handles, with corners
// anywhere; the patch must be a disk bounded by the four geodesics, else Infeasible saying which
// case and where. Every patch's sides are checked to be shortest geodesics of the final patch
// with the CGAL engine as an independent oracle, and against closed forms on flat meshes.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <set>
#include <string>

#include "gridshell/design/target_patch.h"
#include "gridshell/foundation/errors.h"
#include "gridshell/mesh/curvature.h"
#include "support.h"

namespace gridshell {
namespace {

constexpr double kPi = std::numbers::pi;

using testing::annulus;
using testing::grid_mesh;
using testing::icosphere;

/// V - E + F of a mesh and its number of boundary loops: a disk has (1, 1).
std::pair<long long, size_t> topology_of(const TriangleMesh& mesh) {
  std::set<std::pair<int, int>> edges;
  for (const Face& f : mesh.faces())
    for (int i = 0; i < 3; ++i)
      edges.insert({std::min(f[i], f[(i + 1) % 3]), std::max(f[i], f[(i + 1) % 3])});
  return {static_cast<long long>(mesh.vertex_count()) - static_cast<long long>(edges.size()) +
              mesh.face_count(),
          mesh.topology().boundary_loops.size()};
}

/// The patch is a disk and every side is an exact shortest geodesic of it: its polyline length
/// equals the CGAL engine's distance between its corners on the final patch (to 1e-9).
void expect_disk_with_exact_sides(const TargetPatch& target) {
  const Patch& patch = target.patch;
  const auto [euler, loops] = topology_of(patch.mesh);
  EXPECT_EQ(euler, 1);
  EXPECT_EQ(loops, 1u);
  const GeodesicSolver oracle(patch.mesh, GeodesicOptions{GeodesicMethod::Cgal});
  const std::array<double, 4> lengths = side_lengths(patch);
  for (int i = 0; i < 4; ++i) {
    const double d = oracle.distances(
        SurfacePoint::at_vertex(patch.mesh, patch.corners[i]))[patch.corners[(i + 1) % 4]];
    EXPECT_NEAR(lengths[i], d, 1e-9 * lengths[i]) << "side " << i;
    EXPECT_LE(target.boundary_excess[i], kBoundaryGeodesicTolerance) << "side " << i;
  }
}

std::string infeasible_message(const TriangleMesh& mesh, const CornerSpec& spec) {
  try {
    make_target_patch(mesh, spec);
  } catch (const Infeasible& e) {
    EXPECT_EQ(e.field(), "corners");
    return e.message();
  } catch (const std::exception& e) {
    ADD_FAILURE() << "expected Infeasible, got: " << e.what();
    return "";
  }
  ADD_FAILURE() << "no exception";
  return "";
}

double shoelace(const std::array<Vec3, 4>& p) {
  double a = 0;
  for (int i = 0; i < 4; ++i) a += p[i].x() * p[(i + 1) % 4].y() - p[(i + 1) % 4].x() * p[i].y();
  return 0.5 * a;
}

// ---- Several boundary loops ------------------------------------------------------------------

TEST(AnySurface, AnnulusSectorIsADiskWithStraightSides) {
  // Flat annulus 1 <= r <= 3, 8 rings, 64 sectors; corners on rings 2 and 6 at sectors 0 and 6:
  // every side is a straight segment (no chord reaches the hole), so lengths and area have
  // closed forms.
  const TriangleMesh mesh = annulus(1, 3, 8, 64);
  ASSERT_EQ(mesh.topology().boundary_loops.size(), 2u);
  const std::array<int, 4> corners{6 * 64 + 0, 6 * 64 + 6, 2 * 64 + 6, 2 * 64 + 0};
  const TargetPatch target = make_target_patch(mesh, CornerSpec::at_vertices(corners));
  expect_disk_with_exact_sides(target);
  std::array<Vec3, 4> p;
  for (int i = 0; i < 4; ++i) p[i] = mesh.vertices()[corners[i]];
  for (int i = 0; i < 4; ++i)
    EXPECT_NEAR(target.boundary_lengths[i], (p[(i + 1) % 4] - p[i]).norm(), 1e-12) << i;
  EXPECT_NEAR(target.area, shoelace(p), 1e-10);
  EXPECT_FALSE(target.patch.corners_reversed);
}

TEST(AnySurface, LoopAroundAHoleIsNotADiskAndSaysWhere) {
  // Four corners at radius 2, 90 degrees apart: the chords pass the hole (radius 1) at 1.41, so
  // the loop goes round the hole.
  const TriangleMesh mesh = annulus(1, 3, 8, 64);
  const std::string message = infeasible_message(
      mesh, CornerSpec::at_vertices({4 * 64, 4 * 64 + 16, 4 * 64 + 32, 4 * 64 + 48}));
  EXPECT_NE(message.find("not a disk"), std::string::npos) << message;
  EXPECT_NE(message.find("contains a hole"), std::string::npos) << message;
  // The place named is on the hole's boundary (radius 1).
  const size_t open = message.find("hole of the mesh (a boundary edge at (");
  ASSERT_NE(open, std::string::npos) << message;
  double x = 0, y = 0;
  ASSERT_EQ(std::sscanf(message.c_str() + open + 39, "%lf, %lf", &x, &y), 2) << message;
  EXPECT_NEAR(std::hypot(x, y), 1.0, 1e-5) << message;  // printed to 6 digits
}

TEST(AnySurface, CornersOnSeparatePiecesAreNamed) {
  // Two unit squares far apart, as one mesh.
  const TriangleMesh a = grid_mesh(4, 4, [](double u, double v) { return Vec3(u, v, 0); });
  std::vector<Vec3> vertices = a.vertices();
  std::vector<Face> faces = a.faces();
  const int n = a.vertex_count();
  for (const Vec3& p : a.vertices()) vertices.push_back(p + Vec3(5, 0, 0));
  for (Face f : a.faces()) faces.push_back({f[0] + n, f[1] + n, f[2] + n});
  const TriangleMesh mesh(std::move(vertices), std::move(faces));
  const std::string message =
      infeasible_message(mesh, CornerSpec::at_vertices({0, 4, n + 24, n + 20}));
  EXPECT_NE(message.find("separate pieces"), std::string::npos) << message;
}

// ---- Closed meshes ---------------------------------------------------------------------------

TEST(AnySurface, ClosedSphereWithCornersInsideCutsTheConvexSide) {
  const double radius = 10;
  const TriangleMesh sphere = icosphere(3, radius);  // 642 vertices
  ASSERT_TRUE(sphere.topology().boundary_loops.empty());
  // A geodesic square about the north pole, counter-clockwise seen from outside.
  CornerSpec spec;
  spec.kind = CornerSpec::Kind::Points;
  const double polar = 40 * kPi / 180;
  for (int k = 0; k < 4; ++k) {
    const double azimuth = kPi / 4 + k * kPi / 2;
    spec.points[k] = radius * Vec3(std::sin(polar) * std::cos(azimuth),
                                   std::sin(polar) * std::sin(azimuth), std::cos(polar));
  }
  const TargetPatch target = make_target_patch(sphere, spec);
  expect_disk_with_exact_sides(target);
  EXPECT_FALSE(target.patch.corners_reversed);
  // The sides are straight: a shortest path on a surface without saddles passes no vertex, so
  // every boundary point but the corners has angle sum pi on the patch.
  const std::vector<double> sums = vertex_angle_sums(target.patch.mesh);
  for (int i = 0; i < 4; ++i)
    for (size_t k = 1; k + 1 < target.patch.sides[i].size(); ++k)
      EXPECT_NEAR(sums[target.patch.sides[i][k]], kPi, 1e-9) << "side " << i << " point " << k;
  // Gauss-Bonnet on the sphere: area = R^2 (sum of corner angles - 2 pi) for a geodesic
  // quadrilateral; on this polyhedron (edges ~1.5) to 10 %.
  double sum = 0;
  for (double a : target.corner_angles) sum += a;
  EXPECT_NEAR(target.area, radius * radius * (sum - 2 * kPi), 0.1 * target.area);
  EXPECT_LT(target.area, 0.5 * surface_area(sphere));
  // Clockwise corners give the same region (reported as reversed), not its complement.
  CornerSpec clockwise = spec;
  std::swap(clockwise.points[1], clockwise.points[3]);
  const TargetPatch reversed = make_target_patch(sphere, clockwise);
  EXPECT_TRUE(reversed.patch.corners_reversed);
  EXPECT_NEAR(reversed.area, target.area, 1e-9 * target.area);
}

TEST(AnySurface, LoopAroundATorusTubeDoesNotBoundARegion) {
  // A torus (R = 3, r = 1); corners on one meridian go round the tube: the loop does not
  // separate the surface. A small square on the outer equator is a disk.
  const int nu = 48, nv = 24;
  const TriangleMesh torus = testing::torus(3, 1, nu, nv);
  auto id = [&](int i, int j) { return (j % nv) * nu + (i % nu); };
  const std::string message = infeasible_message(
      torus, CornerSpec::at_vertices({id(0, 0), id(0, 6), id(0, 12), id(0, 18)}));
  EXPECT_TRUE(message.find("do not bound a region") != std::string::npos ||
              message.find("touch or cross") != std::string::npos)
      << message;
  const TargetPatch square =
      make_target_patch(torus, CornerSpec::at_vertices({id(0, 22), id(6, 22), id(6, 2), id(0, 2)}));
  expect_disk_with_exact_sides(square);
}

// ---- Smoothing keeps exact boundaries (item 3) -----------------------------------------------

/// A cone over the square [0,10]^2 with a slightly rounded apex (height 4) at (5, 2.5): the
/// Gaussian curvature sits in the small apex region, so the injectivity bound fails and the patch
/// is smoothed. Corners inside the square, so that side c0-c1 passes near the apex.
TriangleMesh apex_cone(int n) {
  return grid_mesh(n, n, [](double u, double v) {
    const double x = 10 * u, y = 10 * v;
    return Vec3(x, y, 4 * (1 - std::sqrt((x - 5) * (x - 5) + (y - 2.5) * (y - 2.5) + 1e-4) / 7.5));
  });
}

std::array<int, 4> apex_cone_corners(int n) {
  const int a = n / 8, b = n - n / 8;
  return {a * (n + 1) + a, a * (n + 1) + b, b * (n + 1) + b, b * (n + 1) + a};
}

TEST(SmoothingRecut, ConeWithASmoothedApexKeepsShortestGeodesicBoundaries) {
  const int n = 24;
  const TriangleMesh cone = apex_cone(n);
  const std::array<int, 4> corners = apex_cone_corners(n);
  const TargetPatch target = make_target_patch(cone, CornerSpec::at_vertices(corners));
  EXPECT_FALSE(target.coverability.injectivity_ok);
  EXPECT_GT(target.smoothing.iterations, 0);
  EXPECT_LE(target.smoothing.eta_after, 1.0015);
  expect_disk_with_exact_sides(target);
  EXPECT_TRUE(target.warnings.empty());

  // Without the re-cut (the former behaviour: smoothing with the boundary held), the sides are
  // no longer shortest geodesics of the smoothed patch: what the re-cut repairs.
  Patch held = cut_patch(
      cone, {SurfacePoint::at_vertex(cone, corners[0]), SurfacePoint::at_vertex(cone, corners[1]),
             SurfacePoint::at_vertex(cone, corners[2]), SurfacePoint::at_vertex(cone, corners[3])});
  std::vector<char> fixed(held.mesh.vertex_count(), 0);
  for (int v = 0; v < held.mesh.vertex_count(); ++v)
    fixed[v] = held.mesh.topology().is_boundary_vertex[v];
  for (int k = 0; k < target.smoothing.iterations; ++k)
    laplacian_smoothing_step(held.mesh, fixed, 0.5);
  const std::array<double, 4> excess = boundary_geodesic_excess(held);
  EXPECT_GT(*std::max_element(excess.begin(), excess.end()), 1e-6);
  EXPECT_GE(target.smoothing.recuts, 1);
}

TEST(SmoothingRecut, EtaAboveEtaMaxIsNeverSilent) {
  // With smoothing off, a patch whose gap factor is above eta_max gets a warning.
  const TriangleMesh cone = apex_cone(24);
  TargetPatchOptions options;
  options.smooth = false;
  const TargetPatch target =
      make_target_patch(cone, CornerSpec::at_vertices(apex_cone_corners(24)), options);
  ASSERT_GT(target.smoothing.eta_after, options.coverability.eta_max);
  ASSERT_EQ(target.warnings.size(), 1u);
  EXPECT_NE(target.warnings[0].find("smoothing is off"), std::string::npos) << target.warnings[0];
}

TEST(SmoothingRecut, CapReachedNamesEtaAndTheBoundary) {
  const TriangleMesh cone = apex_cone(24);
  TargetPatchOptions options;
  options.coverability.max_smoothing_iterations = 1;
  const std::string message = [&] {
    try {
      make_target_patch(cone, CornerSpec::at_vertices(apex_cone_corners(24)), options);
    } catch (const Infeasible& e) {
      return e.message();
    }
    return std::string();
  }();
  EXPECT_NE(message.find("gap factor eta"), std::string::npos) << message;
  EXPECT_NE(message.find("boundary exceeds the shortest geodesics"), std::string::npos) << message;
}

}  // namespace
}  // namespace gridshell
