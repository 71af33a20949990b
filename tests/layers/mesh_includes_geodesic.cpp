// SPDX-License-Identifier: GPL-3.0-or-later
// Back-edge probe: the mesh layer reaching for the geodesic layer must not compile.
#include "gridshell/geodesic/geodesic.h"

int main() { return 0; }
