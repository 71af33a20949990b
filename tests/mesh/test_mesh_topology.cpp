// SPDX-License-Identifier: GPL-3.0-or-later
// Mesh connectivity (gridshell/mesh/mesh_topology.h): face adjacency, one-rings, boundary flags
// and loops of build_topology against brute-force recomputations, and the problems
// check_manifold reports with their field paths.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <map>
#include <random>
#include <set>
#include <string>
#include <unordered_map>
#include <vector>

#include "gridshell/foundation/errors.h"
#include "gridshell/mesh/mesh.h"
#include "gridshell/mesh/mesh_topology.h"
#include "support.h"

namespace gridshell {
namespace {

using testing::annulus;
using testing::flat_square;
using testing::icosphere;

double cross2(const Vec3& a, const Vec3& b) { return a.x() * b.y() - a.y() * b.x(); }

/// Signed area of a closed polygon in the xy plane (positive counter-clockwise).
double signed_area(const TriangleMesh& mesh, const std::vector<int>& loop) {
  double area = 0;
  for (std::size_t k = 0; k < loop.size(); ++k)
    area += cross2(mesh.vertices()[loop[k]], mesh.vertices()[loop[(k + 1) % loop.size()]]);
  return area / 2;
}

/// Boundary edges by brute force: directed edges a->b of faces whose reverse b->a is no face's.
std::set<std::pair<int, int>> boundary_edges(const std::vector<Face>& faces) {
  std::set<std::pair<int, int>> directed;
  for (const Face& f : faces)
    for (int i = 0; i < 3; ++i) directed.insert({f[i], f[(i + 1) % 3]});
  std::set<std::pair<int, int>> boundary;
  for (const auto& [a, b] : directed)
    if (!directed.count({b, a})) boundary.insert({a, b});
  return boundary;
}

/// Every invariant of MeshTopology that can be recomputed from the faces alone.
void expect_consistent_topology(const TriangleMesh& mesh) {
  const MeshTopology& top = mesh.topology();
  const std::vector<Face>& faces = mesh.faces();
  const int nf = mesh.face_count(), nv = mesh.vertex_count();
  ASSERT_EQ(static_cast<int>(top.face_neighbors.size()), nf);
  ASSERT_EQ(static_cast<int>(top.vertex_faces.size()), nv);
  ASSERT_EQ(static_cast<int>(top.is_boundary_vertex.size()), nv);
  // face_neighbors: symmetric, across the same edge traversed the other way.
  int boundary_half_edges = 0;
  for (int f = 0; f < nf; ++f)
    for (int i = 0; i < 3; ++i) {
      const int n = top.face_neighbors[f][i];
      const int a = faces[f][i], b = faces[f][(i + 1) % 3];
      if (n < 0) {
        ++boundary_half_edges;
        continue;
      }
      ASSERT_LT(n, nf);
      ASSERT_NE(n, f);
      int back = -1;
      for (int j = 0; j < 3; ++j)
        if (top.face_neighbors[n][j] == f) back = j;
      ASSERT_GE(back, 0) << "face " << n << " does not list face " << f << " as a neighbour";
      EXPECT_EQ(faces[n][back], b) << "faces " << f << " and " << n;
      EXPECT_EQ(faces[n][(back + 1) % 3], a) << "faces " << f << " and " << n;
    }
  // vertex_faces: exactly the incident faces, in increasing order.
  std::vector<std::vector<int>> incident(nv);
  for (int f = 0; f < nf; ++f)
    for (int v : faces[f]) incident[v].push_back(f);
  for (int v = 0; v < nv; ++v) EXPECT_EQ(top.vertex_faces[v], incident[v]) << "vertex " << v;
  // Boundary flags and loops against the brute-force boundary edges.
  const std::set<std::pair<int, int>> edges = boundary_edges(faces);
  EXPECT_EQ(boundary_half_edges, static_cast<int>(edges.size()));
  std::set<int> on_boundary;
  for (const auto& [a, b] : edges) on_boundary.insert(a), on_boundary.insert(b);
  for (int v = 0; v < nv; ++v)
    EXPECT_EQ(static_cast<bool>(top.is_boundary_vertex[v]), on_boundary.count(v) == 1) << v;
  std::size_t loop_edges = 0;
  int previous_smallest = -1;
  for (const std::vector<int>& loop : top.boundary_loops) {
    ASSERT_GE(loop.size(), 3u);
    loop_edges += loop.size();
    for (std::size_t k = 0; k < loop.size(); ++k)
      EXPECT_TRUE(edges.count({loop[k], loop[(k + 1) % loop.size()]}))
          << loop[k] << " -> " << loop[(k + 1) % loop.size()]
          << " is not a boundary edge in face orientation";
    const int smallest = *std::min_element(loop.begin(), loop.end());
    EXPECT_GT(smallest, previous_smallest) << "loops not in the order of their smallest vertex";
    previous_smallest = smallest;
  }
  EXPECT_EQ(loop_edges, edges.size()) << "every boundary edge in exactly one loop";
}

// ---------------------------------------------------------------------------------------------
// build_topology on valid meshes

TEST(MeshTopology, DiskInvariantsAndOneCounterClockwiseLoop) {
  const TriangleMesh mesh = flat_square(8);
  expect_consistent_topology(mesh);
  const MeshTopology& top = mesh.topology();
  ASSERT_EQ(top.boundary_loops.size(), 1u);
  EXPECT_EQ(top.boundary_loops[0].size(), 32u);  // 4 sides of 8 edges
  EXPECT_GT(signed_area(mesh, top.boundary_loops[0]), 0.0);
  EXPECT_NEAR(signed_area(mesh, top.boundary_loops[0]), 100.0, 1e-9);
  // Euler: V - E + F = 1 for a disk; E from the half-edges.
  const int half_edges = 3 * mesh.face_count();
  const int boundary = static_cast<int>(top.boundary_loops[0].size());
  const int edges = (half_edges + boundary) / 2;
  EXPECT_EQ(mesh.vertex_count() - edges + mesh.face_count(), 1);
}

// The interior lies to the left of every boundary edge: the face's third vertex is on the left
// of the directed edge a -> b in the plane.
TEST(MeshTopology, BoundaryLoopsHaveTheInteriorOnTheLeft) {
  for (const TriangleMesh& mesh : {flat_square(6), annulus(1, 3, 3, 16)}) {
    const MeshTopology& top = mesh.topology();
    for (const std::vector<int>& loop : top.boundary_loops)
      for (std::size_t k = 0; k < loop.size(); ++k) {
        const int a = loop[k], b = loop[(k + 1) % loop.size()];
        int third = -1;
        for (int f : top.vertex_faces[a]) {
          const Face& t = mesh.faces()[f];
          for (int i = 0; i < 3; ++i)
            if (t[i] == a && t[(i + 1) % 3] == b) third = t[(i + 2) % 3];
        }
        ASSERT_GE(third, 0);
        const Vec3& pa = mesh.vertices()[a];
        EXPECT_GT(cross2(mesh.vertices()[b] - pa, mesh.vertices()[third] - pa), 0.0)
            << a << " -> " << b;
      }
  }
}

TEST(MeshTopology, AnnulusHasTwoLoopsOuterCounterClockwiseInnerClockwise) {
  const int rings = 3, sectors = 16;
  const TriangleMesh mesh = annulus(1, 3, rings, sectors);
  expect_consistent_topology(mesh);
  const MeshTopology& top = mesh.topology();
  ASSERT_EQ(top.boundary_loops.size(), 2u);
  // Loops in the order of their smallest vertex: the inner circle (vertices 0..15) first.
  const std::vector<int>& inner = top.boundary_loops[0];
  const std::vector<int>& outer = top.boundary_loops[1];
  ASSERT_EQ(inner.size(), static_cast<std::size_t>(sectors));
  ASSERT_EQ(outer.size(), static_cast<std::size_t>(sectors));
  for (int v : inner) EXPECT_LT(v, sectors);
  for (int v : outer) EXPECT_GE(v, rings * sectors);
  EXPECT_EQ(inner.front(), 0);  // each loop starts at its smallest vertex
  EXPECT_EQ(outer.front(), rings * sectors);
  // Interior on the left: the outer loop runs counter-clockwise, the hole clockwise.
  const double polygon = sectors / 2.0 * std::sin(2 * M_PI / sectors);  // regular n-gon, r = 1
  EXPECT_NEAR(signed_area(mesh, outer), 9 * polygon, 1e-9);
  EXPECT_NEAR(signed_area(mesh, inner), -polygon, 1e-9);
  // Every vertex of the middle rings is interior.
  for (int v = sectors; v < rings * sectors; ++v) EXPECT_FALSE(top.is_boundary_vertex[v]) << v;
}

TEST(MeshTopology, ClosedMeshHasNoBoundary) {
  for (int subdivisions : {0, 2}) {
    const TriangleMesh mesh = icosphere(subdivisions, 1.0);
    expect_consistent_topology(mesh);
    const MeshTopology& top = mesh.topology();
    EXPECT_TRUE(top.boundary_loops.empty());
    for (char b : top.is_boundary_vertex) EXPECT_FALSE(b);
    for (const auto& n : top.face_neighbors)
      for (int f : n) EXPECT_GE(f, 0);
    // Euler: V - E + F = 2 for a sphere.
    EXPECT_EQ(mesh.vertex_count() - 3 * mesh.face_count() / 2 + mesh.face_count(), 2);
  }
}

TEST(MeshTopology, IsolatedVerticesHaveNoFacesAndAreNotBoundary) {
  const MeshTopology top = build_topology(4, {{0, 2, 3}});
  EXPECT_TRUE(top.vertex_faces[1].empty());
  EXPECT_FALSE(top.is_boundary_vertex[1]);
  ASSERT_EQ(top.boundary_loops.size(), 1u);
  EXPECT_EQ(top.boundary_loops[0], (std::vector<int>{0, 2, 3}));
  EXPECT_EQ(top.face_neighbors[0], (std::array<int, 3>{-1, -1, -1}));
}

TEST(MeshTopology, TwoTrianglesShareOneEdge) {
  // 0 1 2 and 0 2 3 share the edge 0-2: local edge 2 (2 -> 0) of face 0, local edge 0 (0 -> 2)
  // of face 1.
  const MeshTopology top = build_topology(4, {{0, 1, 2}, {0, 2, 3}});
  EXPECT_EQ(top.face_neighbors[0], (std::array<int, 3>{-1, -1, 1}));
  EXPECT_EQ(top.face_neighbors[1], (std::array<int, 3>{0, -1, -1}));
  EXPECT_EQ(top.vertex_faces[0], (std::vector<int>{0, 1}));
  EXPECT_EQ(top.vertex_faces[1], (std::vector<int>{0}));
  ASSERT_EQ(top.boundary_loops.size(), 1u);
  EXPECT_EQ(top.boundary_loops[0], (std::vector<int>{0, 1, 2, 3}));
}

// ---------------------------------------------------------------------------------------------
// check_manifold against the hash-map implementation it replaced (kept here as the oracle):
// the same first problem on random face soups and on damaged meshes.

std::uint64_t key(int a, int b) {
  return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(a)) << 32) |
         static_cast<std::uint32_t>(b);
}

TopologyProblem reference_check_manifold(int nv, const std::vector<Face>& faces) {
  TopologyProblem problem;
  const int nf = static_cast<int>(faces.size());
  std::unordered_map<std::uint64_t, int> directed;  // directed edge -> count
  std::unordered_map<std::uint64_t, int> undirected;
  directed.reserve(faces.size() * 3);
  undirected.reserve(faces.size() * 3);
  for (int f = 0; f < nf; ++f) {
    const Face& t = faces[f];
    for (int i = 0; i < 3; ++i) {
      if (t[i] < 0 || t[i] >= nv || t[i] == t[(i + 1) % 3]) {
        problem.kind = TopologyProblem::Kind::InvalidIndex;
        problem.element = f;
        return problem;
      }
    }
    for (int i = 0; i < 3; ++i) {
      const int a = t[i], b = t[(i + 1) % 3];
      if (++undirected[key(std::min(a, b), std::max(a, b))] > 2) {
        problem.kind = TopologyProblem::Kind::NonManifoldEdge;
        problem.element = std::min(a, b);
        problem.other = std::max(a, b);
        return problem;
      }
      if (++directed[key(a, b)] > 1) {
        problem.kind = TopologyProblem::Kind::InconsistentOrientation;
        problem.element = f;
        return problem;
      }
    }
  }
  // Vertex manifoldness: the faces around a vertex must form one fan (a single chain or cycle).
  std::vector<std::vector<int>> vertex_faces(nv);
  for (int f = 0; f < nf; ++f)
    for (int v : faces[f]) vertex_faces[v].push_back(f);
  for (int v = 0; v < nv; ++v) {
    const auto& fan = vertex_faces[v];
    if (fan.size() <= 1) continue;
    // For each incident face: the "next" vertex (after v) and "previous" vertex (before v).
    std::unordered_map<int, int> next_of_prev;  // prev vertex -> face index in list
    std::vector<int> nextv(fan.size()), prevv(fan.size());
    for (size_t k = 0; k < fan.size(); ++k) {
      const Face& t = faces[fan[k]];
      const int i = t[0] == v ? 0 : (t[1] == v ? 1 : 2);
      nextv[k] = t[(i + 1) % 3];
      prevv[k] = t[(i + 2) % 3];
      next_of_prev[prevv[k]] = static_cast<int>(k);
    }
    // Walk from a start face (a face whose next vertex is no one's prev, if the fan is open).
    std::unordered_map<int, int> by_next;
    for (size_t k = 0; k < fan.size(); ++k) by_next[nextv[k]] = static_cast<int>(k);
    int start = 0;
    for (size_t k = 0; k < fan.size(); ++k)
      if (!by_next.count(prevv[k])) {
        start = static_cast<int>(k);
        break;
      }
    size_t visited = 0;
    int k = start;
    std::vector<char> seen(fan.size(), 0);
    while (k >= 0 && !seen[k]) {
      seen[k] = 1;
      ++visited;
      auto it = next_of_prev.find(nextv[k]);
      k = it == next_of_prev.end() ? -1 : it->second;
    }
    if (visited != fan.size()) {
      problem.kind = TopologyProblem::Kind::NonManifoldVertex;
      problem.element = v;
      return problem;
    }
  }
  return problem;
}

void expect_same_problem(int nv, const std::vector<Face>& faces) {
  const TopologyProblem ours = check_manifold(nv, faces);
  const TopologyProblem reference = reference_check_manifold(nv, faces);
  EXPECT_EQ(ours.kind, reference.kind) << reference.message();
  EXPECT_EQ(ours.element, reference.element) << reference.message();
  EXPECT_EQ(ours.other, reference.other) << reference.message();
  if (reference.kind == TopologyProblem::Kind::None) {
    const MeshTopology top = build_topology(nv, faces);
    EXPECT_EQ(top.face_neighbors.size(), faces.size());
  }
}

TEST(CheckManifold, SameFirstProblemAsTheHashMapVersion) {
  std::mt19937 rng(7);
  int kinds[5] = {0, 0, 0, 0, 0};
  for (int trial = 0; trial < 4000; ++trial) {
    const int nv = 4 + static_cast<int>(rng() % 6);
    const int nf = 1 + static_cast<int>(rng() % 10);
    std::vector<Face> faces(nf);
    for (Face& f : faces)
      for (int& v : f) v = static_cast<int>(rng() % (nv + 1)) - (rng() % 40 == 0 ? nv + 1 : 0);
    expect_same_problem(nv, faces);
    ++kinds[static_cast<int>(reference_check_manifold(nv, faces).kind)];
  }
  // Damaged closed meshes: a face flipped, removed, duplicated or glued to a far vertex.
  const TriangleMesh sphere = icosphere(1, 1.0);
  for (int trial = 0; trial < 400; ++trial) {
    std::vector<Face> faces = sphere.faces();
    const std::size_t f = rng() % faces.size();
    switch (trial % 4) {
      case 0:
        std::swap(faces[f][0], faces[f][1]);
        break;
      case 1:
        faces.erase(faces.begin() + static_cast<long>(f));
        break;
      case 2:
        faces.push_back(faces[f]);
        break;
      case 3:
        faces[f][rng() % 3] = static_cast<int>(rng() % sphere.vertex_count());
        break;
    }
    expect_same_problem(sphere.vertex_count(), faces);
    ++kinds[static_cast<int>(reference_check_manifold(sphere.vertex_count(), faces).kind)];
  }
  for (int k = 0; k < 5; ++k) EXPECT_GT(kinds[k], 5) << "problem kind " << k << " too rare";
}

// check_manifold: the problem kinds and their fields

TEST(MeshTopologyProblem, NoneForAValidMesh) {
  const TriangleMesh mesh = flat_square(4);
  const TopologyProblem problem = check_manifold(mesh.vertex_count(), mesh.faces());
  EXPECT_EQ(problem.kind, TopologyProblem::Kind::None);
  EXPECT_EQ(problem.field(), "");
  EXPECT_EQ(problem.message(), "no problem");
}

TEST(MeshTopologyProblem, InvalidIndexNamesTheFace) {
  const std::vector<std::pair<std::vector<Face>, int>> cases = {
      {{{0, 1, 2}, {0, 2, 4}}, 1},              // index 4 of 4 vertices
      {{{0, 1, 2}, {0, 2, 3}, {-1, 2, 3}}, 2},  // negative
      {{{0, 1, 1}}, 0},                         // repeated
      {{{0, 1, 2}, {3, 2, 3}}, 1},              // repeated, not adjacent in the triple
  };
  for (const auto& [faces, bad] : cases) {
    const TopologyProblem problem = check_manifold(4, faces);
    EXPECT_EQ(problem.kind, TopologyProblem::Kind::InvalidIndex);
    EXPECT_EQ(problem.element, bad);
    EXPECT_EQ(problem.field(), "faces[" + std::to_string(bad) + "]");
    EXPECT_NE(problem.message().find("face " + std::to_string(bad)), std::string::npos)
        << problem.message();
  }
}

TEST(MeshTopologyProblem, NonManifoldEdgeNamesItsSmallerVertex) {
  // Three triangles on the edge 3-7.
  const std::vector<Face> faces = {{3, 7, 0}, {7, 3, 1}, {3, 7, 2}};
  const TopologyProblem problem = check_manifold(8, faces);
  EXPECT_EQ(problem.kind, TopologyProblem::Kind::NonManifoldEdge);
  EXPECT_EQ(problem.element, 3);
  EXPECT_EQ(problem.other, 7);
  EXPECT_EQ(problem.field(), "vertices[3]");
  EXPECT_NE(problem.message().find("between vertices 3 and 7"), std::string::npos)
      << problem.message();
}

TEST(MeshTopologyProblem, NonManifoldVertexNamesTheVertex) {
  // Two fans touching only at vertex 2 (a bowtie).
  const std::vector<Face> faces = {{2, 0, 1}, {2, 3, 4}};
  const TopologyProblem problem = check_manifold(5, faces);
  EXPECT_EQ(problem.kind, TopologyProblem::Kind::NonManifoldVertex);
  EXPECT_EQ(problem.element, 2);
  EXPECT_EQ(problem.field(), "vertices[2]");
  EXPECT_NE(problem.message().find("vertex 2"), std::string::npos) << problem.message();
}

TEST(MeshTopologyProblem, InconsistentOrientationNamesTheLaterFace) {
  // A consistent fan around vertex 0; flipping face 2 makes it traverse 2 -> 0 like face 0.
  const std::vector<Face> faces = {{0, 1, 2}, {1, 3, 2}, {0, 2, 4}, {0, 4, 5}};
  EXPECT_EQ(check_manifold(6, faces).kind, TopologyProblem::Kind::None);
  std::vector<Face> bad = faces;
  bad[2] = {2, 0, 4};
  const TopologyProblem problem = check_manifold(6, bad);
  EXPECT_EQ(problem.kind, TopologyProblem::Kind::InconsistentOrientation);
  EXPECT_EQ(problem.element, 2);
  EXPECT_EQ(problem.field(), "faces[2]");
  EXPECT_NE(problem.message().find("face 2"), std::string::npos) << problem.message();
}

TEST(MeshTopologyProblem, BuildTopologyThrowsTheProblemAsInvalidInput) {
  const std::vector<std::pair<int, std::vector<Face>>> cases = {
      {4, {{0, 1, 2}, {0, 2, 4}}},
      {8, {{3, 7, 0}, {7, 3, 1}, {3, 7, 2}}},
      {5, {{2, 0, 1}, {2, 3, 4}}},
      {6, {{0, 1, 2}, {1, 3, 2}, {2, 0, 4}, {0, 4, 5}}},
  };
  for (const auto& [nv, faces] : cases) {
    const TopologyProblem problem = check_manifold(nv, faces);
    ASSERT_NE(problem.kind, TopologyProblem::Kind::None);
    try {
      build_topology(nv, faces);
      ADD_FAILURE() << "no exception for " << problem.message();
    } catch (const InvalidInput& e) {
      EXPECT_EQ(e.code(), ErrorCode::InvalidInput);
      EXPECT_EQ(e.field(), problem.field());
      EXPECT_EQ(e.message(), problem.message());
      EXPECT_EQ(std::string(e.what()), problem.field() + ": " + problem.message());
    }
  }
}

}  // namespace
}  // namespace gridshell
