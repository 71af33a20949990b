#!/bin/bash
# SPDX-License-Identifier: GPL-3.0-or-later
# Checks that a change left every output alone: runs `gridshell run` and `gridshell fabricate` on
# the seven paper-like examples with two builds of the CLI and compares the folders byte for byte
# (design.json, deployment.json, the views, the kit), apart from timings: report.json is all
# timings and is skipped, and deployment.json's "seconds*" members are dropped before comparing.
#
#   bash scripts/outputs-identical.sh OLD_GRIDSHELL NEW_GRIDSHELL [WORKDIR]
#
# e.g. with the old binary copied aside before a refactor. Exit 0 when identical.
set -euo pipefail
old=$1
new=$2
work=${3:-$(mktemp -d)}
examples=(torus-wide waves-bump sphere double-vault waves archway triple-vault)
for side in old new; do
  bin=${!side}
  for ex in "${examples[@]}"; do
    "$bin" run "example:$ex" --out "$work/$side/$ex" --quiet --threads 2 >/dev/null
    "$bin" fabricate "$work/$side/$ex/design.json" --unit cm --out "$work/$side/$ex-kit" \
      --quiet >/dev/null
  done
  # Timings differ from run to run: drop them from deployment.json.
  find "$work/$side" -name deployment.json -exec sed -i '/"seconds[a-z_]*": /d' {} +
done
if diff -r -x report.json "$work/old" "$work/new"; then
  echo "identical: ${#examples[@]} examples (run + fabricate) in $work"
else
  echo "outputs differ (above); folders in $work" >&2
  exit 1
fi
