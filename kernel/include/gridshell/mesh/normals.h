// SPDX-License-Identifier: GPL-3.0-or-later
// gridshell — surface normals of a triangle mesh.
#pragma once

#include <vector>

#include "gridshell/mesh/mesh.h"

namespace gridshell {

/// #V area-weighted unit vertex normals (the sum of the incident faces' normals weighted by
/// their areas, normalized; zero for a vertex no face with non-zero area uses).
std::vector<Vec3> vertex_normals(const TriangleMesh& mesh);

}  // namespace gridshell
