# SPDX-License-Identifier: GPL-3.0-or-later
"""The workbench's GUI: commands Design, Simulate and Run, and for layouts of several patches
Layout and Build all patches, each opening a task panel with the server and the options; the call runs on a background thread while FreeCAD stays responsive
(progress in the panel and the status bar, Cancel stops the daemon's work), and the results are
built in the document when the answer is in. Errors go to the panel and the report view.

The panel reads the daemon's description (its materials, the options' ranges and help) in the
background when it opens and when the server is edited: the material list and the spin boxes'
ranges are the daemon's (until it is read: the saved material, or the daemon's default, and
ranges only the box's own; the daemon checks every value and names the field it refuses)."""

import sys
import time

import FreeCAD
import FreeCADGui
from PySide2 import QtCore, QtWidgets

from . import core
from .remote import gs

COMMANDS = ["Gridshell_Design", "Gridshell_Simulate", "Gridshell_Run", "Gridshell_Layout",
            "Gridshell_BuildLayout"]
LAYOUT_MODES = ("layout", "build")


def picked_target():
    """(Mesh object, picked points or None) from the selection: the first selected Mesh object,
    and the points picked on it (in picking order) when there are any."""
    for selection in FreeCADGui.Selection.getSelectionEx():
        obj = selection.Object
        if hasattr(obj, "Mesh"):
            points = [FreeCAD.Vector(p) for p in selection.PickedPoints]
            return obj, (points or None)
    return None, None


class TaskPanel:
    """Options, progress and errors of one call (mode "design", "simulate", "run", "layout" or
    "build")."""

    current = None  # the open panel (for scripts and tests)

    def __init__(self, mode):
        TaskPanel.current = self
        self.mode = mode
        self.doc = FreeCAD.ActiveDocument
        self.obj, self.points = picked_target()
        self.settings = core.Settings.load()
        self.call = None
        self.finish = None
        self.timer = QtCore.QTimer()
        self.timer.setInterval(100)
        self.timer.timeout.connect(self.poll)
        self.description = None  # the daemon's description, once read
        self.describing = None  # (server, BackgroundCall) reading the daemon's description
        self.description_timer = QtCore.QTimer()
        self.description_timer.setInterval(50)
        self.description_timer.timeout.connect(self._poll_description)
        self.form = self._build_form()
        self._describe()

    def _build_form(self):
        s = self.settings
        form = QtWidgets.QWidget()
        form.setWindowTitle("gridshell " + self.mode)
        layout = QtWidgets.QFormLayout(form)
        if self.mode == "simulate":
            target = "the design in the group 'gridshell'"
        elif self.obj is None:
            target = "(select a Mesh object)"
        elif self.mode in LAYOUT_MODES:
            target = "%s, several patches (the layout below)" % self.obj.Label
        else:
            target = "%s, corners %s" % (
                self.obj.Label,
                "%d picked points" % len(self.points) if self.points else "automatic",
            )
        layout.addRow("Target", QtWidgets.QLabel(target))
        self.server = QtWidgets.QLineEdit(s.server)
        self.server.editingFinished.connect(self._describe)
        layout.addRow("Server", self.server)
        self.token = QtWidgets.QLineEdit(s.token)
        self.token.setEchoMode(QtWidgets.QLineEdit.Password)
        layout.addRow("Token", self.token)
        self.fields = {}
        self.layout_fields = {}
        if self.mode in LAYOUT_MODES:
            self.layout_source = QtWidgets.QComboBox()
            for key, label in core.LAYOUT_SOURCES:
                self.layout_source.addItem(label, key)
            self.layout_source.setCurrentIndex(max(0, self.layout_source.findData(s.layout)))
            layout.addRow("Layout", self.layout_source)
            self.layout_file = QtWidgets.QLineEdit(s.layout_file)
            self.layout_file.setPlaceholderText("layout.json (a gridshell.v1.Layout or a layout report)")
            browse = QtWidgets.QPushButton("...")
            browse.clicked.connect(self._browse_layout)
            row = QtWidgets.QHBoxLayout()
            row.addWidget(self.layout_file)
            row.addWidget(browse)
            layout.addRow("Layout file", row)
            # The ranges are the daemon's (group "layout" of its description), once read.
            box = QtWidgets.QSpinBox()
            box.setRange(0, 2147483647)
            box.setValue(int(s.max_patches))
            layout.addRow("Patches at most (0 = default)", box)
            self.layout_fields["max_patches"] = box
            box = QtWidgets.QDoubleSpinBox()
            box.setRange(0, 1)
            box.setDecimals(3)
            box.setSingleStep(0.01)
            box.setValue(float(s.coverage_goal))
            layout.addRow("Coverage goal (0 = default)", box)
            self.layout_fields["coverage_goal"] = box

            def sources(_=None):
                automatic = self.layout_source.currentData() == "auto"
                for widget in self.layout_fields.values():
                    widget.setEnabled(automatic)
                self.layout_file.setEnabled(self.layout_source.currentData() == "file")

            self.layout_source.currentIndexChanged.connect(sources)
            sources()
        if self.mode in ("design", "run", "build"):
            self.alpha = QtWidgets.QComboBox()
            self.alpha.addItems(["min", "max", "value"])
            self.alpha_value = QtWidgets.QDoubleSpinBox()
            self.alpha_value.setRange(1, 179)
            self.alpha_value.setSuffix(" °")
            self.alpha_value.setValue(70)
            if s.alpha in ("min", "max"):
                self.alpha.setCurrentText(s.alpha)
            else:
                self.alpha.setCurrentText("value")
                self.alpha_value.setValue(float(str(s.alpha).replace("deg", "") or 70))
            self.alpha_value.setEnabled(self.alpha.currentText() == "value")
            self.alpha.currentTextChanged.connect(lambda text: self.alpha_value.setEnabled(text == "value"))
            row = QtWidgets.QHBoxLayout()
            row.addWidget(self.alpha)
            row.addWidget(self.alpha_value)
            layout.addRow("Planar angle", row)
            # The ranges are the daemon's (_described); until its description is read, only the
            # boxes' own.
            for name, label in (
                ("members_u", "Members u (0 = auto)"),
                ("members_v", "Members v (0 = auto)"),
                ("resolution", "Map resolution"),
                ("interior_anchors", "Inner anchors"),
            ):
                box = QtWidgets.QSpinBox()
                box.setRange(0, 2147483647)
                box.setValue(int(getattr(s, name)))
                layout.addRow(label, box)
                self.fields[name] = box
            for name, label in (("lamella_width", "Lamella width (0 = auto)"),
                                ("lamella_thickness", "Lamella thickness (0 = auto)")):
                box = QtWidgets.QDoubleSpinBox()
                box.setRange(0, sys.float_info.max)
                box.setDecimals(3)
                box.setSuffix(" mm")
                box.setValue(float(getattr(s, name)))
                layout.addRow(label, box)
                self.fields[name] = box
        if self.mode in ("simulate", "run", "build"):
            # The daemon's materials (_described); until they are read, the saved one or the
            # daemon's default.
            self.material = QtWidgets.QComboBox()
            self._fill_materials(None, s.material)
            layout.addRow("Material", self.material)
            self.notches = QtWidgets.QComboBox()
            self.notches.addItems(["both", "on", "off"])
            self.notches.setCurrentText(s.notches)
            layout.addRow("Notches", self.notches)
            self.auto_anchors = QtWidgets.QCheckBox("where each lowers the deviation by 5% or more")
            self.auto_anchors.setChecked(bool(s.auto_anchors))
            layout.addRow("Find inner anchors", self.auto_anchors)
        self.progress = QtWidgets.QProgressBar()
        self.progress.setRange(0, 1000)
        self.progress.setValue(0)
        layout.addRow("Progress", self.progress)
        self.status = QtWidgets.QLabel("Press OK to start; Cancel stops a running call.")
        self.status.setWordWrap(True)
        layout.addRow(self.status)
        return form

    def _browse_layout(self):
        path, _ = QtWidgets.QFileDialog.getOpenFileName(
            self.form, "Layout file", self.layout_file.text(), "Layouts (*.json);;All files (*)")
        if path:
            self.layout_file.setText(path)
            self.layout_source.setCurrentIndex(self.layout_source.findData("file"))

    def _fill_materials(self, description, chosen):
        self.material.clear()
        for name, label in core.material_choices(description, chosen):
            self.material.addItem(label, name)
        self.material.setCurrentIndex(max(0, self.material.findData(chosen)))

    def _form_settings(self):
        """The settings with the server and token as the form has them now."""
        s = self.settings
        return core.Settings(server=self.server.text().strip(), token=self.token.text().strip(),
                             ca_file=s.ca_file, timeout=s.timeout)

    def _describe(self):
        """Reads the description of the form's daemon (kept for the session) in the background."""
        settings = self._form_settings()
        if self.describing is not None and self.describing[0] == settings.server:
            return
        known = core.cached_description(settings)
        if known is not None:
            self._described(known)
            return
        self.describing = (settings.server, gs.plugin.BackgroundCall(
            lambda progress, cancel: core.describe(settings)))
        self.description_timer.start()

    def _poll_description(self):
        if self.describing is None or not self.describing[1].done:
            return
        self.description_timer.stop()
        (server, call), self.describing = self.describing, None
        try:
            if server != self._form_settings().server:
                self._describe()  # the server was edited meanwhile
                return
            try:
                description = call.result()
            except Exception as e:  # the call's own error says more when the user presses OK
                if hasattr(self, "material"):
                    self.material.setToolTip("The daemon's materials were not read: %s"
                                             % (e.message if isinstance(e, gs.GridshellError) else e))
                return
            self._described(description)
        except RuntimeError:
            pass  # the panel was closed meanwhile: its widgets are gone

    def _described(self, description):
        """The daemon's materials into the combo box, its ranges and help into the spin boxes."""
        self.description = description
        if hasattr(self, "material"):
            chosen = self.material.currentData() or self.settings.material
            self._fill_materials(description, chosen)
            option = description.option("simulation", "material")
            self.material.setToolTip(option.get("help", "") if option else "")
        for name, box in self.fields.items():
            span = core.spin_range(description, "design", name)
            if span is not None:
                box.setRange(*span)
            option = description.option("design", name)
            if option is not None:
                box.setToolTip(option.get("help", ""))
        for name, box in self.layout_fields.items():
            span = core.spin_range(description, "layout", name)
            if span is not None:
                box.setRange(*span)
            option = description.option("layout", name)
            if option is not None:
                box.setToolTip(option.get("help", ""))

    def _read_form(self):
        s = self.settings
        s.server = self.server.text().strip()
        s.token = self.token.text().strip()
        if self.mode in LAYOUT_MODES:
            s.layout = self.layout_source.currentData()
            s.layout_file = self.layout_file.text().strip()
            s.max_patches = self.layout_fields["max_patches"].value()
            s.coverage_goal = round(self.layout_fields["coverage_goal"].value(), 6)
        if self.mode in ("design", "run", "build"):
            mode = self.alpha.currentText()
            s.alpha = mode if mode != "value" else "%gdeg" % self.alpha_value.value()
            for name, box in self.fields.items():
                setattr(s, name, box.value())
        if self.mode in ("simulate", "run", "build"):
            s.material = self.material.currentData() or ""
            s.notches = self.notches.currentText()
            s.auto_anchors = self.auto_anchors.isChecked()
        s.save()

    def getStandardButtons(self):
        return int(QtWidgets.QDialogButtonBox.Ok | QtWidgets.QDialogButtonBox.Cancel)

    def accept(self):
        if self.call is not None:
            return False
        self._read_form()
        try:
            if self.mode == "design":
                work, self.finish = core.prepare_design(self.doc, self.obj, self.settings, self.points)
            elif self.mode == "simulate":
                work, self.finish = core.prepare_simulate(self.doc, self.settings)
            elif self.mode == "layout":
                work, self.finish = core.prepare_layout(self.doc, self.obj, self.settings)
            elif self.mode == "build":
                work, self.finish = core.prepare_build(self.doc, self.obj, self.settings)
            else:
                work, self.finish = core.prepare_run(self.doc, self.obj, self.settings, self.points)
        except (core.InputError, gs.GridshellError) as e:
            self._error(e)
            return False
        self.call = gs.plugin.BackgroundCall(work)
        self.status.setText("starting")
        self.timer.start()
        return False  # the panel stays open until the answer is in

    def reject(self):
        if self.call is not None:
            self.call.cancel()
            self.status.setText("cancelling")
            return False
        FreeCADGui.Control.closeDialog()
        return True

    def poll(self):
        call = self.call
        if call is None:
            return
        text = gs.plugin.progress_text(call.progress, time.monotonic() - call.started)
        if call.progress is not None:
            self.progress.setValue(int(1000 * min(max(call.progress.fraction, 0.0), 1.0)))
        if call.cancelled:
            text = "cancelling"
        self.status.setText(text)
        FreeCADGui.getMainWindow().statusBar().showMessage("gridshell %s: %s" % (self.mode, text))
        if not call.done:
            return
        self.timer.stop()
        self.call = None
        FreeCADGui.getMainWindow().statusBar().clearMessage()
        try:
            result = call.result()
            made = self.finish(result, call.finished - call.started)
        except Exception as e:  # every failure is shown, never a traceback
            self._error(e)
            return
        FreeCAD.Console.PrintMessage("gridshell: %s done in %.1f s\n" % (self.mode, call.finished - call.started))
        colour_by_deviation(self.doc)
        if self.mode in LAYOUT_MODES:
            colour_patches(self.doc)
        if self.mode == "build" and not made.Converged:
            warn_not_converged(made)
        FreeCADGui.Control.closeDialog()
        FreeCADGui.SendMsgToActiveView("ViewFit")

    def _error(self, error):
        message = core.error_message(error, self.settings, self.obj.Label if self.obj is not None else "")
        self.status.setText(message)
        self.status.setStyleSheet("color: #b00020")
        FreeCAD.Console.PrintError(message + "\n")


def _lamella_objects(doc):
    """The deployed lamellas of the single patch and of every built patch of a layout."""
    group = doc.getObject(core.DEPLOYED.replace(" ", "_"))
    objects = list(group.Group) if group is not None else []
    parent = doc.getObject(core.PATCHES.replace(" ", "_"))
    for sub in parent.Group if parent is not None else []:
        if sub.TypeId == "App::DocumentObjectGroup":
            objects += list(sub.Group)
    return objects


def colour_by_deviation(doc, bins=12):
    """Colours the deployed lamellas' facets by their deviation from the target: deviation.ply's
    map, blue at 0 to red at the largest (a layout's patches: the largest of all of them), in
    ``bins`` steps (mesh segments)."""
    for obj in _lamella_objects(doc):
        values = getattr(obj, "FacetDeviation", None)
        if not values or obj.ViewObject is None:
            continue
        top = getattr(obj, "DeviationScale", 0.0) or max(values) or 1.0
        segments = [[] for _ in range(bins)]
        for facet, value in enumerate(values):
            segments[min(bins - 1, int(bins * value / top))].append(facet)
        mesh = obj.Mesh.copy()
        colours = []
        for k, facets in enumerate(segments):
            if facets:
                mesh.addSegment(facets)
                colours.append(gs.plugin.deviation_colour((k + 0.5) / bins, 1.0))
        obj.Mesh = mesh
        obj.ViewObject.highlightSegments(colours)


def colour_patches(doc):
    """The layout's patches in their colours (the property ``Colour`` of each)."""
    group = doc.getObject(core.LAYOUT.replace(" ", "_"))
    for obj in group.Group if group is not None else []:
        if obj.ViewObject is not None and "Colour" in obj.PropertiesList:
            obj.ViewObject.ShapeColor = obj.Colour


_WARNINGS = []  # the open warning boxes (kept alive)


def warn_not_converged(parent):
    """A warning box (not modal) when the simulation of a layout's patches did not converge."""
    late = [g.Label for g in parent.Group if getattr(g, "Converged", True) is False]
    box = QtWidgets.QMessageBox(
        QtWidgets.QMessageBox.Warning, "gridshell: not converged",
        "The simulation of %s did not reach equilibrium: the deviations (RMS %s) are not those of "
        "the deployed shell." % (", ".join(late) or "the patches",
                                 "%.4g" % parent.RmsWithNotches if "RmsWithNotches" in parent.PropertiesList else "-"),
        QtWidgets.QMessageBox.Ok, FreeCADGui.getMainWindow())
    box.setModal(False)
    box.finished.connect(lambda _: _WARNINGS.remove(box) if box in _WARNINGS else None)
    _WARNINGS.append(box)
    box.show()


class _Command:
    mode = ""
    text = ""
    tip = ""

    def GetResources(self):
        return {"MenuText": self.text, "ToolTip": self.tip}

    def IsActive(self):
        return FreeCAD.ActiveDocument is not None and FreeCADGui.Control.activeDialog() is False

    def Activated(self):
        FreeCADGui.Control.showDialog(TaskPanel(self.mode))


class DesignCommand(_Command):
    mode, text = "design", "Design"
    tip = "Design the planar grid for the selected Mesh (4 picked points as corners; none: automatic)"


class SimulateCommand(_Command):
    mode, text = "simulate", "Simulate"
    tip = "Simulate the deployment of the design in the group 'gridshell'"


class RunCommand(_Command):
    mode, text = "run", "Design + Simulate"
    tip = "Design and simulate the selected Mesh in one call"


class LayoutCommand(_Command):
    mode, text = "layout", "Layout (several patches)"
    tip = ("Cover the selected Mesh with several four-sided patches joined at seams (automatic, from "
           "a layout file, or the last layout): one coloured Mesh per patch, the coverage")


class BuildLayoutCommand(_Command):
    mode, text = "build", "Build all patches"
    tip = ("Design and simulate every patch of the layout in one call: each patch's deployed "
           "lamellas in its own group, the whole's RMS, seam bolts and gaps")


def register():
    FreeCADGui.addCommand("Gridshell_Design", DesignCommand())
    FreeCADGui.addCommand("Gridshell_Simulate", SimulateCommand())
    FreeCADGui.addCommand("Gridshell_Run", RunCommand())
    FreeCADGui.addCommand("Gridshell_Layout", LayoutCommand())
    FreeCADGui.addCommand("Gridshell_BuildLayout", BuildLayoutCommand())
