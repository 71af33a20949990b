// SPDX-License-Identifier: GPL-3.0-or-later
// Back-edge probe: mesh-layer code that declares a design-layer function by hand (no header
// needed) must not link, because gridshell_mesh does not link gridshell_design.
#include <array>

#include "gridshell/mesh/mesh.h"

namespace gridshell {
std::array<int, 4> auto_corners(const TriangleMesh& mesh);  // lives in gridshell_design
}  // namespace gridshell

int main() { return gridshell::auto_corners(gridshell::TriangleMesh())[0]; }
