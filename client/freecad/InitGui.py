# SPDX-License-Identifier: GPL-3.0-or-later
# FreeCAD runs this at start-up with the GUI: the gridshell workbench.
import FreeCADGui


class GridshellWorkbench(FreeCADGui.Workbench):
    MenuText = "gridshell"
    ToolTip = "Elastic geodesic gridshells designed and simulated by gridshelld"

    def Initialize(self):
        import gridshell_freecad.gui as gui

        gui.register()
        self.appendToolbar("gridshell", gui.COMMANDS)
        self.appendMenu("gridshell", gui.COMMANDS)

    def GetClassName(self):
        return "Gui::PythonWorkbench"


FreeCADGui.addWorkbench(GridshellWorkbench())
