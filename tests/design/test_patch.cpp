// SPDX-License-Identifier: GPL-3.0-or-later
// Target patch: corner parsing, cutting along boundary geodesics, grid criterion (iv).
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "gridshell/design/patch.h"
#include "gridshell/design/target_patch.h"
#include "gridshell/example_surfaces.h"
#include "gridshell/foundation/errors.h"
#include "gridshell/geodesic/geodesic.h"
#include "gridshell/mesh/mesh_io.h"
#include "gridshell/mesh/mesh_topology.h"
#include "gridshell/mesh/surface_distance.h"
#include "support.h"

namespace gridshell {
namespace {

using testing::bump;
using testing::flat_square;
using testing::grid_mesh;

std::array<SurfacePoint, 4> points(const TriangleMesh& mesh, const std::array<Vec3, 4>& p) {
  return {closest_surface_point(mesh, p[0]), closest_surface_point(mesh, p[1]),
          closest_surface_point(mesh, p[2]), closest_surface_point(mesh, p[3])};
}

double planar_angle(const Vec3& prev, const Vec3& at, const Vec3& next) {
  const Vec3 a = prev - at, b = next - at;
  return std::atan2(a.cross(b).norm(), a.dot(b));
}

TEST(AutoCorners, FindsTheFourCornersOfASquare) {
  const TriangleMesh mesh = flat_square(10);
  auto corners = auto_corners(mesh);
  std::sort(corners.begin(), corners.end());
  EXPECT_EQ(corners, (std::array<int, 4>{0, 10, 110, 120}));
}

TEST(CutPatch, PlanarQuadrilateralHasExactAreaSidesAndAngles) {
  const TriangleMesh mesh = flat_square(24);
  const std::array<Vec3, 4> q{Vec3(2, 1, 0), Vec3(8.3, 2.2, 0), Vec3(9, 9, 0), Vec3(1.1, 7.3, 0)};
  const Patch patch = cut_patch(mesh, points(mesh, q));
  EXPECT_FALSE(patch.corners_reversed);
  // Shoelace area of the quadrilateral.
  double area = 0;
  for (int i = 0; i < 4; ++i) area += 0.5 * q[i].cross(q[(i + 1) % 4]).z();
  EXPECT_NEAR(surface_area(patch.mesh), area, 1e-9 * area);
  const auto lengths = side_lengths(patch);
  const auto angles = corner_angles(patch);
  for (int i = 0; i < 4; ++i) {
    EXPECT_NEAR(lengths[i], (q[(i + 1) % 4] - q[i]).norm(), 1e-9) << "side " << i;
    EXPECT_NEAR(angles[i], planar_angle(q[(i + 3) % 4], q[i], q[(i + 1) % 4]), 1e-9);
    EXPECT_LT((patch.mesh.vertices()[patch.corners[i]] - q[i]).norm(), 1e-12);
  }
  // The boundary is exactly the four sides.
  const MeshTopology& topology = patch.mesh.topology();
  ASSERT_EQ(topology.boundary_loops.size(), 1u);
  size_t side_vertices = 0;
  for (const auto& side : patch.sides) {
    side_vertices += side.size() - 1;
    for (int v : side) EXPECT_TRUE(topology.is_boundary_vertex[v]);
  }
  EXPECT_EQ(topology.boundary_loops[0].size(), side_vertices);
  EXPECT_NO_THROW(check_convex_corners(patch));
}

TEST(CutPatch, ClockwiseCornersGiveTheSamePatch) {
  const TriangleMesh mesh = flat_square(24);
  const std::array<Vec3, 4> q{Vec3(2, 1, 0), Vec3(8.3, 2.2, 0), Vec3(9, 9, 0), Vec3(1.1, 7.3, 0)};
  const Patch ccw = cut_patch(mesh, points(mesh, q));
  const Patch cw = cut_patch(mesh, points(mesh, {q[0], q[3], q[2], q[1]}));
  EXPECT_TRUE(cw.corners_reversed);
  EXPECT_NEAR(surface_area(cw.mesh), surface_area(ccw.mesh), 1e-9);
  EXPECT_EQ(cw.mesh.vertex_count(), ccw.mesh.vertex_count());
  // Corners are reordered counter-clockwise: same cyclic sequence as the ccw input.
  for (int i = 0; i < 4; ++i)
    EXPECT_LT((cw.mesh.vertices()[cw.corners[i]] - ccw.mesh.vertices()[ccw.corners[i]]).norm(),
              1e-12);
}

TEST(CutPatch, CornersOnTheBoundaryOfAConvexMeshKeepEverything) {
  const TriangleMesh mesh = flat_square(12);
  std::array<SurfacePoint, 4> corners{
      SurfacePoint::at_vertex(mesh, 0), SurfacePoint::at_vertex(mesh, 12),
      SurfacePoint::at_vertex(mesh, 168), SurfacePoint::at_vertex(mesh, 156)};
  const Patch patch = cut_patch(mesh, corners);
  EXPECT_EQ(patch.mesh.vertex_count(), mesh.vertex_count());
  EXPECT_EQ(patch.mesh.face_count(), mesh.face_count());
  EXPECT_NEAR(surface_area(patch.mesh), 100.0, 1e-9);
  for (double l : side_lengths(patch)) EXPECT_NEAR(l, 10.0, 1e-12);
  for (double a : corner_angles(patch)) EXPECT_NEAR(a, std::numbers::pi / 2, 1e-12);
  for (int i = 0; i < 4; ++i)
    EXPECT_EQ(patch.input_vertex[patch.corners[i]], corners[i].vertex(mesh));
}

TEST(CutPatch, CurvedSurfaceSidesAreShortestGeodesics) {
  const TriangleMesh mesh = bump(30);
  const std::array<Vec3, 4> q{Vec3(1.3, 0.8, 0), Vec3(9.1, 1.7, 0), Vec3(8.6, 9.2, 0),
                              Vec3(0.7, 8.4, 0)};
  // Corners: points of the analytic surface, snapped to the mesh.
  std::array<SurfacePoint, 4> corners;
  for (int i = 0; i < 4; ++i) {
    const double z =
        2.5 * std::exp(-((q[i].x() - 5) * (q[i].x() - 5) + (q[i].y() - 5) * (q[i].y() - 5)) / 8);
    corners[i] = closest_surface_point(mesh, Vec3(q[i].x(), q[i].y(), z));
  }
  const Patch patch = cut_patch(mesh, corners);
  const GeodesicSolver solver(mesh);
  const auto lengths = side_lengths(patch);
  for (int i = 0; i < 4; ++i) {
    const double exact = solver.solve(corners[i]).distance_to(corners[(i + 1) % 4]);
    EXPECT_NEAR(lengths[i], exact, 1e-9 * exact) << "side " << i;
  }
  EXPECT_LT(surface_area(patch.mesh), surface_area(mesh));
  // Each side is a global shortest path lying in the patch, so it is also the shortest path
  // between its corners on the cut patch: the cut must not have changed its length.
  const GeodesicSolver inside(patch.mesh);
  for (int i = 0; i < 4; ++i) {
    const double d = inside.solve(SurfacePoint::at_vertex(patch.mesh, patch.corners[i]))
                         .vertex_distances()[patch.corners[(i + 1) % 4]];
    EXPECT_NEAR(d, lengths[i], 1e-9 * lengths[i]) << "side " << i;
  }
}

TEST(CutPatch, CrossingBoundaryGeodesicsAreInfeasible) {
  const TriangleMesh mesh = flat_square(24);
  const std::array<Vec3, 4> bow_tie{Vec3(2, 2, 0), Vec3(8, 8, 0), Vec3(8, 2, 0), Vec3(2, 8, 0)};
  try {
    cut_patch(mesh, points(mesh, bow_tie));
    FAIL() << "bow tie accepted";
  } catch (const Infeasible& e) {
    EXPECT_NE(std::string(e.what()).find("criterion iv"), std::string::npos) << e.what();
  }
}

TEST(CutPatch, ReflexCornerIsInfeasible) {
  const TriangleMesh mesh = flat_square(24);
  const std::array<Vec3, 4> dart{Vec3(1, 1, 0), Vec3(9, 1, 0), Vec3(4, 4, 0), Vec3(1, 9, 0)};
  const Patch patch = cut_patch(mesh, points(mesh, dart));
  try {
    check_convex_corners(patch);
    FAIL() << "reflex corner accepted";
  } catch (const Infeasible& e) {
    EXPECT_NE(std::string(e.what()).find("corner c2"), std::string::npos) << e.what();
  }
}

TEST(CutPatch, CoincidentCornersAreInvalid) {
  const TriangleMesh mesh = flat_square(8);
  const SurfacePoint a = SurfacePoint::at_vertex(mesh, 10);
  EXPECT_THROW(
      cut_patch(mesh, {a, SurfacePoint::at_vertex(mesh, 12), a, SurfacePoint::at_vertex(mesh, 30)}),
      InvalidInput);
}

// Invariants of a cut on a real surface: the boundary is exactly the four sides, each side is
// as long as the exact geodesic distance between its corners on the input, vertices kept from
// the input have not moved, and the patch is part of the input's area.
void expect_consistent_cut(const TriangleMesh& input, const std::array<int, 4>& corner_vertices,
                           const std::string& name) {
  SCOPED_TRACE(name);
  std::array<SurfacePoint, 4> corners;
  for (int i = 0; i < 4; ++i) corners[i] = SurfacePoint::at_vertex(input, corner_vertices[i]);
  const Patch patch = cut_patch(input, corners);
  const MeshTopology& topology = patch.mesh.topology();
  ASSERT_EQ(topology.boundary_loops.size(), 1u);
  size_t side_vertices = 0;
  for (const auto& side : patch.sides) side_vertices += side.size() - 1;
  EXPECT_EQ(topology.boundary_loops[0].size(), side_vertices);
  const GeodesicSolver solver(input);
  const auto lengths = side_lengths(patch);
  for (int i = 0; i < 4; ++i) {
    const double exact = solver.solve(corners[i]).vertex_distances()[corner_vertices[(i + 1) % 4]];
    EXPECT_NEAR(lengths[i], exact, 1e-9 * exact) << "side " << i;
    EXPECT_EQ(patch.input_vertex[patch.corners[i]],
              corner_vertices[patch.corners_reversed ? (4 - i) % 4 : i]);
  }
  for (int v = 0; v < patch.mesh.vertex_count(); ++v)
    if (patch.input_vertex[v] >= 0) {
      EXPECT_EQ(patch.mesh.vertices()[v], input.vertices()[patch.input_vertex[v]]);
    }
  EXPECT_LE(surface_area(patch.mesh), surface_area(input) * (1 + 1e-12));
  EXPECT_GT(surface_area(patch.mesh), 0.0);
  const auto angles = corner_angles(patch);
  for (double a : angles) EXPECT_LT(a, std::numbers::pi);
}

TEST(CutPatch, ConsistentOnEveryExampleSurface) {
  for (const std::string& name : example_names()) {
    const ExampleSurface example = make_example(name);
    expect_consistent_cut(example.mesh, example.corners, name);
  }
}

TEST(CutPatch, ConsistentOnTheSharedMeshesWithAutoCorners) {
  for (const std::string& path : testing::test_mesh_paths()) {
    const TriangleMesh mesh = load_mesh(path);
    expect_consistent_cut(mesh, auto_corners(mesh), path);
  }
}

}  // namespace
}  // namespace gridshell
