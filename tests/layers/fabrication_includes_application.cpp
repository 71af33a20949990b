// SPDX-License-Identifier: GPL-3.0-or-later
// Back-edge probe: the kernel's top layer reaching for the application layer must not compile.
#include "gridshell/application/requests.h"

int main() { return 0; }
