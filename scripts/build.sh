#!/usr/bin/env bash
# SPDX-License-Identifier: GPL-3.0-or-later
# Configures and builds gridshell (optimized, Ninja, ccache) into ./build.
set -euo pipefail
cd "$(dirname "$0")/.."
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DGRIDSHELL_BUILD_SERVER="${GRIDSHELL_BUILD_SERVER:-ON}" >/dev/null
cmake --build build -j "$(nproc)"
# The CAD plugins' installable zips (build/gridshell_blender.zip, build/gridshell_freecad.zip).
python3 scripts/build-plugins.py build
