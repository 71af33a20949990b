// SPDX-License-Identifier: GPL-3.0-or-later
// Closest points and distances to a mesh (gridshell/mesh/surface_distance.h) against closed
// forms (a plane, a polyhedral sphere) and an independent brute-force point-triangle distance
// over all faces; closest() and normal_at_closest() against the distance and the face normal.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <thread>
#include <vector>

#include "gridshell/foundation/errors.h"
#include "gridshell/mesh/mesh.h"
#include "gridshell/mesh/surface_distance.h"
#include "gridshell/mesh/surface_point.h"
#include "support.h"

namespace gridshell {
namespace {

using testing::bump;
using testing::flat_square;
using testing::grid_mesh;
using testing::icosphere;

/// Distance from p to segment ab.
double segment_distance(const Vec3& p, const Vec3& a, const Vec3& b) {
  const double t = std::clamp((p - a).dot(b - a) / (b - a).squaredNorm(), 0.0, 1.0);
  return (a + t * (b - a) - p).norm();
}

/// Distance from p to triangle abc, independently of the kernel: the plane distance if the
/// projection falls inside, else the nearest edge.
double triangle_distance(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 n = (b - a).cross(c - a).normalized();
  const double height = (p - a).dot(n);
  const Vec3 q = p - height * n;
  if ((b - a).cross(q - a).dot(n) >= 0 && (c - b).cross(q - b).dot(n) >= 0 &&
      (a - c).cross(q - c).dot(n) >= 0)
    return std::abs(height);
  return std::min(
      {segment_distance(p, a, b), segment_distance(p, b, c), segment_distance(p, c, a)});
}

double brute_force_distance(const TriangleMesh& mesh, const Vec3& p) {
  double best = std::numeric_limits<double>::infinity();
  for (const Face& f : mesh.faces())
    best = std::min(best, triangle_distance(p, mesh.vertices()[f[0]], mesh.vertices()[f[1]],
                                            mesh.vertices()[f[2]]));
  return best;
}

void expect_valid(const TriangleMesh& mesh, const SurfacePoint& p) {
  ASSERT_GE(p.face, 0);
  ASSERT_LT(p.face, mesh.face_count());
  EXPECT_GE(p.barycentric.minCoeff(), 0.0);
  EXPECT_NEAR(p.barycentric.sum(), 1.0, 1e-12);
}

TEST(SurfaceDistance, PointsAboveAndBesideAPlane) {
  const TriangleMesh mesh = flat_square(8);  // [0,10]^2, z = 0, irregular inside
  const SurfaceDistance distance(mesh);
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> inside(0.0, 10.0), height(-5.0, 5.0), outside(-6.0, 16.0);
  for (int k = 0; k < 200; ++k) {
    const Vec3 above(inside(rng), inside(rng), height(rng));
    EXPECT_NEAR(distance.distance(above), std::abs(above.z()), 1e-12);
    const SurfacePoint foot = distance.closest(above);
    expect_valid(mesh, foot);
    EXPECT_LT((foot.position(mesh) - Vec3(above.x(), above.y(), 0)).norm(), 1e-12);
    // Anywhere: the distance to the square [0,10]^2 in the plane z = 0.
    const Vec3 p(outside(rng), outside(rng), height(rng));
    const double dx = std::max({0.0, -p.x(), p.x() - 10}), dy = std::max({0.0, -p.y(), p.y() - 10});
    EXPECT_NEAR(distance.distance(p), std::sqrt(dx * dx + dy * dy + p.z() * p.z()), 1e-12);
  }
}

// A polyhedral sphere inscribed in the sphere of radius R lies between R - s and R, s its
// sagitta (R minus the smallest distance of a face plane from the centre): the distance from a
// point at radius r is |r - R| to within s.
TEST(SurfaceDistance, InsideAndOutsideASphereWithinTheSagitta) {
  const double R = 3.0;
  const TriangleMesh mesh = icosphere(3, R);
  double inradius = R;
  for (const Face& f : mesh.faces()) {
    const Vec3& a = mesh.vertices()[f[0]];
    const Vec3 n = (mesh.vertices()[f[1]] - a).cross(mesh.vertices()[f[2]] - a).normalized();
    inradius = std::min(inradius, std::abs(a.dot(n)));
  }
  const double sagitta = R - inradius;
  ASSERT_GT(sagitta, 0.0);
  ASSERT_LT(sagitta, 0.02 * R);
  const SurfaceDistance distance(mesh);
  std::mt19937 rng(2);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::uniform_real_distribution<double> radius(0.0, 3 * R);
  int inside = 0, outside = 0;
  for (int k = 0; k < 300; ++k) {
    const Vec3 direction = Vec3(normal(rng), normal(rng), normal(rng)).normalized();
    const double r = radius(rng);
    const double d = distance.distance(r * direction);
    EXPECT_LE(std::abs(d - std::abs(r - R)), sagitta + 1e-12) << "r = " << r;
    (r < R ? inside : outside)++;
  }
  EXPECT_GT(inside, 50);
  EXPECT_GT(outside, 50);
  // At the centre: the inradius exactly (the nearest face plane).
  EXPECT_NEAR(distance.distance(Vec3::Zero()), inradius, 1e-12);
  // Along a vertex direction the nearest point is the vertex itself, outside and inside.
  const Vec3 vertex = mesh.vertices()[0];
  EXPECT_NEAR(distance.distance(2.0 * vertex), R, 1e-12);
}

TEST(SurfaceDistance, MatchesBruteForceOverAllFaces) {
  const TriangleMesh meshes[] = {bump(10), icosphere(2, 1.5),
                                 grid_mesh(7, 9, [](double u, double v) {
                                   return Vec3(3 * u, 2 * v, std::sin(4 * u) * std::cos(3 * v));
                                 })};
  std::mt19937 rng(3);
  for (const TriangleMesh& mesh : meshes) {
    const SurfaceDistance distance(mesh);
    const Vec3 size = bounding_box_size(mesh);
    Vec3 min = mesh.vertices()[0];
    for (const Vec3& p : mesh.vertices()) min = min.cwiseMin(p);
    std::uniform_real_distribution<double> uni(-0.3, 1.3);
    for (int k = 0; k < 200; ++k) {
      const Vec3 p =
          min + Vec3(uni(rng) * size.x(), uni(rng) * size.y(), uni(rng) * std::max(size.z(), 1.0));
      const double expected = brute_force_distance(mesh, p);
      const double d = distance.distance(p);
      EXPECT_NEAR(d, expected, 1e-12 * std::max(1.0, expected));
      const SurfacePoint q = distance.closest(p);
      expect_valid(mesh, q);
      // The closest point is at that distance.
      EXPECT_NEAR((q.position(mesh) - p).norm(), d, 1e-9 * std::max(1.0, d));
    }
  }
}

TEST(SurfaceDistance, NormalAtClosestIsUnitAndTheFaceNormalOnAPlane) {
  const TriangleMesh up = grid_mesh(6, 6, [](double u, double v) {
    return Vec3(6 * u, 6 * v, 0.5 * 6 * u - 0.25 * 6 * v);  // the plane z = x/2 - y/4
  });
  const Vec3 n = Vec3(-0.5, 0.25, 1).normalized();
  std::vector<Face> flipped = up.faces();
  for (Face& f : flipped) std::swap(f[1], f[2]);
  const TriangleMesh down(up.vertices(), flipped);
  const SurfaceDistance d_up(up), d_down(down);
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> uni(-2.0, 8.0);
  for (int k = 0; k < 100; ++k) {
    const Vec3 p(uni(rng), uni(rng), uni(rng));
    const Vec3 a = d_up.normal_at_closest(p), b = d_down.normal_at_closest(p);
    EXPECT_NEAR(a.norm(), 1.0, 1e-12);
    EXPECT_LT((a - n).norm(), 1e-12);
    EXPECT_LT((b + n).norm(), 1e-12);
  }
  // On a sphere: unit and nearly radial (interpolated vertex normals).
  const TriangleMesh sphere = icosphere(3, 2.0);
  const SurfaceDistance d_sphere(sphere);
  std::normal_distribution<double> normal(0.0, 1.0);
  for (int k = 0; k < 100; ++k) {
    const Vec3 direction = Vec3(normal(rng), normal(rng), normal(rng)).normalized();
    const Vec3 m = d_sphere.normal_at_closest((1 + 2 * uni(rng) / 8) * direction);
    EXPECT_NEAR(m.norm(), 1.0, 1e-12);
    EXPECT_GT(m.dot(direction), 0.99);
  }
}

TEST(SurfaceDistance, ClosestSurfacePointIsTheSameQuery) {
  const TriangleMesh mesh = bump(8);
  const SurfaceDistance distance(mesh);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> uni(-2.0, 12.0);
  for (int k = 0; k < 30; ++k) {
    const Vec3 p(uni(rng), uni(rng), uni(rng) / 3);
    const SurfacePoint a = closest_surface_point(mesh, p);
    const SurfacePoint b = distance.closest(p);
    EXPECT_LT((a.position(mesh) - b.position(mesh)).norm(), 1e-12);
    EXPECT_NEAR((a.position(mesh) - p).norm(), brute_force_distance(mesh, p), 1e-9);
  }
  // A point on a vertex snaps to that vertex.
  const SurfacePoint at = closest_surface_point(mesh, mesh.vertices()[40]);
  EXPECT_LT((at.position(mesh) - mesh.vertices()[40]).norm(), 1e-12);
}

TEST(SurfaceDistance, MeshWithoutFacesIsInvalidInput) {
  const TriangleMesh empty;
  EXPECT_THROW(SurfaceDistance{empty}, InvalidInput);
  EXPECT_THROW(closest_surface_point(empty, Vec3::Zero()), InvalidInput);
  const TriangleMesh points({{0, 0, 0}, {1, 0, 0}}, {});
  try {
    SurfaceDistance distance(points);
    FAIL() << "no exception";
  } catch (const InvalidInput& e) {
    EXPECT_NE(e.message().find("no faces"), std::string::npos) << e.message();
  }
}

TEST(SurfaceDistance, MovedAndConcurrentQueriesGiveTheSameAnswers) {
  const TriangleMesh mesh = bump(12);
  SurfaceDistance original(mesh);
  std::vector<Vec3> points;
  std::mt19937 rng(6);
  std::uniform_real_distribution<double> uni(-1.0, 11.0);
  for (int k = 0; k < 400; ++k) points.push_back(Vec3(uni(rng), uni(rng), uni(rng) / 2));
  std::vector<double> sequential;
  for (const Vec3& p : points) sequential.push_back(original.distance(p));
  const SurfaceDistance moved = std::move(original);
  std::vector<double> parallel(points.size());
  std::vector<std::thread> threads;
  for (int t = 0; t < 4; ++t)
    threads.emplace_back([&, t] {
      for (std::size_t k = t; k < points.size(); k += 4) parallel[k] = moved.distance(points[k]);
    });
  for (std::thread& thread : threads) thread.join();
  EXPECT_EQ(parallel, sequential);
}

}  // namespace
}  // namespace gridshell
