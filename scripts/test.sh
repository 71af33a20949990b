#!/usr/bin/env bash
# SPDX-License-Identifier: GPL-3.0-or-later
# Set up, build and run the whole test suite: the C++ tests (ctest), then the web page's unit
# and end-to-end tests (headless Chromium against a real gridshelld; tests/web), then the Python
# client's and the CAD plugins' tests (real Blender and FreeCAD against a real gridshelld).
# Prints each part's wall time.
set -euo pipefail
cd "$(dirname "$0")/.."
timed() {
  local name="$1" t0=$SECONDS
  shift
  "$@"
  echo "test: $name took $((SECONDS - t0)) s"
}
timed "setup" bash scripts/setup.sh
timed "build" bash scripts/build.sh
timed "ctest" ctest --test-dir build --output-on-failure -j "$(nproc)" -LE cluster
timed "cluster" bash scripts/test-cluster.sh  # Slurm sweeps, replicas behind haproxy (starts and stops them)
timed "web setup and build" bash -c 'bash scripts/setup-web.sh && bash scripts/build-web.sh'
timed "web" bash scripts/test-web.sh
timed "cad setup" bash scripts/setup-cad.sh
timed "python and cad" bash scripts/test-cad.sh
