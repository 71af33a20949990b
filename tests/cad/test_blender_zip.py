# SPDX-License-Identifier: GPL-3.0-or-later
"""The installable zip (build/gridshell_blender.zip) installs and enables in real Blender the way a
user does it (Preferences > Add-ons > Install...), into a temporary user scripts folder, and runs
with the copy of the Python client it carries:

    blender -b --factory-startup --python-exit-code 1 --python tests/cad/test_blender_zip.py
"""

import os
import shutil
import sys
import tempfile

import addon_utils
import bpy

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
ZIP = os.path.join(os.environ.get("GRIDSHELL_BUILD", os.path.join(ROOT, "build")), "gridshell_blender.zip")

scripts = tempfile.mkdtemp(prefix="gridshell-blender-scripts-")
try:
    addons = os.path.join(scripts, "addons")
    os.makedirs(addons)
    bpy.context.preferences.filepaths.script_directory = scripts
    bpy.utils.refresh_script_paths()
    assert os.path.exists(ZIP), "no %s (scripts/build-plugins.py builds it)" % ZIP
    bpy.ops.preferences.addon_install(filepath=ZIP, target="PREFS")
    installed = [m for m in addon_utils.modules(refresh=True) if m.__name__ == "gridshell_blender"]
    assert installed, "the add-on is not listed after installing the zip"
    path = installed[0].__file__
    bpy.ops.preferences.addon_enable(module="gridshell_blender")
    import gridshell_blender
    from gridshell_blender.remote import gs

    here = os.path.dirname(gridshell_blender.__file__)
    assert not here.startswith(os.path.join(ROOT, "client")), here
    assert os.path.dirname(gs.__file__) == os.path.join(here, "gridshell_client"), gs.__file__
    assert hasattr(bpy.ops.gridshell, "design") and hasattr(bpy.types.Scene, "gridshell")
    assert hasattr(bpy.ops.gridshell, "refresh_options"), "no refresh of the daemon's materials"
    assert hasattr(bpy.ops.gridshell, "layout") and hasattr(bpy.ops.gridshell, "build_layout"), "no layouts"
    assert hasattr(gs, "Description") and hasattr(gs.options, "cached"), "the client it carries is old"
    assert bpy.context.scene.gridshell.server, "no default server"
    bpy.ops.preferences.addon_disable(module="gridshell_blender")
    assert not hasattr(bpy.types.Scene, "gridshell")
    print("blender zip: installed at %s, client %s" % (path, gs.__file__))
    print("blender zip: 1 passed, 0 failed")
finally:
    shutil.rmtree(scripts, ignore_errors=True)
