// SPDX-License-Identifier: GPL-3.0-or-later
// gridshell — reading target meshes (OBJ, OFF, PLY, STL) and writing OBJ, with a load report.
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "gridshell/mesh/mesh.h"

namespace gridshell {

struct MeshLoadOptions {
  /// Reject meshes that are not a topological disk (exactly one boundary loop, one piece, no
  /// handle). Default: false: any orientable manifold surface is a target (holes, several
  /// boundary loops, closed meshes); the patch cut out of it must be a disk, which cut_patch
  /// checks.
  bool require_single_boundary = false;
  /// Vertices closer than this (relative to the bounding-box diagonal) are merged. Default 1e-12.
  double duplicate_tolerance = 1e-12;
};

/// What the loader found and repaired. Repairs never change the meaning of the surface.
struct LoadReport {
  std::string format;                 ///< "obj" | "off" | "ply" | "stl"
  int file_vertices = 0;              ///< vertices as read from the file
  int file_faces = 0;                 ///< polygons as read from the file
  int polygons_triangulated = 0;      ///< faces with more than three corners, fan-split
  int degenerate_faces_removed = 0;   ///< zero-area or repeated-index triangles dropped
  int duplicate_vertices_merged = 0;  ///< coincident vertices welded to the first occurrence
  int isolated_vertices_removed = 0;  ///< vertices no face uses
  std::vector<std::string> warnings;  ///< one line per repair kind, ready to print
  /// For each vertex of the file (0-based, file order): its index in the loaded mesh, or -1 if
  /// it was removed. Merged duplicates map to the vertex they were welded to. When nothing was
  /// removed this is the identity: vertex indices are kept in file order.
  std::vector<int> vertex_of_file_vertex;
};

/// The mesh file formats gridshell reads.
enum class MeshFormat { Obj, Off, Ply, Stl };

/// The format named by a file name's extension or by the format's own name ("cube.STL",
/// ".ply", "off"), case-insensitive; nullopt for anything else.
std::optional<MeshFormat> mesh_format_from_name(const std::string& name);
/// "obj" | "off" | "ply" | "stl".
const char* to_string(MeshFormat format);

/// Reads a mesh from the bytes of a file of the given format: the same parser, repairs, checks
/// and report as `load_mesh`. Errors name `name` as their field (the file name, or the field of
/// a request that carried the bytes) and the line or element in the message. Never reads
/// outside `data`.
TriangleMesh read_mesh(std::string_view data, MeshFormat format, const std::string& name,
                       LoadReport* report = nullptr, const MeshLoadOptions& options = {});

/// The vertices of a mesh file as its parser reads them (file order, every vertex; faces may be
/// absent and are not checked): a point cloud given as OBJ `v` lines, OFF or PLY (ASCII and
/// binary; properties other than x, y, z, such as normals, are skipped). Throws InvalidInput
/// naming `name` and the line or element for an empty file, a malformed one and NaN/Inf.
std::vector<Vec3> read_points(std::string_view data, MeshFormat format, const std::string& name);

/// A whole file as bytes, with the mesh loader's checks (exists, regular file, at most 4 GiB);
/// InvalidInput naming the path.
std::string read_file_bytes(const std::string& path);

/// Reads a mesh; the format is chosen by the extension (case-insensitive): .obj .off .ply (ASCII
/// and binary little/big endian) .stl (ASCII and binary). Polygons are triangulated.
/// Throws InvalidInput whose field is the path and whose message names the line or element for:
/// missing or unreadable file, unknown extension, empty file or no faces, unparseable
/// line/header/element, NaN/Inf coordinate, out-of-range index, non-manifold edge or vertex, a
/// surface that is not orientable (and, with require_single_boundary, one that is not a disk).
TriangleMesh load_mesh(const std::string& path, LoadReport* report = nullptr,
                       const MeshLoadOptions& options = {});

/// A mesh given as arrays in memory (the daemon's packed arrays): the same repairs, checks and
/// report as `load_mesh`; errors name the element as a field under `name` ("mesh.faces[7]",
/// "mesh.vertices[3]"), vertices and faces numbered from 0 in the given order. Throws InvalidInput
/// for no vertices, a non-finite coordinate, no faces, an out-of-range index and every topology
/// problem.
TriangleMesh mesh_from_arrays(const std::string& name, const std::vector<Vec3>& vertices,
                              const std::vector<Face>& faces, LoadReport* report = nullptr,
                              const MeshLoadOptions& options = {});

/// The mesh as Wavefront OBJ text (shortest round-trip decimal coordinates, 1-based faces).
std::string obj_text(const TriangleMesh& mesh);
/// The same for plain arrays (written as they are, unchecked).
std::string obj_text(const std::vector<Vec3>& vertices, const std::vector<Face>& faces);

/// Writes a Wavefront OBJ atomically (temporary file in the same folder, then rename).
void save_obj(const TriangleMesh& mesh, const std::string& path);

/// Writes `contents` to `path` atomically (temporary file + rename). Throws InvalidInput with the
/// path as its field if it cannot be written.
void write_file_atomically(const std::string& path, const std::string& contents);

}  // namespace gridshell
