// SPDX-License-Identifier: GPL-3.0-or-later
// Discrete curvature (gridshell/mesh/curvature.h): Gaussian curvature against closed forms,
// incident angle sums, mixed Voronoi and barycentric vertex areas against closed forms and the
// surface area, and the discrete Gauss-Bonnet theorem.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <numeric>
#include <vector>

#include "gridshell/mesh/curvature.h"
#include "gridshell/mesh/mesh.h"
#include "gridshell/mesh/mesh_topology.h"
#include "support.h"

namespace gridshell {
namespace {

constexpr double kPi = std::numbers::pi;

using testing::bump;
using testing::flat_square;
using testing::grid_mesh;
using testing::icosphere;

double sum(const std::vector<double>& values) {
  return std::accumulate(values.begin(), values.end(), 0.0);
}

/// A spherical cap of radius R over a square grid of (polar-ish) angles in [-0.6, 0.6]^2.
TriangleMesh cap(int n, double R) {
  return grid_mesh(n, n, [R](double u, double v) {
    const double theta = (u - 0.5) * 1.2, phi = (v - 0.5) * 1.2;
    return Vec3(R * std::sin(theta) * std::cos(phi), R * std::sin(phi),
                R * std::cos(theta) * std::cos(phi));
  });
}

// ---------------------------------------------------------------------------------------------
// Gaussian curvature (moved here from tests/design/test_coverability.cpp)

TEST(GaussianCurvature, SphereIsOneOverRSquared) {
  const double R = 7;
  const TriangleMesh mesh = grid_mesh(40, 40, [R](double u, double v) {
    const double theta = (u - 0.5) * 1.2, phi = (v - 0.5) * 1.2;
    return Vec3(R * std::sin(theta) * std::cos(phi), R * std::sin(phi),
                R * std::cos(theta) * std::cos(phi));
  });
  const std::vector<double> k = gaussian_curvature(mesh);
  const MeshTopology& topology = mesh.topology();
  for (int v = 0; v < mesh.vertex_count(); ++v)
    if (!topology.is_boundary_vertex[v]) {
      EXPECT_NEAR(k[v] * R * R, 1.0, 0.05) << v;
    }
}

TEST(GaussianCurvature, DevelopableSurfacesAreFlat) {
  const TriangleMesh plane =
      grid_mesh(12, 9, [](double u, double v) { return Vec3(5 * u, 3 * v + u * u, 0); });
  const TriangleMesh cylinder = grid_mesh(16, 8, [](double u, double v) {
    return Vec3(3 * std::cos(2 * u), 3 * std::sin(2 * u), 4 * v);
  });
  for (const TriangleMesh* mesh : {&plane, &cylinder})
    for (double k : gaussian_curvature(*mesh)) EXPECT_NEAR(k, 0.0, 1e-9);
}

TEST(GaussianCurvature, SaddleIsNegative) {
  const TriangleMesh hypar = grid_mesh(16, 16, [](double u, double v) {
    return Vec3(u - 0.5, v - 0.5, (u - 0.5) * (u - 0.5) - (v - 0.5) * (v - 0.5));
  });
  const MeshTopology& topology = hypar.topology();
  const std::vector<double> k = gaussian_curvature(hypar);
  for (int v = 0; v < hypar.vertex_count(); ++v)
    if (!topology.is_boundary_vertex[v]) {
      EXPECT_LT(k[v], 0.0);
    }
}

// ---------------------------------------------------------------------------------------------
// More Gaussian curvature

TEST(GaussianCurvature, IsTheAngleDefectOverTheMixedAreaAndZeroOnTheBoundary) {
  const TriangleMesh mesh = bump(10);
  const std::vector<double> k = gaussian_curvature(mesh);
  const std::vector<double> sums = vertex_angle_sums(mesh);
  const std::vector<double> areas = mixed_voronoi_areas(mesh);
  const MeshTopology& topology = mesh.topology();
  for (int v = 0; v < mesh.vertex_count(); ++v) {
    if (topology.is_boundary_vertex[v]) {
      EXPECT_EQ(k[v], 0.0) << v;
    } else {
      EXPECT_NEAR(k[v], (2 * kPi - sums[v]) / areas[v], 1e-12 * std::abs(k[v]) + 1e-15) << v;
    }
  }
  // The top of the bump is curved positively.
  int top = 0;
  for (int v = 0; v < mesh.vertex_count(); ++v)
    if (mesh.vertices()[v].z() > mesh.vertices()[top].z()) top = v;
  EXPECT_GT(k[top], 0.0);
}

TEST(GaussianCurvature, ClosedSphereIsOneOverRSquared) {
  const double R = 2.5;
  const TriangleMesh mesh = icosphere(3, R);
  const std::vector<double> k = gaussian_curvature(mesh);
  double worst = 0;
  for (double kv : k) worst = std::max(worst, std::abs(kv * R * R - 1));
  EXPECT_LT(worst, 0.05);
}

// ---------------------------------------------------------------------------------------------
// Angle sums

TEST(VertexAngleSums, FlatMeshIsTwoPiInsideAndPiOrHalfPiOnTheBoundary) {
  const int n = 10;
  const TriangleMesh mesh = flat_square(n);
  const std::vector<double> sums = vertex_angle_sums(mesh);
  const MeshTopology& topology = mesh.topology();
  int corners = 0;
  for (int v = 0; v < mesh.vertex_count(); ++v) {
    const Vec3& p = mesh.vertices()[v];
    const bool at_corner =
        (p.x() == 0 || p.x() == 10) && (p.y() == 0 || p.y() == 10);  // unjittered boundary
    if (!topology.is_boundary_vertex[v]) {
      EXPECT_NEAR(sums[v], 2 * kPi, 1e-12) << v;
    } else if (at_corner) {
      ++corners;
      EXPECT_NEAR(sums[v], kPi / 2, 1e-12) << v;
    } else {
      EXPECT_NEAR(sums[v], kPi, 1e-12) << v;
    }
  }
  EXPECT_EQ(corners, 4);
  // The angles of every triangle sum to pi: the total is pi F.
  EXPECT_NEAR(sum(sums), kPi * mesh.face_count(), 1e-9);
}

TEST(VertexAngleSums, RegularIcosahedronHasFiveEquilateralAngles) {
  for (double s : vertex_angle_sums(icosphere(0, 1.0))) EXPECT_NEAR(s, 5 * kPi / 3, 1e-12);
}

// ---------------------------------------------------------------------------------------------
// Vertex areas

TEST(MixedVoronoiAreas, SumToTheSurfaceArea) {
  // A sheared grid has obtuse triangles (the half / quarter rule), the others mostly not.
  const TriangleMesh sheared =
      grid_mesh(6, 6, [](double u, double v) { return Vec3(4 * u + 3 * v, 1.5 * v, 0); });
  int obtuse = 0;
  for (const Face& f : sheared.faces())
    for (int i = 0; i < 3; ++i) {
      const Vec3& p = sheared.vertices()[f[i]];
      obtuse +=
          (sheared.vertices()[f[(i + 1) % 3]] - p).dot(sheared.vertices()[f[(i + 2) % 3]] - p) < 0;
    }
  ASSERT_GT(obtuse, 0);
  for (const TriangleMesh& mesh :
       {flat_square(9), bump(12), cap(10, 3.0), icosphere(2, 1.3), sheared}) {
    const double area = surface_area(mesh);
    EXPECT_NEAR(sum(mixed_voronoi_areas(mesh)), area, 1e-12 * area);
    EXPECT_NEAR(sum(vertex_areas(mesh)), area, 1e-12 * area);
    for (double a : mixed_voronoi_areas(mesh)) EXPECT_GT(a, 0.0);
  }
}

TEST(MixedVoronoiAreas, SquareGridCellsAreHSquared) {
  // Right triangles: the circumcentres are the midpoints of the diagonals, so the Voronoi cell
  // of an interior vertex is the h x h square around it, of a side vertex half of it, of a
  // corner a quarter.
  const int n = 8;
  const double h = 10.0 / n;
  const TriangleMesh mesh =
      grid_mesh(n, n, [](double u, double v) { return Vec3(10 * u, 10 * v, 0); });
  const std::vector<double> areas = mixed_voronoi_areas(mesh);
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) {
      const int on_sides = (i == 0 || i == n) + (j == 0 || j == n);
      const double expected = h * h / (on_sides == 0 ? 1 : on_sides == 1 ? 2 : 4);
      EXPECT_NEAR(areas[j * (n + 1) + i], expected, 1e-12) << i << " " << j;
    }
}

TEST(MixedVoronoiAreas, EquilateralLatticeCellsAreHexagons) {
  // Interior vertices of an equilateral triangle lattice of side a: a regular hexagon of area
  // sqrt(3)/2 a^2.
  const double a = 0.7;
  const int n = 6;
  const TriangleMesh mesh = grid_mesh(n, n, [&](double u, double v) {
    const double i = u * n, j = v * n;
    return Vec3(a * (i + 0.5 * j), a * std::sqrt(3.0) / 2 * j, 0);
  });
  // grid_mesh alternates diagonals: keep only a lattice with one diagonal direction.
  std::vector<Face> faces;
  auto id = [](int i, int j) { return j * (n + 1) + i; };
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      faces.push_back({id(i, j), id(i + 1, j), id(i, j + 1)});
      faces.push_back({id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  const TriangleMesh lattice(mesh.vertices(), faces);
  const std::vector<double> areas = mixed_voronoi_areas(lattice);
  const MeshTopology& topology = lattice.topology();
  int interior = 0;
  for (int v = 0; v < lattice.vertex_count(); ++v)
    if (!topology.is_boundary_vertex[v]) {
      ++interior;
      EXPECT_NEAR(areas[v], std::sqrt(3.0) / 2 * a * a, 1e-12) << v;
    }
  EXPECT_EQ(interior, (n - 1) * (n - 1));
}

TEST(MixedVoronoiAreas, ObtuseTriangleGetsHalfAtTheObtuseCornerAndQuartersElsewhere) {
  // Obtuse at vertex 2: (0,0)-(1,0.5) . (4,0)-(1,0.5) = -3 + 0.25 < 0. Area 1.
  const TriangleMesh triangle({{0, 0, 0}, {4, 0, 0}, {1, 0.5, 0}}, {{0, 1, 2}});
  const std::vector<double> areas = mixed_voronoi_areas(triangle);
  EXPECT_NEAR(areas[0], 0.25, 1e-15);
  EXPECT_NEAR(areas[1], 0.25, 1e-15);
  EXPECT_NEAR(areas[2], 0.5, 1e-15);
  // An acute triangle: the Voronoi regions |e|^2 cot / 8, here for the equilateral triangle a
  // third each.
  const TriangleMesh equilateral({{0, 0, 0}, {2, 0, 0}, {1, std::sqrt(3.0), 0}}, {{0, 1, 2}});
  for (double a : mixed_voronoi_areas(equilateral)) EXPECT_NEAR(a, std::sqrt(3.0) / 3, 1e-15);
}

TEST(VertexAreas, AreAThirdOfTheIncidentTriangles) {
  const TriangleMesh mesh = bump(6);
  std::vector<double> expected(mesh.vertex_count(), 0.0);
  for (const Face& f : mesh.faces()) {
    const TriangleMesh one({mesh.vertices()[f[0]], mesh.vertices()[f[1]], mesh.vertices()[f[2]]},
                           {{0, 1, 2}});
    for (int v : f) expected[v] += surface_area(one) / 3;
  }
  const std::vector<double> areas = vertex_areas(mesh);
  for (int v = 0; v < mesh.vertex_count(); ++v) EXPECT_NEAR(areas[v], expected[v], 1e-14) << v;
}

// ---------------------------------------------------------------------------------------------
// Gauss-Bonnet: sum K A over interior vertices + sum of boundary turning angles (pi - angle sum,
// the geodesic curvature of the polygonal boundary) = 2 pi chi: 2 pi on a disk, 4 pi on a sphere.

TEST(GaussBonnet, DisksTotalTwoPi) {
  for (const TriangleMesh& mesh :
       {flat_square(7), bump(14), cap(12, 4.0), grid_mesh(9, 5, [](double u, double v) {
          return Vec3(u, v, 0.3 * (u - 0.5) * (u - 0.5) - 0.2 * v * v);
        })}) {
    const std::vector<double> k = gaussian_curvature(mesh);
    const std::vector<double> areas = mixed_voronoi_areas(mesh);
    const std::vector<double> sums = vertex_angle_sums(mesh);
    const MeshTopology& topology = mesh.topology();
    double interior = 0, boundary = 0;
    for (int v = 0; v < mesh.vertex_count(); ++v) {
      if (topology.is_boundary_vertex[v])
        boundary += kPi - sums[v];
      else
        interior += k[v] * areas[v];
    }
    EXPECT_NEAR(interior + boundary, 2 * kPi, 1e-9);
  }
}

TEST(GaussBonnet, ClosedSphereTotalsFourPi) {
  for (int subdivisions : {0, 1, 3}) {
    const TriangleMesh mesh = icosphere(subdivisions, 0.8);
    const std::vector<double> k = gaussian_curvature(mesh);
    const std::vector<double> areas = mixed_voronoi_areas(mesh);
    double total = 0;
    for (int v = 0; v < mesh.vertex_count(); ++v) total += k[v] * areas[v];
    EXPECT_NEAR(total, 4 * kPi, 1e-9);
  }
}

}  // namespace
}  // namespace gridshell
