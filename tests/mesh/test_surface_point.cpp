// SPDX-License-Identifier: GPL-3.0-or-later
// Points on a mesh (gridshell/mesh/surface_point.h): at_vertex, on_edge, position and vertex
// with their exact-weight conventions and errors, and closest_point_on_triangle against an
// independent exact construction and brute-force sampling of the triangle, in all seven Voronoi
// regions of a triangle (three vertices, three edges, the face).
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "gridshell/foundation/errors.h"
#include "gridshell/mesh/mesh.h"
#include "gridshell/mesh/surface_point.h"
#include "support.h"

namespace gridshell {
namespace {

using testing::bump;

// ---------------------------------------------------------------------------------------------
// at_vertex, on_edge, position, vertex

TEST(SurfacePoint, AtVertexIsExactlyTheVertex) {
  const TriangleMesh mesh = bump(5);
  for (int v = 0; v < mesh.vertex_count(); ++v) {
    const SurfacePoint p = SurfacePoint::at_vertex(mesh, v);
    ASSERT_GE(p.face, 0);
    const Face& f = mesh.faces()[p.face];
    EXPECT_TRUE(f[0] == v || f[1] == v || f[2] == v);
    for (int i = 0; i < 3; ++i) EXPECT_EQ(p.barycentric[i], f[i] == v ? 1.0 : 0.0);
    EXPECT_EQ(p.position(mesh), mesh.vertices()[v]);
    EXPECT_EQ(p.vertex(mesh), v);
  }
}

TEST(SurfacePoint, AtVertexRejectsOutOfRangeAndIsolatedVertices) {
  const TriangleMesh mesh({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {5, 5, 5}}, {{0, 1, 2}});
  EXPECT_THROW(SurfacePoint::at_vertex(mesh, -1), InvalidInput);
  EXPECT_THROW(SurfacePoint::at_vertex(mesh, 4), InvalidInput);
  try {
    SurfacePoint::at_vertex(mesh, 3);
    FAIL() << "isolated vertex accepted";
  } catch (const InvalidInput& e) {
    EXPECT_NE(e.message().find("isolated"), std::string::npos) << e.message();
  }
}

TEST(SurfacePoint, OnEdgeInterpolatesAndIsExactAtTheEnds) {
  const TriangleMesh mesh = bump(4);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  int edges = 0;
  for (const Face& f : mesh.faces())
    for (int i = 0; i < 3; ++i) {
      const int a = f[i], b = f[(i + 1) % 3];
      for (const auto& [from, to] : {std::pair{a, b}, std::pair{b, a}}) {
        const double t = uni(rng);
        const SurfacePoint p = SurfacePoint::on_edge(mesh, from, to, t);
        const Vec3 expected = (1 - t) * mesh.vertices()[from] + t * mesh.vertices()[to];
        EXPECT_LT((p.position(mesh) - expected).norm(), 1e-14);
        EXPECT_EQ(p.vertex(mesh), -1);
        // The weight of the vertex opposite the edge is exactly 0, the others sum to 1.
        const Face& g = mesh.faces()[p.face];
        int zeros = 0;
        for (int k = 0; k < 3; ++k) {
          if (g[k] != from && g[k] != to) {
            EXPECT_EQ(p.barycentric[k], 0.0);
          }
          zeros += p.barycentric[k] == 0.0;
        }
        EXPECT_EQ(zeros, 1);
        EXPECT_NEAR(p.barycentric.sum(), 1.0, 1e-15);
        EXPECT_EQ(SurfacePoint::on_edge(mesh, from, to, 0.0).vertex(mesh), from);
        EXPECT_EQ(SurfacePoint::on_edge(mesh, from, to, 1.0).vertex(mesh), to);
        EXPECT_EQ(SurfacePoint::on_edge(mesh, from, to, 0.0).position(mesh), mesh.vertices()[from]);
        ++edges;
      }
    }
  EXPECT_EQ(edges, 6 * mesh.face_count());
}

TEST(SurfacePoint, OnEdgeRejectsNonEdgesAndParametersOutsideZeroOne) {
  const TriangleMesh mesh = bump(3);                                    // vertex (i, j) = 4 j + i
  EXPECT_THROW(SurfacePoint::on_edge(mesh, 0, 2, 0.5), InvalidInput);   // same row, not adjacent
  EXPECT_THROW(SurfacePoint::on_edge(mesh, 0, 15, 0.5), InvalidInput);  // opposite corners
  EXPECT_THROW(SurfacePoint::on_edge(mesh, 0, 99, 0.5), InvalidInput);  // out of range
  EXPECT_THROW(SurfacePoint::on_edge(mesh, -1, 0, 0.5), InvalidInput);
  EXPECT_THROW(SurfacePoint::on_edge(mesh, 0, 1, -1e-9), InvalidInput);
  EXPECT_THROW(SurfacePoint::on_edge(mesh, 0, 1, 1 + 1e-9), InvalidInput);
  EXPECT_THROW(SurfacePoint::on_edge(mesh, 0, 1, std::nan("")), InvalidInput);
  EXPECT_NO_THROW(SurfacePoint::on_edge(mesh, 0, 1, 0.5));
}

TEST(SurfacePoint, PositionIsTheBarycentricCombination) {
  const TriangleMesh mesh = bump(4);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  for (int k = 0; k < 100; ++k) {
    SurfacePoint p;
    p.face = static_cast<int>(rng() % mesh.faces().size());
    p.barycentric = Vec3(uni(rng), uni(rng), uni(rng));
    p.barycentric /= p.barycentric.sum();
    const Face& f = mesh.faces()[p.face];
    const Vec3 expected = p.barycentric[0] * mesh.vertices()[f[0]] +
                          p.barycentric[1] * mesh.vertices()[f[1]] +
                          p.barycentric[2] * mesh.vertices()[f[2]];
    EXPECT_LT((p.position(mesh) - expected).norm(), 1e-14);
    EXPECT_EQ(p.vertex(mesh), -1);
  }
  SurfacePoint invalid;  // face -1
  EXPECT_EQ(invalid.vertex(mesh), -1);
  invalid.face = mesh.face_count();
  invalid.barycentric = Vec3(1, 0, 0);
  EXPECT_EQ(invalid.vertex(mesh), -1);
  EXPECT_THROW(invalid.position(mesh), std::out_of_range);
  // Nearly a vertex is not a vertex: the convention is exact weights.
  SurfacePoint almost;
  almost.face = 0;
  almost.barycentric = Vec3(1 - 1e-16, 1e-16, 0);
  EXPECT_EQ(almost.vertex(mesh), -1);
}

// ---------------------------------------------------------------------------------------------
// Moved from tests/geodesic/test_geodesic.cpp (Geodesic.SurfacePointHelpers), unchanged but for
// the suite name; its mesh is the same height field on the support grid (alternating instead of
// random diagonals).

/// Height field over a 10 x 8 rectangle with a Gaussian bump and a hyperbolic-paraboloid term.
TriangleMesh bump_saddle_mesh() {
  return testing::grid_mesh(18, 15, [](double u, double v) {
    const double x = 10 * u, y = 8 * v;
    const double z = 2.5 * std::exp(-((x - 3.5) * (x - 3.5) + (y - 4) * (y - 4)) / 3.0) +
                     0.12 * (x - 5) * (y - 4);
    return Vec3(x, y, z);
  });
}

TEST(SurfacePoint, SurfacePointHelpers) {
  const TriangleMesh mesh = bump_saddle_mesh();
  const Face& f = mesh.faces()[10];
  const SurfacePoint v = SurfacePoint::at_vertex(mesh, f[1]);
  EXPECT_EQ(v.vertex(mesh), f[1]);
  EXPECT_EQ((v.position(mesh) - mesh.vertices()[f[1]]).norm(), 0.0);
  const SurfacePoint e = SurfacePoint::on_edge(mesh, f[2], f[0], 0.25);
  EXPECT_EQ(e.vertex(mesh), -1);
  EXPECT_LT(
      (e.position(mesh) - (0.75 * mesh.vertices()[f[2]] + 0.25 * mesh.vertices()[f[0]])).norm(),
      1e-15);
  int zeros = 0;
  for (int i = 0; i < 3; ++i) zeros += e.barycentric[i] == 0.0;
  EXPECT_EQ(zeros, 1);
  EXPECT_EQ(SurfacePoint::on_edge(mesh, f[2], f[0], 0.0).vertex(mesh), f[2]);
  EXPECT_EQ(SurfacePoint::on_edge(mesh, f[2], f[0], 1.0).vertex(mesh), f[0]);
  EXPECT_THROW(SurfacePoint::at_vertex(mesh, -1), InvalidInput);
  EXPECT_THROW(SurfacePoint::at_vertex(mesh, mesh.vertex_count()), InvalidInput);
  EXPECT_THROW(SurfacePoint::on_edge(mesh, f[0], f[1], 1.5), InvalidInput);
  EXPECT_THROW(SurfacePoint::on_edge(mesh, 0, mesh.vertex_count() - 1, 0.5), InvalidInput);
  std::vector<Vec3> more = mesh.vertices();
  more.push_back(Vec3(100, 100, 100));
  const TriangleMesh with_isolated(std::move(more), mesh.faces());
  EXPECT_THROW(SurfacePoint::at_vertex(with_isolated, mesh.vertex_count()), InvalidInput);
}

// ---------------------------------------------------------------------------------------------
// closest_point_on_triangle

/// Closest point of segment ab to p.
Vec3 closest_on_segment(const Vec3& p, const Vec3& a, const Vec3& b) {
  const double t = std::clamp((p - a).dot(b - a) / (b - a).squaredNorm(), 0.0, 1.0);
  return a + t * (b - a);
}

/// An independent exact construction: the projection onto the plane if it falls inside the
/// triangle, else the closest of the three edges' closest points.
Vec3 closest_reference(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 n = (b - a).cross(c - a).normalized();
  const Vec3 q = p - (p - a).dot(n) * n;
  const bool inside = (b - a).cross(q - a).dot(n) >= 0 && (c - b).cross(q - b).dot(n) >= 0 &&
                      (a - c).cross(q - c).dot(n) >= 0;
  if (inside) return q;
  Vec3 best = closest_on_segment(p, a, b);
  for (const Vec3& candidate : {closest_on_segment(p, b, c), closest_on_segment(p, c, a)})
    if ((candidate - p).norm() < (best - p).norm()) best = candidate;
  return best;
}

/// Brute force: the closest of the (N+1)(N+2)/2 points of a barycentric lattice on the triangle.
double sampled_distance(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c, int N) {
  double best = std::numeric_limits<double>::infinity();
  for (int i = 0; i <= N; ++i)
    for (int j = 0; i + j <= N; ++j) {
      const double u = double(i) / N, v = double(j) / N;
      best = std::min(best, ((1 - u - v) * a + u * b + v * c - p).norm());
    }
  return best;
}

/// The Voronoi region the weights name: 0..2 a vertex, 3..5 the edge opposite vertex k - 3,
/// 6 the face.
int region(const Vec3& w) {
  const int zeros = (w[0] == 0.0) + (w[1] == 0.0) + (w[2] == 0.0);
  if (zeros == 2) return w[0] != 0.0 ? 0 : w[1] != 0.0 ? 1 : 2;
  if (zeros == 1) return 3 + (w[0] == 0.0 ? 0 : w[1] == 0.0 ? 1 : 2);
  return 6;
}

TEST(ClosestPointOnTriangle, EachVoronoiRegionOfAFixedTriangle) {
  const Vec3 a(0, 0, 0), b(1, 0, 0), c(0, 1, 0);
  struct Case {
    Vec3 p, weights;
  };
  const std::vector<Case> cases = {
      {{-1, -1, 0.3}, {1, 0, 0}},         // vertex a
      {{2, -0.5, -0.2}, {0, 1, 0}},       // vertex b
      {{-0.5, 2, 0.7}, {0, 0, 1}},        // vertex c
      {{0.5, -1, 0.4}, {0.5, 0.5, 0}},    // edge ab
      {{-1, 0.25, -3}, {0.75, 0, 0.25}},  // edge ca
      {{1, 1, 2}, {0, 0.5, 0.5}},         // edge bc
      {{0.2, 0.3, 5}, {0.5, 0.2, 0.3}},   // face (projection)
  };
  std::array<int, 7> seen{};
  for (const Case& k : cases) {
    const Vec3 w = closest_point_on_triangle(k.p, a, b, c);
    EXPECT_LT((w - k.weights).norm(), 1e-15) << k.p.transpose() << " -> " << w.transpose();
    ++seen[region(w)];
  }
  for (int r = 0; r < 7; ++r) EXPECT_EQ(seen[r], 1) << "region " << r;
}

TEST(ClosestPointOnTriangle, RandomPointsAgainstExactAndSampledDistances) {
  std::mt19937 rng(11);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::array<int, 7> seen{};
  const int N = 120;
  double worst_exact = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const Vec3 a(normal(rng), normal(rng), normal(rng));
    const Vec3 b(normal(rng), normal(rng), normal(rng));
    const Vec3 c(normal(rng), normal(rng), normal(rng));
    if ((b - a).cross(c - a).norm() < 0.05) continue;  // skip needles
    const Vec3 p = 2.0 * Vec3(normal(rng), normal(rng), normal(rng));
    const Vec3 w = closest_point_on_triangle(p, a, b, c);
    // Valid barycentric weights.
    EXPECT_GE(w.minCoeff(), 0.0);
    EXPECT_NEAR(w.sum(), 1.0, 1e-12);
    ++seen[region(w)];
    const Vec3 q = w[0] * a + w[1] * b + w[2] * c;
    const double d = (q - p).norm();
    const double reference = (closest_reference(p, a, b, c) - p).norm();
    worst_exact = std::max(worst_exact, std::abs(d - reference));
    EXPECT_NEAR(d, reference, 1e-12) << "trial " << trial;
    if (trial < 100) {
      // No lattice point is closer; the lattice is within one cell of the closest point.
      const double sampled = sampled_distance(p, a, b, c, N);
      const double cell = std::max({(b - a).norm(), (c - b).norm(), (a - c).norm()}) / N;
      EXPECT_LE(d, sampled + 1e-12) << "trial " << trial;
      EXPECT_LE(sampled, d + cell) << "trial " << trial;
    }
  }
  for (int r = 0; r < 7; ++r) EXPECT_GT(seen[r], 0) << "region " << r << " never sampled";
  EXPECT_LT(worst_exact, 1e-12);
}

TEST(ClosestPointOnTriangle, PointsOnTheTriangleAreThemselves) {
  const Vec3 a(1, 2, 3), b(4, 0, 1), c(0, -2, 5);
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  for (int k = 0; k < 50; ++k) {
    Vec3 w(uni(rng), uni(rng), uni(rng));
    w /= w.sum();
    const Vec3 p = w[0] * a + w[1] * b + w[2] * c;
    EXPECT_LT((closest_point_on_triangle(p, a, b, c) - w).norm(), 1e-12);
  }
  EXPECT_EQ(closest_point_on_triangle(a, a, b, c), Vec3(1, 0, 0));
  EXPECT_EQ(closest_point_on_triangle(b, a, b, c), Vec3(0, 1, 0));
  EXPECT_EQ(closest_point_on_triangle(c, a, b, c), Vec3(0, 0, 1));
}

}  // namespace
}  // namespace gridshell
