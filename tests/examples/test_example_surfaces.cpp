// SPDX-License-Identifier: GPL-3.0-or-later
// Tests for examples/example_surfaces.cpp: the paper's seven models (Table 1 bounding boxes and
// vertex counts) and the analytic cases, checked for disk topology, orientation, triangle
// quality, corners, discrete curvature sign and resolution scaling.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numbers>
#include <set>

#include "gridshell/example_surfaces.h"
#include "gridshell/foundation/errors.h"
#include "gridshell/mesh/mesh_topology.h"

namespace gridshell {
namespace {

constexpr double kPi = std::numbers::pi;

/// Table 1 of Pillwein et al. 2020: width, depth, height and |M_V|.
struct TableRow {
  double width, depth, height;
  int vertex_count;
};

const std::map<std::string, TableRow>& paper_table() {
  static const std::map<std::string, TableRow> table = {
      {"torus-wide", {100.0, 61.9, 27.2, 2122}},   {"waves-bump", {100.0, 100.0, 12.7, 3385}},
      {"sphere", {100.0, 100.0, 29.9, 1083}},      {"double-vault", {100.0, 51.7, 14.6, 571}},
      {"waves", {100.0, 65.5, 15.1, 1929}},        {"archway", {100.0, 58.0, 20.7, 975}},
      {"triple-vault", {100.0, 42.8, 16.3, 1322}},
  };
  return table;
}

const std::vector<std::string> kAnalyticNames = {"cylinder", "cone", "hypar", "plane"};

/// Smallest triangle angle we accept anywhere, in degrees. The worst triangles are the stretched
/// ones on the steep sides of the height fields (sphere corners, torus rim) and in the jittered
/// plane; all examples stay above ~25 degrees at the default resolution.
constexpr double kMinAngleDegrees = 15.0;

/// Smallest accepted z component of a unit face normal (every example is a height field; the
/// torus rim is the steepest, at about 84 degrees from horizontal).
constexpr double kMinNormalZ = 0.02;

Vec3 face_normal(const TriangleMesh& mesh, const Face& f) {
  const Vec3& a = mesh.vertices()[f[0]];
  return (mesh.vertices()[f[1]] - a).cross(mesh.vertices()[f[2]] - a);
}

/// Interior angle of face f at its local corner k.
double corner_angle(const TriangleMesh& mesh, const Face& f, int k) {
  const Vec3& p = mesh.vertices()[f[k]];
  const Vec3 e1 = mesh.vertices()[f[(k + 1) % 3]] - p, e2 = mesh.vertices()[f[(k + 2) % 3]] - p;
  return std::atan2(e1.cross(e2).norm(), e1.dot(e2));
}

/// Sum of the face angles at every vertex.
std::vector<double> angle_sums(const TriangleMesh& mesh) {
  std::vector<double> sums(mesh.vertex_count(), 0.0);
  for (const Face& f : mesh.faces())
    for (int k = 0; k < 3; ++k) sums[f[k]] += corner_angle(mesh, f, k);
  return sums;
}

double min_angle_degrees(const TriangleMesh& mesh) {
  double smallest = kPi;
  for (const Face& f : mesh.faces())
    for (int k = 0; k < 3; ++k) smallest = std::min(smallest, corner_angle(mesh, f, k));
  return smallest * 180.0 / kPi;
}

/// Checks the structural contract every example must meet, at any resolution.
void expect_valid_disk(const ExampleSurface& example, double min_angle_degrees_bound) {
  SCOPED_TRACE(example.name);
  const TriangleMesh& mesh = example.mesh;
  ASSERT_GT(mesh.vertex_count(), 8);
  ASSERT_GT(mesh.face_count(), 8);

  // Manifold, consistently oriented, a single boundary loop (a disk: V - E + F = 1).
  const TopologyProblem problem = check_manifold(mesh.vertex_count(), mesh.faces());
  ASSERT_EQ(problem.kind, TopologyProblem::Kind::None) << problem.message();
  const MeshTopology& topology = mesh.topology();
  ASSERT_EQ(topology.boundary_loops.size(), 1u);
  std::set<std::pair<int, int>> edges;
  for (const Face& f : mesh.faces())
    for (int k = 0; k < 3; ++k)
      edges.insert({std::min(f[k], f[(k + 1) % 3]), std::max(f[k], f[(k + 1) % 3])});
  EXPECT_EQ(mesh.vertex_count() - static_cast<int>(edges.size()) + mesh.face_count(), 1);
  std::vector<char> used(mesh.vertex_count(), 0);
  for (const Face& f : mesh.faces())
    for (int v : f) used[v] = 1;
  EXPECT_EQ(std::count(used.begin(), used.end(), 0), 0) << "unreferenced vertices";

  // Orientation: every normal points up (all examples are height fields).
  double lowest_normal_z = 1.0;
  for (const Face& f : mesh.faces()) {
    const Vec3 n = face_normal(mesh, f);
    ASSERT_GT(n.norm(), 0.0);
    lowest_normal_z = std::min(lowest_normal_z, n.normalized().z());
  }
  EXPECT_GT(lowest_normal_z, kMinNormalZ);

  // No degenerate or sliver triangles.
  EXPECT_GT(min_angle_degrees(mesh), min_angle_degrees_bound);

  // Corners: distinct boundary vertices, in the order of the (counter-clockwise) boundary loop,
  // each with a corner angle below pi.
  const std::vector<int>& loop = topology.boundary_loops.front();
  std::array<int, 4> position{};
  for (int c = 0; c < 4; ++c) {
    const int corner = example.corners[c];
    ASSERT_GE(corner, 0);
    ASSERT_LT(corner, mesh.vertex_count());
    EXPECT_TRUE(topology.is_boundary_vertex[corner]) << "corner " << c;
    const auto it = std::find(loop.begin(), loop.end(), corner);
    ASSERT_NE(it, loop.end()) << "corner " << c;
    position[c] = static_cast<int>(it - loop.begin());
  }
  // Cyclically increasing positions: exactly one wrap-around among the four steps.
  int descents = 0;
  for (int c = 0; c < 4; ++c) {
    EXPECT_NE(position[c], position[(c + 1) % 4]);
    if (position[(c + 1) % 4] < position[c]) ++descents;
  }
  EXPECT_EQ(descents, 1) << "corners are not in boundary order";
  const std::vector<double> sums = angle_sums(mesh);
  // Corners are sharp mesh corners, except the cone's near corners: they sit mid-side (angle pi
  // in the mesh) so that the boundary geodesic between them clears the concave inner arc.
  for (int c = 0; c < 4; ++c) {
    const bool mid_side = example.name == "cone" && c < 2;
    if (mid_side)
      EXPECT_NEAR(sums[example.corners[c]], kPi, 1e-9) << "corner " << c;
    else
      EXPECT_LT(sums[example.corners[c]], kPi - 0.1) << "corner " << c;
  }
}

TEST(ExampleSurfaces, NamesListPaperModelsFirst) {
  const std::vector<std::string> expected = {
      "torus-wide",   "waves-bump", "sphere", "double-vault", "waves", "archway",
      "triple-vault", "cylinder",   "cone",   "hypar",        "plane"};
  EXPECT_EQ(example_names(), expected);
}

TEST(ExampleSurfaces, EveryExampleIsAWellShapedDiskWithCorners) {
  for (const std::string& name : example_names()) {
    const ExampleSurface example = make_example(name);
    EXPECT_EQ(example.name, name);
    EXPECT_FALSE(example.description.empty()) << name;
    EXPECT_EQ(example.description.find('\n'), std::string::npos) << name;
    expect_valid_disk(example, kMinAngleDegrees);
  }
}

TEST(ExampleSurfaces, PaperModelsMatchTable1) {
  for (const auto& [name, row] : paper_table()) {
    SCOPED_TRACE(name);
    const ExampleSurface example = make_example(name);
    const Vec3 box = bounding_box_size(example.mesh);
    EXPECT_NEAR(box.x(), row.width, 0.005 * row.width);
    EXPECT_NEAR(box.y(), row.depth, 0.005 * row.depth);
    EXPECT_NEAR(box.z(), row.height, 0.005 * row.height);
    EXPECT_NEAR(example.mesh.vertex_count(), row.vertex_count, 0.25 * row.vertex_count);
  }
}

TEST(ExampleSurfaces, AnalyticCasesAreAbout100Wide) {
  for (const std::string& name : kAnalyticNames) {
    SCOPED_TRACE(name);
    const ExampleSurface example = make_example(name);
    const Vec3 box = bounding_box_size(example.mesh);
    EXPECT_NEAR(box.x(), 100.0, 5.0);
    EXPECT_GT(box.y(), 50.0);
    EXPECT_LT(box.y(), 110.0);
    EXPECT_GE(example.mesh.vertex_count(), 1000);
    EXPECT_LE(example.mesh.vertex_count(), 2000);
  }
}

TEST(ExampleSurfaces, ExamplesAreCentredOnTheGround) {
  for (const std::string& name : example_names()) {
    SCOPED_TRACE(name);
    const TriangleMesh mesh = make_example(name).mesh;
    Vec3 lo = mesh.vertices().front(), hi = lo;
    for (const Vec3& p : mesh.vertices()) {
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
    EXPECT_NEAR(lo.x() + hi.x(), 0.0, 1e-9);
    EXPECT_NEAR(lo.y() + hi.y(), 0.0, 1e-9);
    EXPECT_NEAR(lo.z(), 0.0, 1e-9);
  }
}

TEST(ExampleSurfaces, DiagonalsAlternate) {
  // Not all cell diagonals one way: both diagonal directions (in xy) occur.
  for (const std::string& name : example_names()) {
    SCOPED_TRACE(name);
    const TriangleMesh mesh = make_example(name).mesh;
    // Count edges whose xy direction lies in each open quadrant pair (slope > 0 or < 0) and
    // is clearly not axis-aligned; both kinds must be common.
    int rising = 0, falling = 0;
    for (const Face& f : mesh.faces()) {
      for (int k = 0; k < 3; ++k) {
        const Vec3 d = mesh.vertices()[f[(k + 1) % 3]] - mesh.vertices()[f[k]];
        const double slope = d.x() * d.y() / (d.head<2>().squaredNorm() + 1e-300);
        if (slope > 0.2) ++rising;
        if (slope < -0.2) ++falling;
      }
    }
    EXPECT_GT(rising, mesh.face_count() / 8);
    EXPECT_GT(falling, mesh.face_count() / 8);
  }
}

/// Angle defect 2 pi - (sum of face angles) at every interior vertex.
std::vector<double> interior_defects(const TriangleMesh& mesh) {
  const MeshTopology& topology = mesh.topology();
  const std::vector<double> sums = angle_sums(mesh);
  std::vector<double> defects;
  for (int v = 0; v < mesh.vertex_count(); ++v)
    if (!topology.is_boundary_vertex[v]) defects.push_back(2 * kPi - sums[v]);
  return defects;
}

TEST(ExampleSurfaces, CylinderConeAndPlaneAreDevelopable) {
  for (const std::string name : {"cylinder", "cone", "plane"}) {
    SCOPED_TRACE(name);
    const std::vector<double> defects = interior_defects(make_example(name).mesh);
    ASSERT_GT(defects.size(), 500u);
    double worst = 0;
    for (double d : defects) worst = std::max(worst, std::abs(d));
    EXPECT_LT(worst, 1e-9);
  }
}

TEST(ExampleSurfaces, HyparIsASaddleEverywhere) {
  const std::vector<double> defects = interior_defects(make_example("hypar").mesh);
  ASSERT_GT(defects.size(), 500u);
  for (double d : defects) ASSERT_LT(d, -1e-9);
}

TEST(ExampleSurfaces, SphereIsPositivelyCurvedEverywhere) {
  const ExampleSurface sphere = make_example("sphere");
  const std::vector<double> defects = interior_defects(sphere.mesh);
  ASSERT_GT(defects.size(), 500u);
  for (double d : defects) ASSERT_GT(d, 1e-9);
  // Discrete Gauss-Bonnet: the defects approximate the curvature 1/R^2 times the vertex areas
  // (a third of the incident faces' area), summed over the interior vertices.
  const double R = (2 * 50.0 * 50.0 + 29.9 * 29.9) / (2 * 29.9);
  const MeshTopology& topology = sphere.mesh.topology();
  double total_defect = 0, interior_area = 0;
  for (double d : defects) total_defect += d;
  for (const Face& f : sphere.mesh.faces())
    for (int v : f)
      if (!topology.is_boundary_vertex[v]) interior_area += face_normal(sphere.mesh, f).norm() / 6;
  EXPECT_NEAR(total_defect, interior_area / (R * R), 0.01 * total_defect);
}

TEST(ExampleSurfaces, SphereIsATrueSphere) {
  const TriangleMesh mesh = make_example("sphere").mesh;
  const double R = (2 * 50.0 * 50.0 + 29.9 * 29.9) / (2 * 29.9);
  const Vec3 centre(0, 0, 29.9 - R);
  for (const Vec3& p : mesh.vertices()) ASSERT_NEAR((p - centre).norm(), R, 1e-6 * R);
}

TEST(ExampleSurfaces, AnalyticFormulasHold) {
  // Hypar: z - 0.02 x y is the constant shift to z >= 0 (12.5).
  const TriangleMesh hypar_mesh = make_example("hypar").mesh;
  for (const Vec3& p : hypar_mesh.vertices()) ASSERT_NEAR(p.z() - 0.02 * p.x() * p.y(), 12.5, 1e-9);
  // Cylinder: every vertex at distance 62.5 from the axis (parallel to y, 62.5 below the crown).
  const TriangleMesh cylinder_mesh = make_example("cylinder").mesh;
  for (const Vec3& p : cylinder_mesh.vertices())
    ASSERT_NEAR(std::hypot(p.x(), p.z() - (25.0 - 62.5)), 62.5, 1e-9);
  // Plane: flat.
  const TriangleMesh plane_mesh = make_example("plane").mesh;
  for (const Vec3& p : plane_mesh.vertices()) ASSERT_EQ(p.z(), 0.0);
  // Cone: the two side boundaries (rulings) are straight lines that meet at an apex outside
  // the patch.
  const ExampleSurface cone = make_example("cone");
  const std::array<int, 4>& c = cone.corners;
  const Vec3 a0 = cone.mesh.vertices()[c[0]], a1 = cone.mesh.vertices()[c[3]];  // left ruling
  const Vec3 b0 = cone.mesh.vertices()[c[1]], b1 = cone.mesh.vertices()[c[2]];  // right ruling
  // Closest points of the two lines.
  const Vec3 da = a1 - a0, db = b1 - b0, w = a0 - b0;
  const double aa = da.dot(da), ab = da.dot(db), bb = db.dot(db), aw = da.dot(w), bw = db.dot(w);
  const double denominator = aa * bb - ab * ab;
  const double s = (ab * bw - bb * aw) / denominator, t = (aa * bw - ab * aw) / denominator;
  const Vec3 pa = a0 + s * da, pb = b0 + t * db;
  EXPECT_LT((pa - pb).norm(), 1e-9);  // the rulings intersect: the apex
  EXPECT_LT(s, -0.5);                 // well before the near edge of the patch
  EXPECT_LT(t, -0.5);
}

TEST(ExampleSurfaces, ResolutionScaleTwoQuadruplesVertices) {
  for (const std::string& name : example_names()) {
    SCOPED_TRACE(name);
    const double base = make_example(name, 1.0).mesh.vertex_count();
    const ExampleSurface fine = make_example(name, 2.0);
    EXPECT_NEAR(fine.mesh.vertex_count() / base, 4.0, 0.4);
    expect_valid_disk(fine, kMinAngleDegrees);
    const auto row = paper_table().find(name);
    if (row != paper_table().end()) {
      const Vec3 box = bounding_box_size(fine.mesh);
      EXPECT_NEAR(box.x(), row->second.width, 0.005 * row->second.width);
      EXPECT_NEAR(box.y(), row->second.depth, 0.005 * row->second.depth);
      EXPECT_NEAR(box.z(), row->second.height, 0.005 * row->second.height);
    }
  }
}

TEST(ExampleSurfaces, ExtremeResolutionScalesStayValid) {
  for (const std::string& name : example_names()) {
    SCOPED_TRACE(name);
    const double base = make_example(name, 1.0).mesh.vertex_count();
    // Coarse: few samples per side, triangles less regular but still valid.
    const ExampleSurface coarse = make_example(name, 0.25);
    expect_valid_disk(coarse, 8.0);
    EXPECT_NEAR(coarse.mesh.vertex_count() / base, 0.0625, 0.05);
    // Fine (~20k-120k vertices): vertex count grows with the square of the scale; triangles keep
    // their shape. The full topology check runs on one fine model only, to keep the test fast
    // (the grid code paths do not depend on the scale).
    const ExampleSurface fine = make_example(name, 6.0);
    EXPECT_NEAR(fine.mesh.vertex_count() / base, 36.0, 3.6);
    EXPECT_GT(min_angle_degrees(fine.mesh), kMinAngleDegrees);
    for (const Face& f : fine.mesh.faces())
      ASSERT_GT(face_normal(fine.mesh, f).normalized().z(), 0);
    if (name == "sphere") expect_valid_disk(fine, kMinAngleDegrees);
  }
}

TEST(ExampleSurfaces, IsDeterministic) {
  for (const std::string& name : example_names()) {
    const ExampleSurface a = make_example(name), b = make_example(name);
    ASSERT_EQ(a.mesh.vertices().size(), b.mesh.vertices().size()) << name;
    for (std::size_t i = 0; i < a.mesh.vertices().size(); ++i)
      ASSERT_EQ(a.mesh.vertices()[i], b.mesh.vertices()[i]) << name;
    EXPECT_EQ(a.mesh.faces(), b.mesh.faces()) << name;
    EXPECT_EQ(a.corners, b.corners) << name;
  }
}

TEST(ExampleSurfaces, UnknownNameThrowsListingKnownNames) {
  try {
    make_example("pretzel");
    FAIL() << "expected InvalidInput";
  } catch (const InvalidInput& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find("pretzel"), std::string::npos) << message;
    for (const std::string& name : example_names())
      EXPECT_NE(message.find(name), std::string::npos) << message;
  }
}

TEST(ExampleSurfaces, BadResolutionScaleThrows) {
  for (double scale : {0.0, -1.0, std::numeric_limits<double>::quiet_NaN(),
                       std::numeric_limits<double>::infinity(), 1000.0})
    EXPECT_THROW(make_example("sphere", scale), InvalidInput) << scale;
}

}  // namespace
}  // namespace gridshell
