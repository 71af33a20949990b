#!/usr/bin/env bash
# SPDX-License-Identifier: GPL-3.0-or-later
# The main job on a built-in example: set up, build the CLI, then patch, design and simulate the
# double vault; results in out/double-vault/, a Table 1-like summary on stdout.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
# The CLI alone: the daemon, the tests and the plugins are not needed for the main job.
bash scripts/build.sh gridshell
./build/gridshell run example:double-vault --out out/double-vault
