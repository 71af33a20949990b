// SPDX-License-Identifier: GPL-3.0-or-later
// Control probe: an application-layer file including an application-layer header builds.
#include "gridshell/application/options.h"

int main() { return static_cast<int>(gridshell::option_specs().size()) > 0 ? 0 : 1; }
