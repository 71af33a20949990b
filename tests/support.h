// SPDX-License-Identifier: GPL-3.0-or-later
// Shared helpers for the GoogleTest suite.
#pragma once

#include <array>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include "gridshell/mesh/mesh.h"

namespace gridshell::testing {

/// Paths of the real freeform meshes in tests/data/meshes (enneper2, knet1, pillow_1; MIT, see
/// the LICENSE-DOS there).
std::vector<std::string> test_mesh_paths();

/// Path of one file in tests/data/meshes, e.g. test_mesh_path("knet1.obj").
std::string test_mesh_path(const std::string& name);

/// A fresh empty temporary folder, removed at process exit.
std::string temp_dir();

/// Writes `contents` to `dir/name` and returns the path.
/// The sphere example's 33 x 33 grid in 2 x 2 patches, as a layout file's JSON (corners by
/// file-order vertex index; patches P1, P2, P3, P4 counter-clockwise).
std::string sphere_layout_json();

std::string write_text(const std::string& dir, const std::string& name,
                       const std::string& contents);

struct CommandResult {
  int exit_code = -1;
  std::string out;  ///< standard output
  std::string err;  ///< standard error
};

/// Runs the gridshell CLI with the given argument string (shell-quoted by the caller).
CommandResult run_cli(const std::string& arguments);
/// Runs a shell command line (e.g. "VAR=x 'prog' args") the same way: output and exit code.
CommandResult run_command(const std::string& command_line);

/// A (nu+1) x (nv+1) grid over (u,v) in [0,1]^2 mapped by `map`, triangulated with alternating
/// diagonals, faces counter-clockwise in (u,v). Vertex (i,j) has index j*(nu+1)+i.
TriangleMesh grid_mesh(int nu, int nv, const std::function<Vec3(double u, double v)>& map);

/// Irregular flat square [0,10]^2: an n x n grid_mesh with interior vertices jittered
/// deterministically (so no two triangles are alike).
TriangleMesh flat_square(int n);

/// A smooth Gaussian bump of height 2.5 over [0,10]^2 on an n x n grid_mesh.
TriangleMesh bump(int n);

/// A closed sphere of radius `radius` about the origin: the regular icosahedron with every
/// triangle split into 4 `subdivisions` times, vertices projected to the sphere; faces
/// counter-clockwise seen from outside. 12 vertices and 20 faces at 0 subdivisions.
TriangleMesh icosphere(int subdivisions, double radius);

/// A flat annulus in the plane z = 0 between radii r0 < r1: `rings` + 1 circles of `sectors`
/// vertices each, faces counter-clockwise seen from +z. Vertex (ring i, sector j) has index
/// i * sectors + j. Two boundary loops.
TriangleMesh annulus(double r0, double r1, int rings, int sectors);

/// A closed torus about the z axis (radii `major` > `minor`): nu x nv vertices, vertex (i, j)
/// at angle 2 pi i / nu round the axis and 2 pi j / nv round the tube has index j * nu + i.
TriangleMesh torus(double major, double minor, int nu, int nv);

/// Closest point to `p` on the triangle (a, b, c), by the Voronoi regions of its vertices,
/// edges and face (Ericson, Real-Time Collision Detection, 5.1.5). Written here, independently
/// of the kernel's closest-point code, as the tests' oracle.
Vec3 closest_point_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c);

/// Distance from `p` to the mesh by brute force over every triangle (the tests' oracle for the
/// kernel's AABB-tree distances: O(faces) per point).
double brute_force_distance(const TriangleMesh& mesh, const Vec3& p);

/// Reads a whole file.
std::string read_text(const std::string& path);

/// `count` points uniformly distributed by area over `triangles`, drawn from `random` (per point:
/// one draw for the triangle, two for the point in it).
std::vector<Vec3> sample_triangles(const std::vector<std::array<Vec3, 3>>& triangles, int count,
                                   std::mt19937_64& random);

}  // namespace gridshell::testing
