# SPDX-License-Identifier: GPL-3.0-or-later
# FreeCAD runs this at start-up, with or without the GUI. Nothing to register without the GUI:
# scripts use gridshell_freecad.core directly.
