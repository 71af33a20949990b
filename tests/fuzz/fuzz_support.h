// SPDX-License-Identifier: GPL-3.0-or-later
// Shared checks of the fuzz targets (tests/fuzz, docs/fuzzing.md).
//
// A target feeds its input to one parser and accepts two outcomes only: a result that satisfies
// the parser's invariants, or gridshell::InvalidInput with a non-empty message. Anything else — a
// crash, a sanitizer report, another exception, an Internal error, a broken invariant — aborts,
// which libFuzzer reports as a crash and the replay driver (replay_main.cpp) as a failed test.
#pragma once

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "gridshell/foundation/errors.h"
#include "gridshell/mesh/mesh.h"
#include "gridshell/mesh/mesh_io.h"

namespace gridshell::fuzz {

[[noreturn]] inline void fail(const std::string& what) {
  std::fprintf(stderr, "fuzz: %s\n", what.c_str());
  std::abort();
}

/// Only InvalidInput, with something to tell the user, is an acceptable failure.
inline void expect_invalid_input(const Error& e) {
  if (e.code() != ErrorCode::InvalidInput)
    fail(std::string("unexpected error code ") + to_string(e.code()) + ": " + e.what());
  if (e.message().empty()) fail("InvalidInput without a message");
}

/// The loader's promises (mesh_io.h): indices in range, finite coordinates, no degenerate face
/// indices, a vertex map into the loaded mesh.
inline void check_loaded(const TriangleMesh& mesh, const LoadReport& report) {
  const int n = mesh.vertex_count();
  if (n == 0 || mesh.face_count() == 0) fail("loaded mesh is empty");
  for (const Vec3& p : mesh.vertices())
    if (!std::isfinite(p.x()) || !std::isfinite(p.y()) || !std::isfinite(p.z()))
      fail("non-finite coordinate in a loaded mesh");
  for (const Face& f : mesh.faces()) {
    for (int k = 0; k < 3; ++k)
      if (f[k] < 0 || f[k] >= n) fail("face index out of range in a loaded mesh");
    if (f[0] == f[1] || f[1] == f[2] || f[0] == f[2]) fail("degenerate face in a loaded mesh");
  }
  for (int v : report.vertex_of_file_vertex)
    if (v < -1 || v >= n) fail("vertex_of_file_vertex out of range");
}

/// One mesh file through read_mesh, the CLI's and the daemon's parser.
inline int read_mesh_input(const unsigned char* data, std::size_t size, MeshFormat format) {
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  try {
    LoadReport report;
    const TriangleMesh mesh = read_mesh(bytes, format, "fuzz", &report);
    check_loaded(mesh, report);
  } catch (const Error& e) {
    expect_invalid_input(e);
  }
  return 0;
}

}  // namespace gridshell::fuzz
