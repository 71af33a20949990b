#!/usr/bin/env bash
# SPDX-License-Identifier: GPL-3.0-or-later
# Configures and builds ./build-sanitized: the one tree that serves both the sanitized tests
# (scripts/test-sanitizers.sh) and fuzzing (scripts/fuzz.sh). clang with AddressSanitizer,
# UndefinedBehaviorSanitizer and libFuzzer's coverage instrumentation on every target, -O1;
# the kernel, the examples, the application layer and the CLI's --corners syntax with their
# tests (tests/<layer>, tests/examples, tests/application) and the fuzz targets, but not the CLI
# itself. No daemon, no client or benchmark tests and no layer probes: those run in the main
# build (scripts/test.sh).
# docs/testing.md, "Sanitizers and fuzzing", says why. Installs clang and libFuzzer from Debian
# when missing (group "sanitize" of scripts/packages.txt). Extra arguments are ninja targets
# (default: all).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
bash scripts/install-packages.sh sanitize
start=$(date +%s)
cmake -S . -B build-sanitized -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_CXX_COMPILER=clang++ -DGRIDSHELL_SANITIZE=ON -DGRIDSHELL_FUZZ=ON \
  -DGRIDSHELL_BUILD_SERVER=OFF -DGRIDSHELL_LAYER_TESTS=OFF \
  "-DGRIDSHELL_TEST_DIRS=foundation;mesh;geodesic;design;simulation;fabrication;examples;application" \
  -DGRIDSHELL_WERROR="$([ "${GRIDSHELL_WERROR:-0}" = 1 ] && echo ON || echo OFF)" >/dev/null
cmake --build build-sanitized -j "$(nproc)" ${1:+--target "$@"}
echo "build-sanitized: build took $(($(date +%s) - start)) s"
