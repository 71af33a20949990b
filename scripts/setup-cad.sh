#!/usr/bin/env bash
# SPDX-License-Identifier: GPL-3.0-or-later
# Installs what the CAD plugins' tests need from Debian 12 packages (group "cad" of
# scripts/packages.txt): Blender (3.4) and FreeCAD (0.20), without recommended packages (both
# run headless without them: `blender -b`, `freecadcmd`), Xvfb with xauth (xvfb-run) for the
# tests and screenshots of their real windows, and curl. Idempotent.
set -euo pipefail
bash "$(dirname "$0")/install-packages.sh" cad
