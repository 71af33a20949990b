// SPDX-License-Identifier: GPL-3.0-or-later
// Back-edge probe: the batch layer reaching for the CLI's headers must not compile.
#include "cli_support.h"

int main() { return 0; }
