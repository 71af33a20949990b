// SPDX-License-Identifier: GPL-3.0-or-later
// Tests for mesh reading (OBJ, OFF, PLY, STL), repairs, rejections and atomic OBJ writing.

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <initializer_list>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "gridshell/foundation/errors.h"
#include "gridshell/mesh/mesh_io.h"
#include "gridshell/mesh/mesh_topology.h"
#include "support.h"

namespace gridshell {
namespace {
namespace fs = std::filesystem;
using testing::read_text;
using testing::temp_dir;
using testing::write_text;

// ---------------------------------------------------------------------------------------------
// Fixtures: a 3x3-vertex grid (2x2 quads) with coordinates exactly representable as float.

constexpr int kGridSide = 3;

TriangleMesh grid_mesh() {
  std::vector<Vec3> vertices;
  std::vector<Face> faces;
  for (int y = 0; y < kGridSide; ++y)
    for (int x = 0; x < kGridSide; ++x) vertices.push_back(Vec3(x, y, 0.125 * x * y));
  for (int y = 0; y + 1 < kGridSide; ++y)
    for (int x = 0; x + 1 < kGridSide; ++x) {
      const int a = y * kGridSide + x, b = a + 1, c = b + kGridSide, d = a + kGridSide;
      faces.push_back({a, b, c});  // fan of the quad (a b c d)
      faces.push_back({a, c, d});
    }
  return TriangleMesh(std::move(vertices), std::move(faces));
}

/// Plain, editable arrays with TriangleMesh's accessors: the contents of files the loader must
/// repair or reject (a TriangleMesh is always valid).
struct Arrays {
  std::vector<Vec3> v;
  std::vector<Face> f;
  explicit Arrays(const TriangleMesh& mesh) : v(mesh.vertices()), f(mesh.faces()) {}
  const std::vector<Vec3>& vertices() const { return v; }
  const std::vector<Face>& faces() const { return f; }
  int vertex_count() const { return static_cast<int>(v.size()); }
};

/// The grid as quads, 0-based.
std::vector<std::array<int, 4>> grid_quads() {
  std::vector<std::array<int, 4>> quads;
  for (int y = 0; y + 1 < kGridSide; ++y)
    for (int x = 0; x + 1 < kGridSide; ++x) {
      const int a = y * kGridSide + x;
      quads.push_back({a, a + 1, a + 1 + kGridSide, a + kGridSide});
    }
  return quads;
}

std::string num(double v) {
  std::ostringstream out;
  out.precision(17);
  out << v;
  return out.str();
}

void append_le(std::string& out, const void* data, size_t n, bool big_endian = false) {
  const char* bytes = static_cast<const char*>(data);
  const bool swap = big_endian != (std::endian::native == std::endian::big);
  for (size_t i = 0; i < n; ++i) out.push_back(bytes[swap ? n - 1 - i : i]);
}
template <class T>
void put(std::string& out, T value, bool big_endian) {
  append_le(out, &value, sizeof value, big_endian);
}

template <class Mesh>
std::string stl_binary(const Mesh& mesh, const std::string& header_start = "") {
  std::string s = header_start;
  s.resize(80, ' ');
  put<std::uint32_t>(s, static_cast<std::uint32_t>(mesh.faces().size()), false);
  for (const Face& f : mesh.faces()) {
    for (int k = 0; k < 3; ++k) put<float>(s, 0.0f, false);  // normal: ignored by the reader
    for (int v : f)
      for (int k = 0; k < 3; ++k) put<float>(s, static_cast<float>(mesh.vertices()[v][k]), false);
    put<std::uint16_t>(s, 0, false);
  }
  return s;
}

template <class Mesh>
std::string stl_ascii(const Mesh& mesh) {
  std::string s = "solid grid\n";
  for (const Face& f : mesh.faces()) {
    s += "  facet normal 0 0 1\n    outer loop\n";
    for (int v : f) {
      const Vec3& p = mesh.vertices()[v];
      s += "      vertex " + num(p.x()) + " " + num(p.y()) + " " + num(p.z()) + "\n";
    }
    s += "    endloop\n  endfacet\n";
  }
  return s + "endsolid grid\n";
}

/// Catches the InvalidInput `load_mesh` must throw and returns its message; also checks that
/// the message starts with the path.
std::string load_error(const std::string& path, const MeshLoadOptions& options = {}) {
  try {
    load_mesh(path, nullptr, options);
  } catch (const InvalidInput& e) {
    const std::string message = e.what();
    EXPECT_EQ(message.rfind(path, 0), 0u) << "message does not start with the path: " << message;
    return message;
  } catch (const std::exception& e) {
    ADD_FAILURE() << "expected InvalidInput, got another exception: " << e.what();
    return {};
  }
  ADD_FAILURE() << "expected InvalidInput for " << path << ", nothing was thrown";
  return {};
}

void expect_contains(const std::string& message, std::initializer_list<const char*> parts) {
  for (const char* part : parts)
    EXPECT_NE(message.find(part), std::string::npos) << "'" << part << "' missing in: " << message;
}

/// Writes `contents` as `name` in a fresh folder and returns the error message of loading it.
std::string reject(const std::string& name, const std::string& contents,
                   const MeshLoadOptions& options = {}) {
  return load_error(write_text(temp_dir(), name, contents), options);
}

void expect_same_mesh(const TriangleMesh& expected, const TriangleMesh& actual) {
  ASSERT_EQ(actual.vertex_count(), expected.vertex_count());
  ASSERT_EQ(actual.face_count(), expected.face_count());
  for (int v = 0; v < expected.vertex_count(); ++v)
    EXPECT_EQ(actual.vertices()[v], expected.vertices()[v]) << "vertex " << v;
  for (int f = 0; f < expected.face_count(); ++f)
    EXPECT_EQ(actual.faces()[f], expected.faces()[f]) << "face " << f;
}

void expect_clean_report(const LoadReport& report, int vertices, int faces) {
  EXPECT_EQ(report.file_vertices, vertices);
  EXPECT_EQ(report.file_faces, faces);
  EXPECT_EQ(report.degenerate_faces_removed, 0);
  EXPECT_EQ(report.duplicate_vertices_merged, 0);
  EXPECT_EQ(report.isolated_vertices_removed, 0);
  EXPECT_TRUE(report.warnings.empty()) << report.warnings.front();
  ASSERT_EQ(static_cast<int>(report.vertex_of_file_vertex.size()), vertices);
  for (int v = 0; v < vertices; ++v) EXPECT_EQ(report.vertex_of_file_vertex[v], v);
}

// ---------------------------------------------------------------------------------------------
// Round trips, one per format.

TEST(MeshIo, ObjRoundTripThroughSaveObj) {
  const TriangleMesh mesh = grid_mesh();
  const std::string path = temp_dir() + "/grid.obj";
  save_obj(mesh, path);
  LoadReport report;
  expect_same_mesh(mesh, load_mesh(path, &report));
  EXPECT_EQ(report.format, "obj");
  expect_clean_report(report, 9, 8);
  EXPECT_EQ(report.polygons_triangulated, 0);
}

TEST(MeshIo, SaveObjKeepsFullPrecision) {
  TriangleMesh mesh = grid_mesh();
  mesh.set_vertex(4, Vec3(1.0 / 3.0, 1 + 1e-15, -2.5e-7));
  const std::string path = temp_dir() + "/precise.obj";
  save_obj(mesh, path);
  EXPECT_EQ(load_mesh(path).vertices()[4], mesh.vertices()[4]);
}

TEST(MeshIo, OffRoundTripWithCommentsColoursAndCountsOnHeaderLine) {
  const TriangleMesh mesh = grid_mesh();
  std::string off = "OFF 9 8 0\n# a comment line\n";
  for (const Vec3& p : mesh.vertices())
    off += num(p.x()) + " " + num(p.y()) + " " + num(p.z()) + "   # vertex\n";
  for (const Face& f : mesh.faces())  // trailing face colour must be ignored
    off += "3 " + std::to_string(f[0]) + " " + std::to_string(f[1]) + " " + std::to_string(f[2]) +
           " 255 0 0\n";
  LoadReport report;
  expect_same_mesh(mesh, load_mesh(write_text(temp_dir(), "grid.off", off), &report));
  EXPECT_EQ(report.format, "off");
  expect_clean_report(report, 9, 8);
}

TEST(MeshIo, OffQuadsAndColouredVertices) {
  const TriangleMesh mesh = grid_mesh();
  std::string off = "COFF\n9 4 12\n";
  for (const Vec3& p : mesh.vertices())
    off += num(p.x()) + " " + num(p.y()) + " " + num(p.z()) + " 0.5 0.5 0.5 1\n";
  for (const auto& q : grid_quads())
    off += "4 " + std::to_string(q[0]) + " " + std::to_string(q[1]) + " " + std::to_string(q[2]) +
           " " + std::to_string(q[3]) + "\n";
  LoadReport report;
  expect_same_mesh(mesh, load_mesh(write_text(temp_dir(), "quads.OFF", off), &report));
  EXPECT_EQ(report.polygons_triangulated, 4);
}

template <class Mesh>
std::string ply_ascii(const Mesh& mesh, const std::string& list_name) {
  std::string s =
      "ply\nformat ascii 1.0\ncomment made by a test\nelement vertex 9\n"
      "property float x\nproperty float y\nproperty float z\nproperty uchar red\n"
      "property float nx\nelement material 1\nproperty list uchar float weights\n"
      "element face 8\nproperty uchar flags\nproperty list uchar int " +
      list_name + "\nelement edge 1\nproperty int vertex1\nproperty int vertex2\nend_header\n";
  for (const Vec3& p : mesh.vertices())
    s += num(p.x()) + " " + num(p.y()) + " " + num(p.z()) + " 255 0.5\n";
  s += "3 0.5 0.25 1\n";
  for (const Face& f : mesh.faces())
    s += "7 3 " + std::to_string(f[0]) + " " + std::to_string(f[1]) + " " + std::to_string(f[2]) +
         "\n";
  return s + "0 1\n";
}

TEST(MeshIo, PlyAsciiRoundTripSkipsOtherPropertiesAndElements) {
  const TriangleMesh mesh = grid_mesh();
  for (const char* list_name : {"vertex_indices", "vertex_index"}) {
    SCOPED_TRACE(list_name);
    LoadReport report;
    expect_same_mesh(
        mesh, load_mesh(write_text(temp_dir(), "grid.ply", ply_ascii(mesh, list_name)), &report));
    EXPECT_EQ(report.format, "ply");
    expect_clean_report(report, 9, 8);
  }
}

/// Binary PLY with a mix of property types; the list count/index types vary.
template <class Mesh>
std::string ply_binary(const Mesh& mesh, bool big, bool doubles, const char* count_type,
                       const char* index_type) {
  std::string s = std::string("ply\nformat ") +
                  (big ? "binary_big_endian" : "binary_little_endian") +
                  " 1.0\nelement vertex 9\nproperty short id\n" +
                  (doubles ? "property double x\nproperty double y\nproperty double z\n"
                           : "property float x\nproperty float y\nproperty float z\n") +
                  "property uchar alpha\nelement extra 2\nproperty list ushort int values\n"
                  "property double weight\n" +
                  "element face 8\nproperty list " + count_type + " " + index_type +
                  " vertex_indices\nproperty float quality\nend_header\n";
  for (int v = 0; v < mesh.vertex_count(); ++v) {
    put<std::int16_t>(s, static_cast<std::int16_t>(v), big);
    for (int k = 0; k < 3; ++k) {
      if (doubles)
        put<double>(s, mesh.vertices()[v][k], big);
      else
        put<float>(s, static_cast<float>(mesh.vertices()[v][k]), big);
    }
    put<std::uint8_t>(s, 200, big);
  }
  for (int e = 0; e < 2; ++e) {  // the "extra" element: a list of e+1 ints and a double
    put<std::uint16_t>(s, static_cast<std::uint16_t>(e + 1), big);
    for (int j = 0; j <= e; ++j) put<std::int32_t>(s, 1000 + j, big);
    put<double>(s, 0.5, big);
  }
  const std::string ct = count_type, it = index_type;
  for (const Face& f : mesh.faces()) {
    if (ct == "uchar") put<std::uint8_t>(s, 3, big);
    if (ct == "ushort") put<std::uint16_t>(s, 3, big);
    if (ct == "int") put<std::int32_t>(s, 3, big);
    for (int v : f) {
      if (it == "int") put<std::int32_t>(s, v, big);
      if (it == "uint") put<std::uint32_t>(s, static_cast<std::uint32_t>(v), big);
      if (it == "ushort") put<std::uint16_t>(s, static_cast<std::uint16_t>(v), big);
      if (it == "uchar") put<std::uint8_t>(s, static_cast<std::uint8_t>(v), big);
    }
    put<float>(s, 1.0f, big);
  }
  return s;
}

TEST(MeshIo, PlyBinaryLittleEndianRoundTrip) {
  const TriangleMesh mesh = grid_mesh();
  LoadReport report;
  expect_same_mesh(mesh, load_mesh(write_text(temp_dir(), "grid.ply",
                                              ply_binary(mesh, false, false, "uchar", "int")),
                                   &report));
  expect_clean_report(report, 9, 8);
  expect_same_mesh(mesh, load_mesh(write_text(temp_dir(), "grid.ply",
                                              ply_binary(mesh, false, true, "ushort", "uint"))));
}

TEST(MeshIo, PlyBinaryBigEndianRoundTrip) {
  const TriangleMesh mesh = grid_mesh();
  LoadReport report;
  expect_same_mesh(mesh, load_mesh(write_text(temp_dir(), "grid.ply",
                                              ply_binary(mesh, true, true, "int", "ushort")),
                                   &report));
  expect_clean_report(report, 9, 8);
  expect_same_mesh(mesh, load_mesh(write_text(temp_dir(), "grid.ply",
                                              ply_binary(mesh, true, false, "uchar", "uchar"))));
}

/// STL has no shared vertices: compare each face's corner positions.
void expect_same_geometry(const TriangleMesh& expected, const TriangleMesh& actual) {
  ASSERT_EQ(actual.face_count(), expected.face_count());
  ASSERT_EQ(actual.vertex_count(), expected.vertex_count());
  for (int f = 0; f < expected.face_count(); ++f)
    for (int k = 0; k < 3; ++k)
      EXPECT_EQ(actual.vertices()[actual.faces()[f][k]],
                expected.vertices()[expected.faces()[f][k]])
          << "face " << f << " corner " << k;
}

void expect_stl_weld_note(const LoadReport& report) {
  EXPECT_EQ(report.format, "stl");
  EXPECT_EQ(report.file_vertices, 24);
  EXPECT_EQ(report.file_faces, 8);
  EXPECT_EQ(report.duplicate_vertices_merged, 15);  // 24 corners -> 9 vertices
  ASSERT_EQ(report.warnings.size(), 1u);
  // Expected for STL: reported, but not as a warning.
  expect_contains(report.warnings[0], {"note:", "welded 24 triangle corners into 9 vertices"});
  EXPECT_EQ(report.warnings[0].find("warning"), std::string::npos) << report.warnings[0];
  ASSERT_EQ(report.vertex_of_file_vertex.size(), 24u);
  EXPECT_EQ(report.vertex_of_file_vertex[3], 0);  // face 1 corner 0 is face 0 corner 0
}

TEST(MeshIo, StlAsciiRoundTripWeldsCorners) {
  const TriangleMesh mesh = grid_mesh();
  LoadReport report;
  expect_same_geometry(mesh,
                       load_mesh(write_text(temp_dir(), "grid.stl", stl_ascii(mesh)), &report));
  expect_stl_weld_note(report);
}

TEST(MeshIo, StlBinaryDetectedBySizeEvenWithSolidHeader) {
  const TriangleMesh mesh = grid_mesh();
  for (const char* header : {"solid exported by a CAD tool", "binary header"}) {
    SCOPED_TRACE(header);
    LoadReport report;
    expect_same_geometry(
        mesh, load_mesh(write_text(temp_dir(), "grid.STL", stl_binary(mesh, header)), &report));
    expect_stl_weld_note(report);
  }
}

// ---------------------------------------------------------------------------------------------
// OBJ syntax, triangulation and index order.

TEST(MeshIo, QuadObjIsFanTriangulated) {
  const TriangleMesh mesh = grid_mesh();
  std::string obj;
  for (const Vec3& p : mesh.vertices())
    obj += "v " + num(p.x()) + " " + num(p.y()) + " " + num(p.z()) + "\n";
  for (const auto& q : grid_quads())
    obj += "f " + std::to_string(q[0] + 1) + " " + std::to_string(q[1] + 1) + " " +
           std::to_string(q[2] + 1) + " " + std::to_string(q[3] + 1) + "\n";
  LoadReport report;
  const TriangleMesh loaded = load_mesh(write_text(temp_dir(), "quads.obj", obj), &report);
  EXPECT_EQ(loaded.face_count(), 8);
  EXPECT_EQ(report.file_faces, 4);
  EXPECT_EQ(report.polygons_triangulated, 4);
  expect_same_mesh(mesh, loaded);
}

TEST(MeshIo, PentagonGivesThreeTriangles) {
  const std::string obj = "v 0 0 0\nv 2 0 0\nv 3 1 0\nv 1 2 0\nv -1 1 0\nf 1 2 3 4 5\n";
  LoadReport report;
  const TriangleMesh loaded = load_mesh(write_text(temp_dir(), "penta.obj", obj), &report);
  ASSERT_EQ(loaded.face_count(), 3);
  EXPECT_EQ(loaded.faces()[0], (Face{0, 1, 2}));
  EXPECT_EQ(loaded.faces()[1], (Face{0, 2, 3}));
  EXPECT_EQ(loaded.faces()[2], (Face{0, 3, 4}));
  EXPECT_EQ(report.polygons_triangulated, 1);
}

TEST(MeshIo, ObjCornerSyntaxesNegativeIndicesAndIgnoredStatements) {
  const std::string obj =
      "# exported\r\n"
      "mtllib scene.mtl\r\n"
      "o patch\r\n"
      "g group1\r\n"
      "v 0 0 0\r\n"
      "v 1 0 0   # trailing comment\r\n"
      "v 1 1 0 1.0\r\n"  // optional w
      "v 0 1 0\r\n"
      "vt 0 0\r\nvt 1 0\r\nvt 1 1\r\n"
      "vn 0 0 1\r\n"
      "usemtl stone\r\n"
      "s off\r\n"
      "l 1 2\r\n"
      "f 1/1 2/2/1 3//1\r\n"
      "f -4 -2 \\\r\n -1\r\n";  // relative indices, continued line
  LoadReport report;
  const TriangleMesh loaded = load_mesh(write_text(temp_dir(), "syntax.obj", obj), &report);
  ASSERT_EQ(loaded.vertex_count(), 4);
  ASSERT_EQ(loaded.face_count(), 2);
  EXPECT_EQ(loaded.faces()[0], (Face{0, 1, 2}));
  EXPECT_EQ(loaded.faces()[1], (Face{0, 2, 3}));
  EXPECT_EQ(loaded.vertices()[2], Vec3(1, 1, 0));
  expect_clean_report(report, 4, 2);
}

TEST(MeshIo, VertexOrderIsFileOrder) {
  // Vertices deliberately not in spatial order; faces reference them in a scrambled way.
  const std::string obj =
      "v 1 1 0\nv 0 0 0\nv 2 0 0\nv 0 2 0\nv 2 2 0\n"
      "f 2 3 1\nf 3 5 1\nf 5 4 1\nf 4 2 1\n";
  LoadReport report;
  const TriangleMesh loaded = load_mesh(write_text(temp_dir(), "order.obj", obj), &report);
  ASSERT_EQ(loaded.vertex_count(), 5);
  EXPECT_EQ(loaded.vertices()[0], Vec3(1, 1, 0));
  EXPECT_EQ(loaded.vertices()[3], Vec3(0, 2, 0));
  EXPECT_EQ(loaded.faces()[0], (Face{1, 2, 0}));
  EXPECT_EQ(loaded.faces()[3], (Face{3, 1, 0}));
  expect_clean_report(report, 5, 4);
}

// ---------------------------------------------------------------------------------------------
// Repairs, each with its count and warning.

TEST(MeshIo, DuplicateVerticesMergedWithinTolerance) {
  // Two triangles of a unit square whose shared edge is stored twice (vertices 5 and 6), plus
  // a near-duplicate within 1e-12 of the diagonal (merged) and one at 1e-9 (kept).
  const std::string obj =
      "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
      "v 1e-14 0 0\n"  // 5: near-duplicate of 1 (merged)
      "v 1 1 0\n"      // 6: exact duplicate of 3
      "f 1 2 3\nf 5 6 4\n";
  LoadReport report;
  const TriangleMesh loaded = load_mesh(write_text(temp_dir(), "dups.obj", obj), &report);
  EXPECT_EQ(loaded.vertex_count(), 4);
  EXPECT_EQ(loaded.face_count(), 2);
  EXPECT_EQ(report.duplicate_vertices_merged, 2);
  EXPECT_EQ(report.vertex_of_file_vertex, (std::vector<int>{0, 1, 2, 3, 0, 2}));
  EXPECT_EQ(loaded.faces()[1], (Face{0, 2, 3}));
  ASSERT_EQ(report.warnings.size(), 1u);
  expect_contains(report.warnings[0], {"warning: ", "dups.obj", "merged 2 duplicate vertices"});

  // 1e-9 relative is well above the default tolerance: not merged, the vertex becomes isolated.
  const std::string far_obj = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 1e-9 0 0\nf 1 2 3\n";
  LoadReport far_report;
  load_mesh(write_text(temp_dir(), "far.obj", far_obj), &far_report);
  EXPECT_EQ(far_report.duplicate_vertices_merged, 0);
  EXPECT_EQ(far_report.isolated_vertices_removed, 1);

  // A larger tolerance option merges it.
  MeshLoadOptions loose;
  loose.duplicate_tolerance = 1e-6;
  LoadReport loose_report;
  load_mesh(write_text(temp_dir(), "far.obj", far_obj), &loose_report, loose);
  EXPECT_EQ(loose_report.duplicate_vertices_merged, 1);
  EXPECT_EQ(loose_report.vertex_of_file_vertex[3], 0);
}

TEST(MeshIo, ManyDuplicatesAreWeldedQuickly) {
  // 120x120 STL-like soup: 6 corners per grid cell, welded by the hash grid (not O(n^2)).
  const int n = 120;
  std::string obj;
  obj.reserve(size_t{n} * n * 200);
  int count = 0;
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      const double q[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
      for (int t : {0, 1}) {
        const int idx[3] = {0, t == 0 ? 1 : 2, t == 0 ? 2 : 3};
        for (int k : idx)
          obj += "v " + num((x + q[k][0]) * 0.1) + " " + num((y + q[k][1]) * 0.1) + " 0\n";
        obj += "f -3 -2 -1\n";
        count += 3;
      }
    }
  LoadReport report;
  const TriangleMesh loaded = load_mesh(write_text(temp_dir(), "soup.obj", obj), &report);
  EXPECT_EQ(loaded.vertex_count(), (n + 1) * (n + 1));
  EXPECT_EQ(report.duplicate_vertices_merged, count - (n + 1) * (n + 1));
}

TEST(MeshIo, DegenerateFacesRemoved) {
  const std::string obj =
      "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0.5 0 0\n"
      "f 1 2 3\nf 1 3 4\n"
      "f 1 1 2\n"   // repeated index
      "f 1 5 2\n";  // collinear: zero area
  LoadReport report;
  const TriangleMesh loaded = load_mesh(write_text(temp_dir(), "degenerate.obj", obj), &report);
  EXPECT_EQ(loaded.face_count(), 2);
  EXPECT_EQ(report.file_faces, 4);
  EXPECT_EQ(report.degenerate_faces_removed, 2);
  // Vertex 5 was only used by the collinear face.
  EXPECT_EQ(report.isolated_vertices_removed, 1);
  EXPECT_EQ(report.vertex_of_file_vertex[4], -1);
  ASSERT_EQ(report.warnings.size(), 2u);
  expect_contains(report.warnings[0],
                  {"warning: ", "degenerate.obj", "removed 2 degenerate faces"});
  expect_contains(report.warnings[1], {"removed 1 isolated vertex"});
}

TEST(MeshIo, IsolatedVerticesRemovedAndMapped) {
  const std::string obj =
      "v 5 5 5\n"  // isolated
      "v 0 0 0\nv 1 0 0\n"
      "v 7 7 7\n"  // isolated
      "v 0 1 0\nf 2 3 5\n";
  LoadReport report;
  const TriangleMesh loaded = load_mesh(write_text(temp_dir(), "isolated.obj", obj), &report);
  EXPECT_EQ(loaded.vertex_count(), 3);
  EXPECT_EQ(loaded.faces()[0], (Face{0, 1, 2}));
  EXPECT_EQ(loaded.vertices()[2], Vec3(0, 1, 0));
  EXPECT_EQ(report.isolated_vertices_removed, 2);
  EXPECT_EQ(report.vertex_of_file_vertex, (std::vector<int>{-1, 0, 1, -1, 2}));
  ASSERT_EQ(report.warnings.size(), 1u);
  expect_contains(report.warnings[0], {"warning: ", "isolated.obj", "removed 2 isolated vertices"});
}

/// A 2x1 strip of four triangles: 1 2 3 on the bottom, 4 5 6 on the top.
const char* kStripVertices = "v 0 0 0\nv 1 0 0\nv 2 0 0\nv 0 1 0\nv 1 1 0\nv 2 1 0\n";

TEST(MeshIo, InconsistentOrientationFixedKeepingTheMajority) {
  // The second face is flipped in the file.
  std::string obj = std::string(kStripVertices) + "f 1 2 5\nf 1 4 5\nf 2 3 6\nf 2 6 5\n";
  LoadReport report;
  TriangleMesh loaded = load_mesh(write_text(temp_dir(), "flip.obj", obj), &report);
  EXPECT_EQ(loaded.faces()[0], (Face{0, 1, 4}));
  EXPECT_EQ(loaded.faces()[1], (Face{0, 4, 3}));
  EXPECT_EQ(loaded.faces()[2], (Face{1, 2, 5}));
  ASSERT_EQ(report.warnings.size(), 1u);
  expect_contains(report.warnings[0], {"warning: ", "flip.obj", "flipped 1 face", "orientation"});
  EXPECT_TRUE(check_manifold(loaded.vertex_count(), loaded.faces()).kind ==
              TopologyProblem::Kind::None);

  // The first face is the odd one: it is flipped, not the three others.
  obj = std::string(kStripVertices) + "f 1 5 2\nf 1 5 4\nf 2 3 6\nf 2 6 5\n";
  loaded = load_mesh(write_text(temp_dir(), "flip.obj", obj), &report);
  EXPECT_EQ(loaded.faces()[0], (Face{0, 1, 4}));
  EXPECT_EQ(loaded.faces()[1], (Face{0, 4, 3}));
  EXPECT_EQ(loaded.faces()[3], (Face{1, 5, 4}));
}

TEST(MeshIo, ClockwiseFileOrientationIsKept) {
  // Consistent but clockwise seen from +z: kept as in the file.
  const std::string obj = std::string(kStripVertices) + "f 1 5 2\nf 1 4 5\nf 2 6 3\nf 2 5 6\n";
  LoadReport report;
  const TriangleMesh loaded = load_mesh(write_text(temp_dir(), "cw.obj", obj), &report);
  EXPECT_EQ(loaded.faces()[0], (Face{0, 4, 1}));
  EXPECT_TRUE(report.warnings.empty());
}

// ---------------------------------------------------------------------------------------------
// Real meshes.

TEST(MeshIo, SharedRealMeshesLoadAsDisks) {
  const std::vector<std::string> paths = testing::test_mesh_paths();
  const int expected_vertices[] = {961, 441, 1369};
  const int expected_quads[] = {900, 400, 1296};
  for (size_t i = 0; i < paths.size(); ++i) {
    SCOPED_TRACE(paths[i]);
    LoadReport report;
    const TriangleMesh mesh = load_mesh(paths[i], &report);
    EXPECT_EQ(mesh.vertex_count(), expected_vertices[i]);
    EXPECT_EQ(report.file_vertices, expected_vertices[i]);
    EXPECT_EQ(report.file_faces, expected_quads[i]);
    EXPECT_EQ(report.polygons_triangulated, expected_quads[i]);
    EXPECT_EQ(mesh.face_count(), 2 * expected_quads[i]);
    EXPECT_TRUE(report.warnings.empty()) << report.warnings.front();
    EXPECT_EQ(mesh.topology().boundary_loops.size(), 1u);
  }
}

// ---------------------------------------------------------------------------------------------
// Rejections: file level.

TEST(MeshIoReject, MissingFile) {
  const std::string message = load_error(temp_dir() + "/nowhere.obj");
  expect_contains(message, {"nowhere.obj", "no such file"});
}

TEST(MeshIoReject, UnreadableFile) {
  // A folder named like a mesh cannot be read.
  const std::string dir = temp_dir() + "/folder.obj";
  fs::create_directories(dir);
  expect_contains(load_error(dir), {"folder.obj", "cannot read", "directory"});
  // A file without read permission (root reads anything, so only checked for other users).
  if (geteuid() != 0) {
    const std::string path = write_text(temp_dir(), "secret.obj", "v 0 0 0\n");
    chmod(path.c_str(), 0);
    expect_contains(load_error(path), {"secret.obj", "cannot open"});
  }
}

TEST(MeshIoReject, UnknownExtension) {
  expect_contains(reject("mesh.xyz", "v 0 0 0\n"),
                  {"mesh.xyz", "unknown mesh file extension", ".xyz"});
  expect_contains(reject("mesh", "v 0 0 0\n"), {"unknown mesh file extension", "(none)"});
}

TEST(MeshIoReject, EmptyFile) {
  for (const char* name : {"empty.obj", "empty.off", "empty.ply", "empty.stl"}) {
    expect_contains(reject(name, ""), {name, "empty"});
  }
  expect_contains(reject("blank.obj", "  \n\n\t\n"), {"blank.obj", "empty"});
}

TEST(MeshIoReject, NoFaces) {
  expect_contains(reject("points.obj", "# only points\nv 0 0 0\nv 1 0 0\nv 0 1 0\n"),
                  {"points.obj", "no faces", "3 vertices"});
  expect_contains(reject("points.off", "OFF\n3 0 0\n0 0 0\n1 0 0\n0 1 0\n"),
                  {"points.off", "no faces"});
  std::string stl = std::string(80, ' ');
  stl.append(4, '\0');
  expect_contains(reject("none.stl", stl), {"none.stl", "no faces"});
}

TEST(MeshIoReject, OnlyDegenerateFaces) {
  expect_contains(reject("flat.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n"),
                  {"flat.obj", "no faces left", "degenerate"});
}

// Rejections: unparseable lines, headers, truncated data.

TEST(MeshIoReject, ObjUnparseableCoordinate) {
  expect_contains(reject("mesh.obj", "v 0 0 0\nv 1 0 0\n# x\nv 0 abc 0\nf 1 2 3\n"),
                  {"mesh.obj: line 4:", "cannot parse vertex coordinate 'abc'"});
}

TEST(MeshIoReject, ObjTooFewCoordinates) {
  expect_contains(reject("mesh.obj", "v 0 0\n"), {"mesh.obj: line 1:", "vertex has 2 coordinates"});
}

TEST(MeshIoReject, ObjUnparseableFaceIndex) {
  expect_contains(reject("mesh.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 two 3\n"),
                  {"mesh.obj: line 4:", "cannot parse face vertex index 'two'"});
}

TEST(MeshIoReject, ObjFaceWithTwoVertices) {
  expect_contains(reject("mesh.obj", "v 0 0 0\nv 1 0 0\nf 1 2\n"),
                  {"mesh.obj: line 3:", "face has 2 vertices", "at least 3"});
}

TEST(MeshIoReject, OffAndPlyFaceWithTwoVertices) {
  expect_contains(reject("two.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n2 0 1\n"),
                  {"two.off: line 6:", "face 0 has 2 vertices", "at least 3"});
  expect_contains(reject("two.ply",
                         "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"
                         "property float y\nproperty float z\nelement face 1\n"
                         "property list uchar int vertex_indices\nend_header\n"
                         "0 0 0\n1 0 0\n0 1 0\n2 0 1\n"),
                  {"two.ply: line 13:", "face 0 has 2 vertices"});
}

TEST(MeshIoReject, ObjUnknownStatement) {
  expect_contains(reject("mesh.obj", "v 0 0 0\nbogus 1 2\n"),
                  {"mesh.obj: line 2:", "unknown OBJ statement 'bogus'"});
}

TEST(MeshIoReject, OffWrongHeader) {
  expect_contains(reject("mesh.off", "PLY\n3 1 0\n"),
                  {"mesh.off: line 1:", "expected the header 'OFF'", "'PLY'"});
  expect_contains(reject("mesh.off", "OFF BINARY\n"), {"mesh.off: line 1:", "binary OFF"});
  expect_contains(reject("mesh.off", "OFF\nthree 1 0\n"),
                  {"mesh.off: line 2:", "vertex count 'three'"});
}

TEST(MeshIoReject, OffTruncated) {
  expect_contains(reject("mesh.off", "OFF\n4 1 0\n0 0 0\n1 0 0\n"),
                  {"mesh.off:", "file ends after 2 of 4 vertices", "truncated"});
  expect_contains(reject("mesh.off", "OFF\n3 2 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"),
                  {"mesh.off:", "file ends after 1 of 2 faces"});
  expect_contains(reject("mesh.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1\n"),
                  {"mesh.off: line 6:", "face 0 lists 2 vertex indices, expected 3"});
  expect_contains(reject("mesh.off", "OFF\n3 1 0\n0 0 0\n1 0\n0 1 0\n"),
                  {"mesh.off: line 4:", "vertex 1 has 2 coordinates"});
}

TEST(MeshIoReject, OffUnparseableCoordinate) {
  expect_contains(reject("mesh.off", "OFF\n3 1 0\n0 0 0\n1 0 x1\n0 1 0\n3 0 1 2\n"),
                  {"mesh.off: line 4:", "cannot parse coordinate of vertex 1", "'x1'"});
}

TEST(MeshIoReject, PlyWrongHeader) {
  expect_contains(reject("mesh.ply", "PLY file\nformat ascii 1.0\n"),
                  {"mesh.ply: line 1:", "not a PLY file", "'ply'"});
  expect_contains(reject("mesh.ply", "ply\nformat binary_middle_endian 1.0\nend_header\n"),
                  {"mesh.ply: line 2:", "unknown PLY format 'binary_middle_endian'"});
  expect_contains(reject("mesh.ply",
                         "ply\nformat ascii 1.0\nelement vertex 3\nproperty quad x\n"
                         "end_header\n"),
                  {"mesh.ply: line 4:", "cannot parse PLY property line", "'property quad x'"});
  expect_contains(reject("mesh.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"),
                  {"mesh.ply", "no 'end_header'"});
  expect_contains(reject("mesh.ply",
                         "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n"
                         "property float y\nend_header\n0 0\n"),
                  {"mesh.ply: line 3:", "no scalar 'z' property"});
  expect_contains(reject("mesh.ply",
                         "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n"
                         "property float y\nproperty float z\nelement face 1\n"
                         "property list uchar int corners\nend_header\n0 0 0\n"),
                  {"mesh.ply: line 7:", "no 'vertex_indices'"});
}

TEST(MeshIoReject, PlyBinaryTruncated) {
  const TriangleMesh mesh = grid_mesh();
  std::string ply = ply_binary(mesh, false, false, "uchar", "int");
  ply.resize(ply.size() - 10);  // cut into the last face
  expect_contains(reject("cut.ply", ply), {"cut.ply", "truncated binary data", "face 7 of 8"});
  ply.resize(ply.find("end_header\n") + 11 + 30);  // cut inside the vertices
  expect_contains(reject("cut.ply", ply), {"cut.ply", "truncated binary data", "vertex 2 of 9"});
}

TEST(MeshIoReject, PlyAsciiUnparseableAndTruncated) {
  std::string ply = ply_ascii(grid_mesh(), "vertex_indices");
  const size_t at = ply.find("2 0 0 255");
  ASSERT_NE(at, std::string::npos);
  std::string bad = ply;
  bad.replace(at, 1, "two");
  // The header has 18 lines, vertex 2 is on line 21.
  expect_contains(reject("bad.ply", bad),
                  {"bad.ply: line 21:", "cannot parse property 'x' of vertex 2", "'two'"});
  ply.resize(ply.size() - 12);
  expect_contains(reject("short.ply", ply), {"short.ply:", "file ends in", "truncated"});
}

TEST(MeshIoReject, StlBinaryTruncated) {
  std::string stl = stl_binary(grid_mesh(), "binary");
  stl.resize(stl.size() - 7);
  expect_contains(reject("cut.stl", stl), {"cut.stl", "truncated binary data", "8 triangles",
                                           std::to_string(stl.size()).c_str()});
  // Even with a "solid" header, binary content of the wrong size is not read as ASCII.
  std::string solid = stl_binary(grid_mesh(), "solid part");
  solid.pop_back();
  expect_contains(reject("cut.stl", solid), {"cut.stl", "truncated binary data"});
  expect_contains(reject("tiny.stl", "abc"), {"tiny.stl", "not an STL file"});
  expect_contains(reject("text.stl", std::string(100, 'v') + "\n"),
                  {"text.stl", "not an STL file", "'solid'"});
}

TEST(MeshIoReject, StlAsciiUnparseable) {
  std::string stl = stl_ascii(grid_mesh());
  stl.replace(stl.find("outer loop"), 10, "outer lop");
  expect_contains(reject("bad.stl", stl), {"bad.stl: line 3:", "expected 'loop'", "'lop'"});
  expect_contains(reject("bad.stl", "solid a\nfacet normal 0 0 1\nouter loop\nvertex 0 0 q\n"),
                  {"bad.stl: line 4:", "cannot parse vertex coordinate 'q'"});
  expect_contains(reject("cut.stl", "solid a\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\n"),
                  {"cut.stl:", "file ends inside facet 0", "truncated"});
}

// Rejections: NaN / Inf coordinates.

TEST(MeshIoReject, NanCoordinateInObjNamesTheLine) {
  expect_contains(reject("nan.obj", "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n"),
                  {"nan.obj: line 2:", "'nan'", "not a finite number"});
}

TEST(MeshIoReject, InfCoordinateInOffNamesTheLine) {
  expect_contains(reject("inf.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 inf 0\n3 0 1 2\n"),
                  {"inf.off: line 5:", "vertex 2", "'inf'", "not a finite number"});
  // Overflowing literals are infinite too.
  expect_contains(reject("big.obj", "v 0 0 1e999\n"), {"big.obj: line 1:", "not a finite number"});
}

TEST(MeshIoReject, NanCoordinateInBinaryPlyNamesTheVertex) {
  Arrays mesh(grid_mesh());
  mesh.v[5].y() = std::numeric_limits<double>::quiet_NaN();
  expect_contains(reject("nan.ply", ply_binary(mesh, true, true, "uchar", "int")),
                  {"nan.ply", "vertex 5", "non-finite coordinate y", "NaN"});
}

TEST(MeshIoReject, InfCoordinateInBinaryStlNamesTheFacet) {
  Arrays mesh(grid_mesh());
  mesh.v[8].z() = std::numeric_limits<double>::infinity();  // used first by facet 6
  expect_contains(reject("inf.stl", stl_binary(mesh)),
                  {"inf.stl", "facet 6", "corner 2", "non-finite"});
}

TEST(MeshIoReject, HugeCoordinateNamesTheVertex) {
  // 1e100 used to pass as "all faces are degenerate", 1e160 as "2 boundary loops".
  for (const char* z : {"1e100", "1e160", "-2e15"})
    expect_contains(reject("huge.obj", std::string("v 0 0 0\nv 1 0 0\nv 0 1 ") + z +
                                           "\nv 1 1 0\nf 1 2 3\nf 2 4 3\n"),
                    {"huge.obj", "vertex 3 (line 3)", "beyond +-1e15"});
  // An isolated vertex far away is only dropped (with a warning), as any isolated vertex.
  LoadReport report;
  const TriangleMesh mesh = load_mesh(
      write_text(temp_dir(), "far.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1e200 0 0\nf 1 2 3\n"),
      &report);
  EXPECT_EQ(mesh.vertex_count(), 3);
}

TEST(MeshIoReject, FifoAndDevicesAreNotRead) {
  // A FIFO would block in open() for ever, /dev/zero never ends.
  const std::string fifo = temp_dir() + "/pipe.obj";
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  expect_contains(load_error(fifo), {"pipe.obj", "not a regular file"});
  const std::string device = temp_dir() + "/zero.obj";
  fs::create_symlink("/dev/zero", device);
  expect_contains(load_error(device), {"zero.obj", "not a regular file"});
}

// Rejections: index out of range.

TEST(MeshIoReject, ObjIndexOutOfRange) {
  expect_contains(reject("range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n\nf 1 2 4\n"),
                  {"range.obj: line 5:", "face vertex index 4 is out of range", "3 vertices"});
  expect_contains(reject("zero.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n"),
                  {"zero.obj: line 4:", "index 0 is out of range"});
  expect_contains(
      reject("rel.obj", "v 0 0 0\nv 1 0 0\nf -1 -2 -3\nv 0 1 0\n"),
      {"rel.obj: line 3:", "relative face vertex index -3 is out of range", "2 vertices"});
}

TEST(MeshIoReject, OffAndPlyIndexOutOfRange) {
  expect_contains(reject("range.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n"),
                  {"range.off: line 6:", "face vertex index 3 is out of range", "3 vertices"});
  Arrays mesh(grid_mesh());
  mesh.f[6][1] = 9;
  expect_contains(reject("range.ply", ply_binary(mesh, false, false, "uchar", "uint")),
                  {"range.ply: face 6:", "vertex index 9 is out of range", "9 vertices"});
  expect_contains(reject("neg.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 -1 2\n"),
                  {"neg.off: line 6:", "-1 is out of range"});
}

// Rejections: topology. Vertex numbers are the file's (an isolated vertex comes first, so the
// loaded numbering differs).

TEST(MeshIoReject, NonManifoldEdgeInFileNumbering) {
  const std::string obj =
      "v 9 9 9\n"  // isolated, removed before the check
      "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 -1 0\nv 0 0 1\n"
      "f 2 3 4\nf 3 2 5\nf 2 3 6\n";
  expect_contains(reject("fin.obj", obj), {"fin.obj", "non-manifold edge", "vertex 2 (line 2)",
                                           "vertex 3 (line 3)", "more than two faces"});
}

TEST(MeshIoReject, NonManifoldVertexInFileNumbering) {
  const std::string obj =
      "v 9 9 9\n"
      "v 0 0 0\nv 1 0 0\nv 1 1 0\nv -1 0 0\nv -1 -1 0\n"
      "f 2 3 4\nf 2 5 6\n";  // two triangles touching only at vertex 2
  expect_contains(reject("bowtie.obj", obj),
                  {"bowtie.obj", "non-manifold vertex", "vertex 2 (line 2)", "single fan"});
  // Same bowtie in OFF, 0-based like the file.
  const std::string off =
      "OFF\n6 2 0\n9 9 9\n0 0 0\n1 0 0\n1 1 0\n-1 0 0\n-1 -1 0\n3 1 2 3\n3 1 4 5\n";
  expect_contains(reject("bowtie.off", off),
                  {"bowtie.off", "non-manifold vertex", "vertex 1 (line 4)"});
}

TEST(MeshIoReject, NonOrientableMoebiusStrip) {
  const int n = 6;
  std::string obj;
  for (int i = 0; i < n; ++i) {
    const double t = 2 * M_PI * i / n;
    const Vec3 centre(2 * std::cos(t), 2 * std::sin(t), 0);
    const Vec3 width = 0.5 * (std::cos(t / 2) * Vec3(std::cos(t), std::sin(t), 0) +
                              std::sin(t / 2) * Vec3(0, 0, 1));
    const Vec3 top = centre + width, bottom = centre - width;
    obj += "v " + num(top.x()) + " " + num(top.y()) + " " + num(top.z()) + "\n";
    obj += "v " + num(bottom.x()) + " " + num(bottom.y()) + " " + num(bottom.z()) + "\n";
  }
  for (int i = 0; i < n; ++i) {  // top i = 2i+1, bottom i = 2i+2 (1-based)
    const int t0 = 2 * i + 1, b0 = 2 * i + 2;
    // After a half turn, top and bottom swap.
    const int t1 = i + 1 < n ? 2 * i + 3 : 2, b1 = i + 1 < n ? 2 * i + 4 : 1;
    obj += "f " + std::to_string(t0) + " " + std::to_string(b0) + " " + std::to_string(b1) + " " +
           std::to_string(t1) + "\n";
  }
  expect_contains(reject("moebius.obj", obj),
                  {"moebius.obj", "inconsistent orientation", "not orientable", "line"});
}

// Any orientable manifold surface loads by default (issue 18: holes, several boundary loops,
// closed meshes, handles, pieces are targets; the patch cut out of them must be a disk). The
// disk check stays available with require_single_boundary.
MeshLoadOptions disk_only() {
  MeshLoadOptions options;
  options.require_single_boundary = true;
  return options;
}

TEST(MeshIoTopology, ClosedSurfaceLoadsAndIsRejectedOnlyWhenADiskIsRequired) {
  const std::string tetra =
      "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 3 1 4\n";
  expect_contains(reject("closed.obj", tetra, disk_only()),
                  {"closed.obj", "closed", "no boundary"});
  const TriangleMesh mesh = load_mesh(write_text(temp_dir(), "closed.obj", tetra));
  EXPECT_EQ(mesh.face_count(), 4);
  EXPECT_TRUE(mesh.topology().boundary_loops.empty());
}

TEST(MeshIoTopology, TwoBoundaryLoopsLoadAndAreRejectedOnlyWhenADiskIsRequired) {
  // A square frame: outer square 1-4, inner square 5-8.
  std::string obj = "v 0 0 0\nv 3 0 0\nv 3 3 0\nv 0 3 0\nv 1 1 0\nv 2 1 0\nv 2 2 0\nv 1 2 0\n";
  for (int k = 0; k < 4; ++k) {
    const int o0 = k + 1, o1 = (k + 1) % 4 + 1, i0 = k + 5, i1 = (k + 1) % 4 + 5;
    obj += "f " + std::to_string(o0) + " " + std::to_string(o1) + " " + std::to_string(i1) + " " +
           std::to_string(i0) + "\n";
  }
  expect_contains(reject("frame.obj", obj, disk_only()),
                  {"frame.obj", "2 boundary loops", "exactly one"});
  LoadReport report;
  const TriangleMesh mesh = load_mesh(write_text(temp_dir(), "frame.obj", obj), &report);
  EXPECT_EQ(mesh.face_count(), 8);
  EXPECT_EQ(mesh.topology().boundary_loops.size(), 2u);
  EXPECT_TRUE(report.warnings.empty());
}

TEST(MeshIoTopology, DiskWithASeparateClosedPiece) {
  // A square (two triangles) plus a tetrahedron far away: one boundary loop, two pieces.
  const std::string obj =
      "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 3 4\n"
      "v 5 5 5\nv 6 5 5\nv 5 6 5\nv 5 5 6\nf 5 7 6\nf 5 6 8\nf 6 7 8\nf 7 5 8\n";
  expect_contains(reject("pieces.obj", obj, disk_only()), {"pieces.obj", "2 separate pieces"});
  EXPECT_EQ(load_mesh(write_text(temp_dir(), "pieces.obj", obj)).face_count(), 6);
}

TEST(MeshIoTopology, OneBoundaryLoopWithAHandle) {
  // A 6 x 6 torus with one face removed: one boundary loop, genus 1.
  const int n = 6;
  std::string obj;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const double u = 2 * M_PI * i / n, v = 2 * M_PI * j / n;
      obj += "v " + std::to_string((3 + std::cos(v)) * std::cos(u)) + " " +
             std::to_string((3 + std::cos(v)) * std::sin(u)) + " " + std::to_string(std::sin(v)) +
             "\n";
    }
  auto id = [](int i, int j) { return std::to_string((j % n) * n + (i % n) + 1); };
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      obj += "f " + id(i, j) + " " + id(i + 1, j) + " " + id(i + 1, j + 1) + "\n";
      if (i + j > 0) obj += "f " + id(i, j) + " " + id(i + 1, j + 1) + " " + id(i, j + 1) + "\n";
    }
  expect_contains(reject("handle.obj", obj, disk_only()),
                  {"handle.obj", "not a topological disk", "Euler characteristic -1"});
  EXPECT_EQ(load_mesh(write_text(temp_dir(), "handle.obj", obj)).face_count(), 2 * n * n - 1);
}

// ---------------------------------------------------------------------------------------------
// Writing.

TEST(MeshIoWrite, AtomicWriteReplacesAndLeavesNoTemporaryFile) {
  const std::string dir = temp_dir();
  const std::string path = dir + "/out.txt";
  write_file_atomically(path, "first");
  write_file_atomically(path, "second\n");
  EXPECT_EQ(read_text(path), "second\n");
  int files = 0;
  for (const auto& entry : fs::directory_iterator(dir)) {
    ++files;
    EXPECT_EQ(entry.path().filename(), "out.txt");
  }
  EXPECT_EQ(files, 1);
}

TEST(MeshIoWrite, AtomicWriteErrorNamesThePath) {
  const std::string path = temp_dir() + "/missing-folder/out.obj";
  try {
    write_file_atomically(path, "x");
    ADD_FAILURE() << "no exception";
  } catch (const InvalidInput& e) {
    expect_contains(e.what(), {path.c_str(), "cannot write"});
  }
  EXPECT_THROW(save_obj(grid_mesh(), path), InvalidInput);
  // A folder in the way of the target.
  const std::string dir = temp_dir();
  fs::create_directories(dir + "/taken.obj");
  EXPECT_THROW(save_obj(grid_mesh(), dir + "/taken.obj"), InvalidInput);
}

}  // namespace
}  // namespace gridshell
