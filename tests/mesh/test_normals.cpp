// SPDX-License-Identifier: GPL-3.0-or-later
// Vertex normals (gridshell/mesh/normals.h): area-weighted, unit, pointing radially on a sphere
// and along +-z on a flat mesh depending on the face orientation.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "gridshell/mesh/mesh.h"
#include "gridshell/mesh/normals.h"
#include "support.h"

namespace gridshell {
namespace {

using testing::flat_square;
using testing::grid_mesh;
using testing::icosphere;

TEST(VertexNormals, SphereNormalsPointRadially) {
  // The icosahedron and its first subdivision are symmetric about every vertex (a 5-fold axis
  // through the icosahedron's vertices, a 2-fold one through its edge midpoints): normals are
  // radial to rounding. Further subdivisions break the symmetry; the deviation shrinks with h
  // (measured 2.36e-2 and 1.18e-2 at 2 and 3 subdivisions).
  std::vector<double> worst;
  for (int subdivisions : {0, 1, 2, 3}) {
    const TriangleMesh mesh = icosphere(subdivisions, 4.0);
    const std::vector<Vec3> normals = vertex_normals(mesh);
    double largest = 0;
    for (int v = 0; v < mesh.vertex_count(); ++v) {
      EXPECT_NEAR(normals[v].norm(), 1.0, 1e-12);
      const Vec3 radial = mesh.vertices()[v].normalized();
      largest = std::max(largest, (normals[v] - radial).norm());
      if (v < 12) {
        EXPECT_LT((normals[v] - radial).norm(), 1e-12) << "icosahedron vertex " << v;
      }
    }
    std::printf("  icosphere(%d): largest |normal - radial| %.3e\n", subdivisions, largest);
    worst.push_back(largest);
  }
  EXPECT_LT(worst[0], 1e-12);
  EXPECT_LT(worst[1], 1e-12);
  EXPECT_LT(worst[2], 0.03);
  EXPECT_LT(worst[3], 0.6 * worst[2]);
}

TEST(VertexNormals, SphericalCapGridPointsRadially) {
  const double R = 5;
  const TriangleMesh cap = grid_mesh(20, 20, [R](double u, double v) {
    const double theta = (u - 0.5) * 1.2, phi = (v - 0.5) * 1.2;
    return Vec3(R * std::sin(theta) * std::cos(phi), R * std::sin(phi),
                R * std::cos(theta) * std::cos(phi));
  });
  const std::vector<Vec3> normals = vertex_normals(cap);
  const MeshTopology& topology = cap.topology();
  for (int v = 0; v < cap.vertex_count(); ++v) {
    const double cosine = normals[v].dot(cap.vertices()[v].normalized());
    // Interior vertices see a nearly symmetric fan; boundary ones only half of it.
    EXPECT_GT(cosine, topology.is_boundary_vertex[v] ? 0.995 : 0.9999) << v;
  }
}

TEST(VertexNormals, FlatMeshGivesPlusOrMinusZ) {
  const TriangleMesh up = flat_square(6);
  for (const Vec3& n : vertex_normals(up)) EXPECT_LT((n - Vec3(0, 0, 1)).norm(), 1e-14);
  // The same faces clockwise: -z.
  std::vector<Face> flipped = up.faces();
  for (Face& f : flipped) std::swap(f[1], f[2]);
  const TriangleMesh down(up.vertices(), flipped);
  for (const Vec3& n : vertex_normals(down)) EXPECT_LT((n - Vec3(0, 0, -1)).norm(), 1e-14);
}

TEST(VertexNormals, WeightedByFaceArea) {
  // A roof: the edge 0-1 is shared by a large face in the plane z = 0 (area 6, normal +z) and a
  // smaller face falling towards -y (area 2 sqrt 2, normal (0, -1, 1)/sqrt 2). The ridge
  // vertices get the area-weighted mean (0, -2, 8)/|.|, the others their face's normal.
  const std::vector<Vec3> vertices = {{0, 0, 0}, {4, 0, 0}, {0, 3, 0}, {2, -1, -1}};
  const TriangleMesh roof(vertices, {{0, 1, 2}, {1, 0, 3}});
  const Vec3 n_large(0, 0, 1), n_small = Vec3(0, -1, 1).normalized();
  const Vec3 expected = (6 * n_large + 2 * std::sqrt(2.0) * n_small).normalized();
  ASSERT_LT((expected - Vec3(0, -2, 8).normalized()).norm(), 1e-15);
  const std::vector<Vec3> normals = vertex_normals(roof);
  EXPECT_LT((normals[0] - expected).norm(), 1e-15);
  EXPECT_LT((normals[1] - expected).norm(), 1e-15);
  EXPECT_LT((normals[2] - n_large).norm(), 1e-15);
  EXPECT_LT((normals[3] - n_small).norm(), 1e-15);
}

TEST(VertexNormals, IsolatedAndDegenerateVerticesGetZero) {
  // Vertex 3 is isolated; the second face has zero area (collinear), and vertex 4 only uses it.
  const TriangleMesh mesh({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {7, 7, 7}, {2, 0, 0}},
                          {{0, 1, 2}, {1, 0, 4}});
  const std::vector<Vec3> normals = vertex_normals(mesh);
  EXPECT_EQ(normals[3], Vec3::Zero());
  EXPECT_EQ(normals[4], Vec3::Zero());
  EXPECT_LT((normals[0] - Vec3(0, 0, 1)).norm(), 1e-15);
  EXPECT_LT((normals[1] - Vec3(0, 0, 1)).norm(), 1e-15);
}

}  // namespace
}  // namespace gridshell
