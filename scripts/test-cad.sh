#!/usr/bin/env bash
# SPDX-License-Identifier: GPL-3.0-or-later
# The Python client's tests (tests/python) and the CAD plugins' tests in real Blender and FreeCAD
# (tests/cad): headless (blender -b, freecadcmd) and in their real windows under Xvfb, each
# against a real gridshelld on free loopback ports that the test starts and stops. Needs the C++
# build (./build/gridshelld and ./build/gridshell, or GRIDSHELL_BUILD=dir), the plugin zips
# (scripts/build-plugins.py, run by scripts/build.sh) and scripts/setup-cad.sh. Prints each
# part's wall time. GRIDSHELL_SCREENSHOTS=DIR: the window tests also save the docs' screenshots.
set -euo pipefail
cd "$(dirname "$0")/.."
build="${GRIDSHELL_BUILD:-$PWD/build}"
timed() {
  local name="$1" t0
  shift
  t0=$(date +%s)
  "$@"
  echo "test-cad: $name took $(($(date +%s) - t0)) s"
}
# FreeCAD's own progress ("create mesh structure... (42 %)") dropped from the log.
quiet_freecad() { "$@" 2>&1 | sed -u -E 's/[[:space:]]*\([0-9]+ %\)//g; /^[[:space:]]*$/d'; }
xvfb() { xvfb-run -a -s "-screen 0 1440x900x24" "$@"; }

export PYTHONDONTWRITEBYTECODE=1  # no __pycache__ in the source tree
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT

timed "python client" python3 -m unittest discover -s tests/python -t tests/python -v
timed "blender" blender -b --factory-startup --python-exit-code 1 --python tests/cad/test_blender.py
timed "blender zip" blender -b --factory-startup --python-exit-code 1 --python tests/cad/test_blender_zip.py
timed "blender window" xvfb blender --factory-startup --enable-event-simulate \
  --python tests/cad/test_blender_ui.py
# FreeCAD writes its settings into its user folder: a temporary one.
mkdir -p "$tmp/freecadcmd"
(export FREECAD_USER_HOME="$tmp/freecadcmd" && timed "freecad" quiet_freecad freecadcmd tests/cad/test_freecad.py)
# The workbench as a user installs it: the zip unpacked into the user's Mod folder (a temporary
# FreeCAD user folder here). The Start page's web view refuses to run as root without this.
mkdir -p "$tmp/freecad/Mod"
python3 -m zipfile -e "$build/gridshell_freecad.zip" "$tmp/freecad/Mod/"
timed "freecad window" env FREECAD_USER_HOME="$tmp/freecad" QTWEBENGINE_DISABLE_SANDBOX=1 \
  bash -c "set -o pipefail; $(declare -f quiet_freecad xvfb); quiet_freecad xvfb freecad tests/cad/test_freecad_gui.py"
