// SPDX-License-Identifier: GPL-3.0-or-later
// TriangleMesh (gridshell/mesh/mesh.h): construction errors name the element, copies share one
// topology, positions move but faces do not; bounding_box_size and surface_area against closed
// forms; find_edge against a brute-force search.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "gridshell/foundation/errors.h"
#include "gridshell/mesh/mesh.h"
#include "support.h"

namespace gridshell {
namespace {

using testing::grid_mesh;
using testing::icosphere;

/// The field of the InvalidInput the constructor throws ("" and a failure if none).
std::string construction_error(std::vector<Vec3> vertices, std::vector<Face> faces) {
  try {
    TriangleMesh mesh(std::move(vertices), std::move(faces));
  } catch (const InvalidInput& e) {
    EXPECT_FALSE(e.message().empty());
    EXPECT_EQ(std::string(e.what()), e.field() + ": " + e.message());
    return e.field();
  } catch (const std::exception& e) {
    ADD_FAILURE() << "expected InvalidInput, got: " << e.what();
    return "";
  }
  ADD_FAILURE() << "no exception";
  return "";
}

std::vector<Vec3> points(int n) {
  std::vector<Vec3> out;
  for (int i = 0; i < n; ++i) out.push_back(Vec3(i, i * i % 7, 0.5 * i));
  return out;
}

TEST(TriangleMesh, EmptyMesh) {
  const TriangleMesh mesh;
  EXPECT_EQ(mesh.vertex_count(), 0);
  EXPECT_EQ(mesh.face_count(), 0);
  EXPECT_TRUE(mesh.topology().face_neighbors.empty());
  EXPECT_TRUE(mesh.topology().boundary_loops.empty());
  EXPECT_EQ(bounding_box_size(mesh), Vec3::Zero());
  EXPECT_EQ(surface_area(mesh), 0.0);
  EXPECT_EQ(find_edge(mesh, 0, 1), (std::array<int, 2>{-1, -1}));
}

TEST(TriangleMesh, ConstructionErrorsNameTheElement) {
  EXPECT_EQ(construction_error(points(4), {{0, 1, 2}, {0, 2, 7}}), "faces[1]");
  EXPECT_EQ(construction_error(points(4), {{0, 1, 2}, {0, 2, 3}, {3, 3, 1}}), "faces[2]");
  EXPECT_EQ(construction_error(points(4), {{0, -2, 1}}), "faces[0]");
  EXPECT_EQ(construction_error(points(8), {{3, 7, 0}, {7, 3, 1}, {3, 7, 2}}), "vertices[3]");
  EXPECT_EQ(construction_error(points(5), {{2, 0, 1}, {2, 3, 4}}), "vertices[2]");
  EXPECT_EQ(construction_error(points(6), {{0, 1, 2}, {1, 3, 2}, {2, 0, 4}}), "faces[2]");
}

TEST(TriangleMesh, KeepsVerticesAndFacesAsGiven) {
  const std::vector<Vec3> v = points(5);  // vertex 4 is isolated: allowed
  const std::vector<Face> f = {{0, 1, 2}, {0, 2, 3}};
  const TriangleMesh mesh(v, f);
  EXPECT_EQ(mesh.vertices(), v);
  EXPECT_EQ(mesh.faces(), f);
  EXPECT_EQ(mesh.vertex_count(), 5);
  EXPECT_EQ(mesh.face_count(), 2);
  EXPECT_TRUE(mesh.topology().vertex_faces[4].empty());
}

TEST(TriangleMesh, CopiesShareTheTopologyButNotThePositions) {
  const TriangleMesh mesh = grid_mesh(3, 3, [](double u, double v) { return Vec3(u, v, 0); });
  TriangleMesh copy = mesh;
  EXPECT_EQ(&copy.topology(), &mesh.topology());
  copy.set_vertex(5, Vec3(7, 8, 9));
  EXPECT_EQ(copy.vertices()[5], Vec3(7, 8, 9));
  EXPECT_NE(mesh.vertices()[5], Vec3(7, 8, 9));
  EXPECT_EQ(&copy.topology(), &mesh.topology());  // moving a vertex keeps the connectivity
  TriangleMesh assigned;
  assigned = copy;
  EXPECT_EQ(&assigned.topology(), &mesh.topology());
  const TriangleMesh moved = std::move(assigned);
  EXPECT_EQ(&moved.topology(), &mesh.topology());
  // A new mesh with the same faces builds a topology of its own.
  const TriangleMesh rebuilt(mesh.vertices(), mesh.faces());
  EXPECT_NE(&rebuilt.topology(), &mesh.topology());
  EXPECT_EQ(rebuilt.topology().face_neighbors, mesh.topology().face_neighbors);
}

TEST(TriangleMesh, SetVerticesMovesAllAndRejectsAWrongCount) {
  TriangleMesh mesh = grid_mesh(2, 2, [](double u, double v) { return Vec3(u, v, 0); });
  const MeshTopology* topology = &mesh.topology();
  std::vector<Vec3> lifted = mesh.vertices();
  for (Vec3& p : lifted) p.z() = p.x() + 2 * p.y();
  mesh.set_vertices(lifted);
  EXPECT_EQ(mesh.vertices(), lifted);
  EXPECT_EQ(&mesh.topology(), topology);
  std::vector<Vec3> short_list(lifted.begin(), lifted.end() - 1);
  EXPECT_THROW(mesh.set_vertices(short_list), std::invalid_argument);
  std::vector<Vec3> long_list = lifted;
  long_list.push_back(Vec3::Zero());
  EXPECT_THROW(mesh.set_vertices(long_list), std::invalid_argument);
  EXPECT_EQ(mesh.vertices(), lifted);  // unchanged by the rejected calls
}

TEST(TriangleMesh, BoundingBoxSize) {
  const TriangleMesh mesh = grid_mesh(
      4, 6, [](double u, double v) { return Vec3(-3 + 5 * u, 2 * v - 7, std::sin(M_PI * u)); });
  const Vec3 box = bounding_box_size(mesh);
  EXPECT_NEAR(box.x(), 5.0, 1e-12);
  EXPECT_NEAR(box.y(), 2.0, 1e-12);
  EXPECT_NEAR(box.z(), 1.0, 1e-12);  // sin(pi/2) at u = 2/4
  // The icosahedron's vertices are (0, +-1, +-t) and their cyclic permutations; the midpoint of
  // (0, -1, t) and (0, 1, t) is on the z axis, so one subdivision puts vertices at +-R on every
  // axis.
  EXPECT_LT(bounding_box_size(icosphere(0, 3.0)).x(), 6.0 - 0.5);
  const Vec3 sphere_box = bounding_box_size(icosphere(2, 3.0));
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(sphere_box[k], 6.0, 1e-12);
}

TEST(TriangleMesh, SurfaceAreaClosedForms) {
  // A tilted plane z = 0.75 x over [0,4] x [0,3]: area 4 * 3 * sqrt(1 + 0.75^2) = 15.
  const TriangleMesh plane =
      grid_mesh(5, 7, [](double u, double v) { return Vec3(4 * u, 3 * v, 3 * u); });
  EXPECT_NEAR(surface_area(plane), 15.0, 1e-12);
  // A prism on a regular n-gon (every quad planar): n * chord * height.
  const int n = 12;
  const double r = 2.0, height = 5.0;
  const TriangleMesh prism = grid_mesh(n, 3, [&](double u, double v) {
    return Vec3(r * std::cos(2 * M_PI * u), r * std::sin(2 * M_PI * u), height * v);
  });
  EXPECT_NEAR(surface_area(prism), n * 2 * r * std::sin(M_PI / n) * height, 1e-12);
  // The regular icosahedron of circumradius R: 20 equilateral faces of side a = R / sin(2 pi/5).
  const double R = 1.7;
  const double a = R / std::sin(2 * std::numbers::pi / 5);
  EXPECT_NEAR(surface_area(icosphere(0, R)), 5 * std::sqrt(3.0) * a * a, 1e-12);
  // A single right triangle.
  const TriangleMesh triangle({{0, 0, 0}, {3, 0, 0}, {0, 0, 4}}, {{0, 1, 2}});
  EXPECT_DOUBLE_EQ(surface_area(triangle), 6.0);
}

TEST(TriangleMesh, SurfaceAreaConvergesToTheSphere) {
  double previous = 0;
  for (int subdivisions : {1, 2, 3}) {
    const double area = surface_area(icosphere(subdivisions, 1.0));
    EXPECT_LT(area, 4 * M_PI);  // inscribed polyhedron
    EXPECT_GT(area, previous);
    previous = area;
  }
  EXPECT_NEAR(previous, 4 * M_PI, 0.02 * 4 * M_PI);
}

TEST(TriangleMesh, FindEdgeMatchesABruteForceSearch) {
  const TriangleMesh mesh = grid_mesh(4, 3, [](double u, double v) { return Vec3(u, v, u * v); });
  int edges = 0;
  for (int a = -1; a <= mesh.vertex_count(); ++a)
    for (int b = -1; b <= mesh.vertex_count(); ++b) {
      bool is_edge = false;
      for (const Face& f : mesh.faces())
        for (int i = 0; i < 3; ++i)
          is_edge |= (f[i] == a && f[(i + 1) % 3] == b) || (f[i] == b && f[(i + 1) % 3] == a);
      const auto [face, local] = find_edge(mesh, a, b);
      if (!is_edge) {
        EXPECT_EQ(face, -1) << a << " " << b;
        EXPECT_EQ(local, -1) << a << " " << b;
        continue;
      }
      ++edges;
      ASSERT_GE(face, 0) << a << " " << b;
      ASSERT_LT(face, mesh.face_count());
      ASSERT_TRUE(local >= 0 && local < 3);
      const Face& f = mesh.faces()[face];
      const int x = f[local], y = f[(local + 1) % 3];
      EXPECT_TRUE((x == a && y == b) || (x == b && y == a)) << a << " " << b;
    }
  // Each undirected edge found in both directions: E = (3F + boundary) / 2 edges.
  const int boundary = static_cast<int>(mesh.topology().boundary_loops.at(0).size());
  EXPECT_EQ(edges, 3 * mesh.face_count() + boundary);
}

}  // namespace
}  // namespace gridshell
