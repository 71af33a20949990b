#!/usr/bin/env bash
# SPDX-License-Identifier: GPL-3.0-or-later
# Installs the missing Debian packages of the named groups of scripts/packages.txt (build, cad,
# web, cluster, sanitize), without recommended packages; root, as on CI, or sudo. Idempotent:
# nothing runs apt when all are there. Waits up to 30 min for another apt to finish (.ci/run
# installs some groups in the background while it builds).
#   bash scripts/install-packages.sh build cad
set -euo pipefail
list="$(dirname "$0")/packages.txt"
wanted=()
for group in "$@"; do
  line="$(grep -E "^$group:" "$list" || true)"
  [ -n "$line" ] || { echo "install-packages: no group '$group' in $list" >&2; exit 2; }
  read -r -a packages <<<"${line#*:}"
  wanted+=("${packages[@]}")
done
missing=()
for p in "${wanted[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
[ ${#missing[@]} -eq 0 ] && exit 0
SUDO=""
[ "$(id -u)" -ne 0 ] && SUDO="sudo"
echo "install-packages: installing ${missing[*]}" >&2
$SUDO apt-get -o DPkg::Lock::Timeout=1800 update -qq
DEBIAN_FRONTEND=noninteractive $SUDO apt-get -o DPkg::Lock::Timeout=1800 install -y -qq \
  --no-install-recommends "${missing[@]}" >&2
