#!/usr/bin/env bash
# The main job on a built-in example: set up, build, and run the pipeline on the double vault.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
bash scripts/build.sh
./build/gridshell design example:double-vault --out out/double-vault
