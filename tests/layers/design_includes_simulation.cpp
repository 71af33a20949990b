// SPDX-License-Identifier: GPL-3.0-or-later
// Back-edge probe: the design layer reaching for the simulation layer must not compile.
#include "gridshell/simulation/simulation.h"

int main() { return 0; }
