// SPDX-License-Identifier: GPL-3.0-or-later
// Control probe: a mesh-layer file including a mesh-layer header builds.
#include "gridshell/mesh/mesh.h"

int main() { return gridshell::TriangleMesh().vertex_count(); }
