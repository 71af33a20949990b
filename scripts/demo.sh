#!/usr/bin/env bash
# SPDX-License-Identifier: GPL-3.0-or-later
# The main job on a built-in example: set up, build, then patch, design and simulate the double
# vault; results in out/double-vault/, a Table 1-like summary on stdout.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
bash scripts/build.sh
./build/gridshell run example:double-vault --out out/double-vault
