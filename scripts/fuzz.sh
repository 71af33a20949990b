#!/usr/bin/env bash
# SPDX-License-Identifier: GPL-3.0-or-later
# Builds the libFuzzer targets (tests/fuzz, docs/fuzzing.md) with clang + ASan + UBSan in
# ./build-sanitized (scripts/build-sanitized.sh) and runs each for SECONDS (default 20) on a copy
# of its seed corpus, the inputs that once failed (tests/fuzz/regressions) included. Fails on the
# first crash, sanitizer report, leak or input slower than 1 s; the input is left in
# build-sanitized/fuzz/artifacts/<target>/ — add it to tests/fuzz/regressions/<target>/ with the
# fix. Usage: scripts/fuzz.sh [SECONDS] [TARGET...]
set -euo pipefail
cd "$(dirname "$0")/.."
seconds="${1:-20}"
shift || true
targets=("$@")
[ ${#targets[@]} -eq 0 ] && targets=(mesh_obj mesh_off mesh_ply mesh_stl request_json corners)

# The fuzz targets live in the sanitized tree (scripts/build-sanitized.sh), beside the tests
# that run there: one clang build for both.
bash scripts/build-sanitized.sh "${targets[@]/#/fuzz_}"

export ASAN_OPTIONS="detect_leaks=1:abort_on_error=1:strict_string_checks=1"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1:abort_on_error=1"
status=0
for t in "${targets[@]}"; do
  work="build-sanitized/fuzz/corpus/$t"
  artifacts="build-sanitized/fuzz/artifacts/$t"
  mkdir -p "$work" "$artifacts"
  dict=()
  [ -f "tests/fuzz/dict/$t.dict" ] && dict=(-dict="tests/fuzz/dict/$t.dict")
  # The new inputs go to the work corpus (kept between runs in build-sanitized/fuzz), the seeds and the
  # regressions are read only. -timeout=1: an input that takes longer is a hang.
  # FUZZ_SEED fixes libFuzzer's random seed (CI: a gate should not turn red by luck); unset, each
  # run takes a new seed.
  seed=()
  [ -n "${FUZZ_SEED:-}" ] && seed=(-seed="$FUZZ_SEED")
  inputs=("$work" "tests/fuzz/corpus/$t")
  # git keeps no empty folders: a target without kept failures has no regressions/ folder.
  [ -d "tests/fuzz/regressions/$t" ] && inputs+=("tests/fuzz/regressions/$t")
  if ! "./build-sanitized/tests/fuzz/fuzz_$t" "${inputs[@]}" "${seed[@]}" \
      "${dict[@]}" -max_total_time="$seconds" -timeout=1 -rss_limit_mb=2048 -max_len=8192 \
      -print_final_stats=1 -artifact_prefix="$artifacts/" >"build-sanitized/fuzz/$t.log" 2>&1; then
    echo "fuzz: $t FAILED; input in $artifacts/, log build-sanitized/fuzz/$t.log:" >&2
    tail -n 60 "build-sanitized/fuzz/$t.log" >&2
    status=1
  fi
  runs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "build-sanitized/fuzz/$t.log" | grep -o '[0-9]*$' || echo "?")
  cov=$(grep -o 'cov: [0-9]*' "build-sanitized/fuzz/$t.log" | tail -n 1 || true)
  echo "fuzz: $t ${seconds}s: $runs inputs, $cov, corpus $(ls "$work" | wc -l) files"
done
exit $status
