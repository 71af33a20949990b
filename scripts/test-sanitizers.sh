#!/usr/bin/env bash
# SPDX-License-Identifier: GPL-3.0-or-later
# Builds everything with AddressSanitizer + UndefinedBehaviorSanitizer into ./build-asan and runs
# the test suite there; any sanitizer report fails the run. The CLI and gridshelld that the tests
# start as subprocesses are sanitized too, and inherit the options below.
#
# Reports of processes that the tests start would be easy to miss: a test captures the CLI's
# stderr and often checks only its exit code, and UBSan exits with 1, the CLI's code for invalid
# input. So AddressSanitizer/LeakSanitizer write their reports to build-asan/sanitizer-logs/
# (log_path; the run fails if any file is there, and prints them), and UBSan aborts
# (abort_on_error: exit 134, which no test expects). UBSan has no log_path when it runs with
# ASan (GCC 12): its reports stay on stderr.
#
# The subset (default): the whole suite except six of the eleven ExampleDeployment cases
# (sphere, waves, torus-wide, waves-bump, knet1, pillow_1). Under the sanitizers each takes
# 80-330 s on this 2-core machine, together about 40% of the suite's time, and they run the same
# design and deployment code on more surfaces. The five that stay cover the paths: example
# corners, a mesh file with corner vertices (enneper2), Laplacian smoothing (triple-vault), an
# inner anchor (waves-bump+1inner), and both notch checks; auto corners on knet1 and pillow_1 are
# designed by Design.GridCriteriaOnTheSharedMeshes. scripts/test.sh runs all of them.
# GRIDSHELL_SANITIZE_FULL=1 runs the whole suite. Extra arguments go to ctest (e.g. -R Geodesic).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
start=$(date +%s)
cmake -S . -B build-asan -G Ninja -DGRIDSHELL_SANITIZE=ON >/dev/null
cmake --build build-asan -j "$(nproc)"
built=$(date +%s)
echo "test-sanitizers: build took $((built - start)) s"

logs="$PWD/build-asan/sanitizer-logs"
rm -rf "$logs"
mkdir -p "$logs"
export ASAN_OPTIONS="detect_leaks=1:abort_on_error=1:strict_string_checks=1:detect_stack_use_after_return=1:log_path=$logs/asan"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1:abort_on_error=1"
# The kernel runs about ten times slower under ASan+UBSan, and the solver polls its cancellation
# flag once per iteration: the cancellation latencies that the daemon's tests check get this
# factor (tests/support.h, time_scale).
export GRIDSHELL_TEST_TIME_SCALE="${GRIDSHELL_TEST_TIME_SCALE:-5}"

# Also left out: Compare.RecoversRigidMotionWithNoiseOutliersAndPartialView (a deployment and a
# 100k-point scan; the same registration runs sanitized in Compare.RegistersASmallScanUnderAnyMotion),
# and the automatic corners' search on all eleven examples (issue 18; the search runs under the
# sanitizers on the helicoid, sphere, annulus and shared meshes in the same binary).
subset=(-E '(ExampleDeployment\..*/(sphere|waves|torus_wide|waves_bump|mesh_knet1_obj|mesh_pillow_1_obj)( |$))|Compare\.RecoversRigidMotion|AutoCorners\.ExamplesAreAtLeastAsLargeAsTheFormerRule')
[ "${GRIDSHELL_SANITIZE_FULL:-0}" = 1 ] && subset=()

status=0
# -LE cluster: the Slurm sweeps and the replicas behind haproxy (scripts/test-cluster.sh) run once,
# unsanitized, in scripts/test.sh; the sweep code they use is sanitized by the local sweep tests.
ctest --test-dir build-asan --output-on-failure -j "$(nproc)" -LE cluster "${subset[@]}" "$@" || status=$?
echo "test-sanitizers: tests took $(($(date +%s) - built)) s"
if compgen -G "$logs/*" >/dev/null; then
  echo "test-sanitizers: sanitizer reports:" >&2
  for f in "$logs"/*; do
    echo "==== $f" >&2
    cat "$f" >&2
  done
  status=1
fi
exit $status
