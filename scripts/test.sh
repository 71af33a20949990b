#!/usr/bin/env bash
# SPDX-License-Identifier: GPL-3.0-or-later
# Set up, build and run the whole test suite: the C++ tests (ctest), then the web page's unit
# and end-to-end tests (headless Chromium against a real gridshelld; tests/web), then the Python
# client's and the CAD plugins' tests (real Blender and FreeCAD against a real gridshelld).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
bash scripts/build.sh
ctest --test-dir build --output-on-failure -j "$(nproc)"
bash scripts/setup-web.sh
bash scripts/build-web.sh
bash scripts/test-web.sh
bash scripts/setup-cad.sh
bash scripts/test-cad.sh
