// SPDX-License-Identifier: GPL-3.0-or-later
// Back-edge probe: the geodesic layer reaching for the design layer must not compile.
#include "gridshell/design/patch.h"

int main() { return 0; }
