// SPDX-License-Identifier: GPL-3.0-or-later
// Back-edge probe: application-layer code that declares a batch-layer function by hand (no
// header needed) must not link, because gridshell_application does not link gridshell_batch.
#include <string>

#include "gridshell/application/options.h"

namespace gridshell::sweep {
std::string now_iso8601();  // lives in gridshell_batch
}  // namespace gridshell::sweep

int main() {
  return static_cast<int>(gridshell::sweep::now_iso8601().size() +
                          gridshell::option_specs().size());
}
