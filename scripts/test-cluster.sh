#!/usr/bin/env bash
# SPDX-License-Identifier: GPL-3.0-or-later
# The tests labelled "cluster": `gridshell sweep --engine slurm` on a one-node Slurm started here
# (scripts/slurm-local.sh, stopped at the end whatever happens), and the replicas behind haproxy
# with the fault test (scripts/replicas.sh, started by the tests themselves). Needs the build
# (scripts/build.sh). Each step prints its wall time (docs/deploy.md lists them).
set -euo pipefail
cd "$(dirname "$0")/.."
t0=$SECONDS
bash scripts/slurm-local.sh start
trap 'bash scripts/slurm-local.sh stop' EXIT
echo "test-cluster: Slurm up in $((SECONDS - t0)) s"
eval "$(bash scripts/slurm-local.sh env)"
export SLURM_CONF
t1=$SECONDS
# Fail rather than skip when Slurm or haproxy is missing: here they must be there.
GRIDSHELL_REQUIRE_CLUSTER=1 ctest --test-dir build -L cluster --output-on-failure -j 1
echo "test-cluster: tests took $((SECONDS - t1)) s"
