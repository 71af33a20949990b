#!/usr/bin/env bash
# SPDX-License-Identifier: GPL-3.0-or-later
# Installs what the CAD plugins' tests need from Debian 12 packages: Blender (3.4) and FreeCAD
# (0.20), without recommended packages (both run headless without them: `blender -b`,
# `freecadcmd`), Xvfb with xauth (xvfb-run) for the tests and screenshots of their real windows,
# and curl (a test compares its answer with the add-on's). Idempotent: installs only what is
# missing (root, as on CI; sudo otherwise).
set -euo pipefail
PKGS=(blender freecad xvfb xauth curl)
missing=()
for p in "${PKGS[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  SUDO=""
  [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  echo "setup-cad: installing ${missing[*]}" >&2
  $SUDO apt-get -o DPkg::Lock::Timeout=600 update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get -o DPkg::Lock::Timeout=600 install -y -qq --no-install-recommends "${missing[@]}" >&2
fi
