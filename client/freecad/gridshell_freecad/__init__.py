# SPDX-License-Identifier: GPL-3.0-or-later
"""gridshell for FreeCAD: design and simulate an elastic geodesic gridshell on a Mesh object,
computed by a gridshell daemon (gridshelld) over its HTTP API. ``core`` works without the GUI
(freecadcmd); ``gui`` adds the commands and the task panel. docs/freecad.md."""
