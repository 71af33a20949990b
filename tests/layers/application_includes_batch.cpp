// SPDX-License-Identifier: GPL-3.0-or-later
// Back-edge probe: the application layer reaching for the batch layer must not compile.
#include "gridshell/batch/sweep.h"

int main() { return 0; }
