#!/usr/bin/env bash
# SPDX-License-Identifier: GPL-3.0-or-later
# Builds the libFuzzer targets (tests/fuzz, docs/fuzzing.md) with clang + ASan + UBSan into
# ./build-fuzz and runs each for SECONDS (default 20) on a copy of its seed corpus, the inputs
# that once failed (tests/fuzz/regressions) included. Fails on the first crash, sanitizer report,
# leak or input slower than 1 s; the input is left in build-fuzz/artifacts/<target>/ — add it to
# tests/fuzz/regressions/<target>/ with the fix. Usage: scripts/fuzz.sh [SECONDS] [TARGET...]
set -euo pipefail
cd "$(dirname "$0")/.."
seconds="${1:-20}"
shift || true
targets=("$@")
[ ${#targets[@]} -eq 0 ] && targets=(mesh_obj mesh_off mesh_ply mesh_stl request_json corners)

bash scripts/setup.sh
missing=()
for p in clang libfuzzer-14-dev libclang-rt-14-dev; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  SUDO=""
  [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >&2
fi

start=$(date +%s)
# The daemon is not needed: the request target decodes JSON as the gateway does, without gRPC.
cmake -S . -B build-fuzz -G Ninja -DCMAKE_CXX_COMPILER=clang++ -DGRIDSHELL_SANITIZE=ON \
  -DGRIDSHELL_FUZZ=ON -DGRIDSHELL_BUILD_SERVER=OFF >/dev/null
cmake --build build-fuzz -j "$(nproc)" --target "${targets[@]/#/fuzz_}"
echo "fuzz: build took $(($(date +%s) - start)) s"

export ASAN_OPTIONS="detect_leaks=1:abort_on_error=1:strict_string_checks=1"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1:abort_on_error=1"
status=0
for t in "${targets[@]}"; do
  work="build-fuzz/corpus/$t"
  artifacts="build-fuzz/artifacts/$t"
  mkdir -p "$work" "$artifacts"
  dict=()
  [ -f "tests/fuzz/dict/$t.dict" ] && dict=(-dict="tests/fuzz/dict/$t.dict")
  # The new inputs go to the work corpus (kept between runs in build-fuzz), the seeds and the
  # regressions are read only. -timeout=1: an input that takes longer is a hang.
  # FUZZ_SEED fixes libFuzzer's random seed (CI: a gate should not turn red by luck); unset, each
  # run takes a new seed.
  seed=()
  [ -n "${FUZZ_SEED:-}" ] && seed=(-seed="$FUZZ_SEED")
  inputs=("$work" "tests/fuzz/corpus/$t")
  # git keeps no empty folders: a target without kept failures has no regressions/ folder.
  [ -d "tests/fuzz/regressions/$t" ] && inputs+=("tests/fuzz/regressions/$t")
  if ! "./build-fuzz/tests/fuzz/fuzz_$t" "${inputs[@]}" "${seed[@]}" \
      "${dict[@]}" -max_total_time="$seconds" -timeout=1 -rss_limit_mb=2048 -max_len=8192 \
      -print_final_stats=1 -artifact_prefix="$artifacts/" >"build-fuzz/$t.log" 2>&1; then
    echo "fuzz: $t FAILED; input in $artifacts/, log build-fuzz/$t.log:" >&2
    tail -n 60 "build-fuzz/$t.log" >&2
    status=1
  fi
  runs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "build-fuzz/$t.log" | grep -o '[0-9]*$' || echo "?")
  cov=$(grep -o 'cov: [0-9]*' "build-fuzz/$t.log" | tail -n 1 || true)
  echo "fuzz: $t ${seconds}s: $runs inputs, $cov, corpus $(ls "$work" | wc -l) files"
done
exit $status
