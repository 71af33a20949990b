# SPDX-License-Identifier: GPL-3.0-or-later
"""gridshell for Blender: design and simulate an elastic geodesic gridshell on a mesh object,
computed by a gridshell daemon (gridshelld) over its HTTP API. docs/blender.md."""

bl_info = {
    "name": "gridshell",
    "author": "the gridshell developers",
    "version": (0, 1, 0),
    "blender": (3, 4, 0),
    "location": "View3D > Sidebar > gridshell",
    "description": "Elastic geodesic gridshells (Pillwein et al. 2020) designed and simulated by gridshelld",
    "doc_url": "",
    "category": "Mesh",
}

if "operators" in locals():  # "Reload Scripts"
    import importlib

    for _module in (remote, described, properties, mesh_input, results, layouts, operators, panel):  # noqa: F821
        importlib.reload(_module)
else:
    from . import remote, described, properties, mesh_input, results, layouts, operators, panel  # noqa: F401


def register():
    properties.register()
    operators.register()
    panel.register()


def unregister():
    panel.unregister()
    operators.unregister()
    properties.unregister()
    described.forget()
