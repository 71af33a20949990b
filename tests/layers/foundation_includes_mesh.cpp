// SPDX-License-Identifier: GPL-3.0-or-later
// Back-edge probe: the foundation reaching for the mesh layer must not compile.
#include "gridshell/mesh/mesh.h"

int main() { return 0; }
