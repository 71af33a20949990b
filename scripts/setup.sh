#!/usr/bin/env bash
# SPDX-License-Identifier: GPL-3.0-or-later
# Installs everything gridshell needs from Debian 12 packages. Idempotent: installs only what is missing.
set -euo pipefail
PKGS=(
  build-essential cmake ninja-build ccache pkg-config clang-format
  libcgal-dev libeigen3-dev libgmp-dev libmpfr-dev libboost-dev libtbb-dev
  libceres-dev libsuitesparse-dev
  libprotobuf-dev protobuf-compiler libgrpc++-dev protobuf-compiler-grpc libssl-dev
  libgtest-dev libgmock-dev libcli11-dev nlohmann-json3-dev
  libcsv-dev haproxy libdxflib-dev libnanoflann-dev python3-ezdxf
)
missing=()
for p in "${PKGS[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  SUDO=""
  [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  echo "setup: installing ${missing[*]}" >&2
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >&2
fi
