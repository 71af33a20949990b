// SPDX-License-Identifier: GPL-3.0-or-later
// Back-edge probe: the simulation layer reaching for the fabrication layer must not compile.
#include "gridshell/fabrication/kit.h"

int main() { return 0; }
