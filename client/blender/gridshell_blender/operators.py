# SPDX-License-Identifier: GPL-3.0-or-later
"""Operators ``gridshell.design``, ``gridshell.simulate`` and ``gridshell.run``,
``gridshell.layout`` and ``gridshell.build_layout`` (several patches joined at seams), and
``gridshell.refresh_options`` (reads the daemon's description: its materials and option ranges).

Started from the UI (a button: INVOKE) they call the daemon on a background thread and keep
Blender responsive: a timer shows the progress in the status bar, Esc cancels (the daemon stops
the work), and the results are built on the main thread when the answer is in. Run from a script
(EXEC) or in background mode (``blender -b``) they block until the results are in the scene,
printing progress in background mode. Every failure is a report (in a script: the RuntimeError
bpy.ops raises for an operator's error report), never a traceback.
"""

import time

import bpy

from . import described, layouts, mesh_input, results
from .properties import FIELD_LABELS
from .remote import gs

# The state of the call running in the UI, for the panel (one call at a time).
STATE = {"call": None, "label": "", "text": ""}


FIELD_NAMES = dict(FIELD_LABELS, design="the design (text '%s')" % results.DESIGN_TEXT)
LAYOUT_FIELD_NAMES = dict(FIELD_LABELS)  # a layout call's "design" is its design options


def _redraw_sidebars(context):
    """Redraws the panel's regions only (not the 3D views: cheaper on every progress tick)."""
    for area in context.screen.areas if context.screen else []:
        if area.type == "VIEW_3D":
            for region in area.regions:
                if region.type == "UI":
                    region.tag_redraw()


class _Call:
    """One operator's work: ``work(progress, cancel)`` on any thread, ``finish(scene, result,
    seconds)`` on the main thread."""

    def __init__(self, label, server, source, work, finish):
        self.label, self.server, self.source = label, server, source
        self.work, self.finish = work, finish


class _GridshellOperator:
    bl_options = {"REGISTER"}
    label = ""

    def prepare(self, context):
        raise NotImplementedError

    field_names = FIELD_NAMES

    def _report_error(self, error, call):
        lines = gs.plugin.error_text(error, call.server if call else "", self.field_names, call.source if call else "")
        level = {"WARNING"} if isinstance(error, gs.Cancelled) else {"ERROR"}
        self.report(level, "\n".join(lines))
        return {"CANCELLED"}

    def _prepare(self, context):
        if STATE["call"] is not None:
            self.report({"ERROR"}, "gridshell: %s is still running (Esc cancels it)" % STATE["label"])
            return None
        try:
            return self.prepare(context)
        except mesh_input.InputError as e:
            self.report({"ERROR"}, "gridshell: %s" % e)
        except gs.GridshellError as e:  # a bad server address, token file or CA file
            self._report_error(e, None)
        return None

    def _finish(self, context, call, result, seconds):
        try:
            lines = call.finish(context.scene, result, seconds)
        except gs.GridshellError as e:
            return self._report_error(e, call)
        described.reached(context.scene.gridshell.server)
        # What the results say (a layout's coverage, a patch that failed, a run that did not
        # converge), then the time.
        for level, text in lines if isinstance(lines, list) else []:
            self.report({level}, text)
        self.report({"INFO"}, "gridshell: %s done in %.1f s" % (call.label, seconds))
        return {"FINISHED"}

    # Blocking: scripts and background mode.
    def execute(self, context):
        call = self._prepare(context)
        if call is None:
            return {"CANCELLED"}
        printer = gs.plugin.ProgressPrinter(print) if bpy.app.background else None
        started = time.monotonic()
        try:
            result = call.work(progress=printer, cancel=None)
        except Exception as e:  # every failure becomes a report
            return self._report_error(e, call)
        return self._finish(context, call, result, time.monotonic() - started)

    # Non-blocking: from the UI.
    def invoke(self, context, event):
        if bpy.app.background or context.window is None:
            return self.execute(context)
        call = self._prepare(context)
        if call is None:
            return {"CANCELLED"}
        self._call = call
        self._background = gs.plugin.BackgroundCall(call.work)
        STATE.update(call=self._background, label=call.label, text="starting")
        self._timer = context.window_manager.event_timer_add(0.1, window=context.window)
        context.window_manager.modal_handler_add(self)
        self._status(context)
        return {"RUNNING_MODAL"}

    def _status(self, context):
        background = self._background
        elapsed = time.monotonic() - background.started
        text = gs.plugin.progress_text(background.progress, elapsed)
        if background.cancelled:
            text = "cancelling"
        STATE["text"] = text
        context.workspace.status_text_set("gridshell %s: %s  (Esc cancels)" % (self._call.label, text))
        _redraw_sidebars(context)

    def _end(self, context):
        context.window_manager.event_timer_remove(self._timer)
        context.workspace.status_text_set(None)
        STATE.update(call=None, label="", text="")
        _redraw_sidebars(context)

    def modal(self, context, event):
        background = self._background
        if event.type == "ESC" and event.value == "PRESS":
            background.cancel()
            self._status(context)
            return {"RUNNING_MODAL"}
        if event.type != "TIMER":
            return {"PASS_THROUGH"}
        if not background.done:
            self._status(context)
            return {"PASS_THROUGH"}
        self._end(context)
        try:
            result = background.result()
        except Exception as e:
            return self._report_error(e, self._call)
        return self._finish(context, self._call, result, background.finished - background.started)

    def cancel(self, context):  # Blender ends the operator (file closed, window gone)
        self._background.cancel()
        self._end(context)


def _inputs(context):
    settings = context.scene.gridshell
    mesh, corners, what = mesh_input.target(context.active_object, context.evaluated_depsgraph_get())
    return settings, mesh, corners, what


class GRIDSHELL_OT_design(_GridshellOperator, bpy.types.Operator):
    """Design the planar grid for the active mesh object (4 selected vertices as corners, in
    selection order; none: automatic)"""

    bl_idname = "gridshell.design"
    bl_label = "Design"

    def prepare(self, context):
        settings, mesh, corners, what = _inputs(context)
        client = settings.client()
        options = settings.design_options()

        def work(progress, cancel):
            return client.design(mesh, corners, options, files=True, progress=progress, cancel=cancel)

        def finish(scene, result, seconds):
            results.show_design(scene, result, mesh["name"], client.server, seconds)

        return _Call("design", client.server, mesh["name"], work, finish)


class GRIDSHELL_OT_simulate(_GridshellOperator, bpy.types.Operator):
    """Simulate the deployment of the last design (the text 'gridshell design.json')"""

    bl_idname = "gridshell.simulate"
    bl_label = "Simulate"

    def prepare(self, context):
        settings = context.scene.gridshell
        design = results.design_json(context)
        if not design:
            raise mesh_input.InputError("no design yet: run Design first (text '%s')" % results.DESIGN_TEXT)
        client = settings.client()
        options = settings.simulation_options(context.scene)

        def work(progress, cancel):
            return client.simulate(
                design, options, design_name=results.DESIGN_TEXT, progress=progress, cancel=cancel
            )

        def finish(scene, result, seconds):
            results.show_deployment(scene, result, seconds)

        return _Call("simulation", client.server, "", work, finish)


class GRIDSHELL_OT_run(_GridshellOperator, bpy.types.Operator):
    """Design and simulate the active mesh object in one call"""

    bl_idname = "gridshell.run"
    bl_label = "Design + Simulate"

    def prepare(self, context):
        settings, mesh, corners, what = _inputs(context)
        client = settings.client()
        design_options = settings.design_options()
        simulation = settings.simulation_options(context.scene)

        def work(progress, cancel):
            return client.run(
                mesh, corners, design_options, simulation, files=True, progress=progress, cancel=cancel
            )

        def finish(scene, result, seconds):
            results.show_design(scene, result["design"], mesh["name"], client.server, seconds)
            results.show_deployment(scene, result["simulation"], seconds)

        return _Call("design + simulation", client.server, mesh["name"], work, finish)


def _layout_inputs(context, settings, mesh_count):
    """(layout, automatic, how) of the layout settings: a layout dict or None, the automatic
    options or None, and words for the report."""
    source = settings.layout_source
    if source == "AUTO":
        return None, settings.automatic_options(), "automatic"
    if source == "FILE":
        return layouts.read_layout_file(settings.layout_file), None, "file %s" % settings.layout_file
    if source == "LAST":
        return layouts.last_layout(), None, "last layout (text '%s')" % layouts.LAYOUT_TEXT
    layout, ignored = mesh_input.vertex_group_layout(context.active_object, mesh_count)
    how = "vertex groups %s" % ", ".join(p["name"] for p in layout["patches"])
    if ignored:
        how += " (left out: %s)" % ", ".join(ignored)
    return layout, None, how


class GRIDSHELL_OT_layout(_GridshellOperator, bpy.types.Operator):
    """Cover the active mesh object with several four-sided patches joined at seams (automatic,
    from a layout file, from vertex groups of 4 vertices, or the last layout): the patches, the
    coverage and what is not covered"""

    bl_idname = "gridshell.layout"
    bl_label = "Layout (several patches)"
    field_names = LAYOUT_FIELD_NAMES

    def prepare(self, context):
        settings = context.scene.gridshell
        mesh, what, count = mesh_input.layout_target(context.active_object, context.evaluated_depsgraph_get())
        layout, automatic, how = _layout_inputs(context, settings, count)
        client = settings.client()

        def work(progress, cancel):
            return client.layout(mesh, layout=layout, automatic=automatic, progress=progress, cancel=cancel)

        def finish(scene, result, seconds):
            return layouts.show_layout(scene, result, mesh["name"], client.server, seconds, how)

        return _Call("layout", client.server, mesh["name"], work, finish)


class GRIDSHELL_OT_build_layout(_GridshellOperator, bpy.types.Operator):
    """Design and simulate every patch of the layout (as Layout chooses it) in one call: each
    patch's deployed lamellas in its own collection, the whole's RMS, seam bolts and gaps"""

    bl_idname = "gridshell.build_layout"
    bl_label = "Build all patches"
    field_names = LAYOUT_FIELD_NAMES

    def prepare(self, context):
        settings = context.scene.gridshell
        mesh, what, count = mesh_input.layout_target(context.active_object, context.evaluated_depsgraph_get())
        layout, automatic, how = _layout_inputs(context, settings, count)
        client = settings.client()
        design_options = settings.design_options()
        simulation = settings.simulation_options(context.scene)

        def work(progress, cancel):
            return client.run_layout(mesh, layout=layout, automatic=automatic, design_options=design_options,
                                     simulation=simulation, progress=progress, cancel=cancel)

        def finish(scene, result, seconds):
            return layouts.show_build(scene, result, mesh["name"], client.server, seconds, how)

        return _Call("build all patches", client.server, mesh["name"], work, finish)


class GRIDSHELL_OT_cancel(bpy.types.Operator):
    """Cancel the running gridshell call"""

    bl_idname = "gridshell.cancel"
    bl_label = "Cancel"

    @classmethod
    def poll(cls, context):
        return STATE["call"] is not None

    def execute(self, context):
        STATE["call"].cancel()
        return {"FINISHED"}


class GRIDSHELL_OT_refresh_options(bpy.types.Operator):
    """Read the daemon's materials and option ranges (its description) again"""

    bl_idname = "gridshell.refresh_options"
    bl_label = "Refresh materials"
    bl_options = {"REGISTER"}

    def execute(self, context):
        settings = context.scene.gridshell
        try:
            description = described.fetch(settings)
        except gs.GridshellError as e:
            self.report({"ERROR"}, "\n".join(gs.plugin.error_text(e, settings.server, FIELD_NAMES)))
            return {"CANCELLED"}
        if context.window_manager.windows:
            described.redraw()
        names = description.material_names()
        self.report({"INFO"}, "gridshell: %d materials from %s: %s" % (len(names), settings.server, ", ".join(names)))
        return {"FINISHED"}


CLASSES = (
    GRIDSHELL_OT_design,
    GRIDSHELL_OT_simulate,
    GRIDSHELL_OT_run,
    GRIDSHELL_OT_layout,
    GRIDSHELL_OT_build_layout,
    GRIDSHELL_OT_cancel,
    GRIDSHELL_OT_refresh_options,
)
register, unregister = bpy.utils.register_classes_factory(CLASSES)
