# Form and Cancel. In the UI, Form is modal: a timer polls the run (Blender stays responsive), the status bar and
# the panel show the progress, Esc or Cancel stops it. In background Blender (-b) there is no event loop, so Form
# runs the same task in a blocking loop (Ctrl+C cancels).
import sys
import time

import bpy

from . import task as form_task

POLL_SECONDS = 0.1


def _redraw(context):
    """Redraws the panel (the status bar redraws itself when its text changes)."""
    for win in context.window_manager.windows:
        for area in win.screen.areas:
            if area.type == "PROPERTIES":
                area.tag_redraw()


def _status(context, text):
    for win in context.window_manager.windows:
        ws = win.workspace
        if ws is not None:
            ws.status_text_set(text)


class FLUIDFORM_OT_form(bpy.types.Operator):
    """Flow fluid into the selected meshes: runs fluidform in the background and imports the forming"""
    bl_idname = "fluidform.form"
    bl_label = "Form"
    bl_options = {"REGISTER", "UNDO"}  # one undo step: the whole import

    _timer = None
    _task = None
    _shown = ""

    @classmethod
    def poll(cls, context):
        if form_task.current() is not None:
            cls.poll_message_set("a Form is running")
            return False
        if not form_task.targets.target_objects(context):
            cls.poll_message_set("select the mesh objects to form")
            return False
        return True

    def _start(self, context):
        try:
            self._task = form_task.start(context)
        except form_task.FormError as e:
            self.report({"ERROR"}, str(e))
            return False
        for w in self._task.warnings:
            self.report({"WARNING"}, w)
        return True

    def execute(self, context):
        if not bpy.app.background and context.window is not None:
            return self.invoke(context, None)
        if not self._start(context):
            return {"CANCELLED"}
        t = self._task
        shown = ""
        try:
            while not t.step(context):
                text = t.status_text()
                if text != shown:
                    print(text, flush=True)
                    shown = text
                time.sleep(POLL_SECONDS / 2)
        except KeyboardInterrupt:
            t.cancel()
        return self._end(context)

    def invoke(self, context, event):
        if not self._start(context):
            return {"CANCELLED"}
        wm = context.window_manager
        self._timer = wm.event_timer_add(POLL_SECONDS, window=context.window)
        wm.progress_begin(0, 100)
        wm.modal_handler_add(self)
        self._update(context)
        return {"RUNNING_MODAL"}

    def _update(self, context):
        # Only when the progress changed: redrawing costs CPU the simulation could use.
        text = self._task.status_text() + "  ·  Esc to cancel"
        if text == self._shown:
            return
        self._shown = text
        f, _ = self._task.progress()
        context.window_manager.fluidform_progress = 100.0 * f
        context.window_manager.progress_update(100.0 * f)
        _status(context, text)
        _redraw(context)

    def modal(self, context, event):
        t = self._task
        if event.type == "ESC" and event.value == "PRESS" and t.state == "RUNNING":
            t.cancel()
        elif event.type != "TIMER":
            if t.state == "RUNNING":
                return {"PASS_THROUGH"}
        if t.state == "RUNNING":
            if t.step(context) is False:
                self._update(context)
                return {"PASS_THROUGH"}
        elif t.state == "IMPORTING":
            return {"PASS_THROUGH"}
        self._finish_ui(context)
        return self._end(context)

    def _finish_ui(self, context):
        wm = context.window_manager
        if self._timer is not None:
            wm.event_timer_remove(self._timer)
            self._timer = None
        wm.progress_end()
        wm.fluidform_progress = 0.0
        _status(context, None)
        _redraw(context)

    def cancel(self, context):
        # Blender ends the operator (a file is loaded, the window closes): stop the run with it.
        if self._task is not None:
            self._task.cancel()
        self._finish_ui(context)

    def _end(self, context):
        t = self._task
        if t.state == "DONE":
            self.report({"INFO"}, t.message)
            return {"FINISHED"}
        if t.state == "CANCELLED":
            self.report({"WARNING"}, "Fluid Form cancelled")
            return {"CANCELLED"}
        self.report({"ERROR"}, f"Fluid Form: {t.message}")
        if bpy.app.background:
            print(f"Fluid Form: {t.message}", file=sys.stderr, flush=True)
        return {"CANCELLED"}


class FLUIDFORM_OT_cancel(bpy.types.Operator):
    """Stop the running Form: ends fluidform and removes its output; nothing is imported"""
    bl_idname = "fluidform.cancel"
    bl_label = "Cancel"
    bl_options = {"REGISTER"}

    @classmethod
    def poll(cls, context):
        return form_task.current() is not None

    def execute(self, context):
        t = form_task.current()
        if t is not None:
            t.cancel()
        return {"FINISHED"}


classes = (FLUIDFORM_OT_form, FLUIDFORM_OT_cancel)


def register():
    for c in classes:
        bpy.utils.register_class(c)


def unregister():
    for c in reversed(classes):
        bpy.utils.unregister_class(c)
