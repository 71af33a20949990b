#!/usr/bin/env bash
# SPDX-License-Identifier: GPL-3.0-or-later
# Configures and builds gridshell (optimized, Ninja, ccache) into ./build.
set -euo pipefail
cd "$(dirname "$0")/.."
# GRIDSHELL_WERROR=1 (as .ci/run sets it): warnings are errors. Extra arguments are ninja targets
# (scripts/demo.sh builds the CLI alone); without them everything is built.
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DGRIDSHELL_BUILD_SERVER="${GRIDSHELL_BUILD_SERVER:-ON}" \
  -DGRIDSHELL_WERROR="$([ "${GRIDSHELL_WERROR:-0}" = 1 ] && echo ON || echo OFF)" >/dev/null
cmake --build build -j "$(nproc)" ${1:+--target "$@"}
[ $# -gt 0 ] && exit 0
# The CAD plugins' installable zips (build/gridshell_blender.zip, build/gridshell_freecad.zip).
python3 scripts/build-plugins.py build
