# The "Fluid Form" panel (Properties → Object, on mesh objects) and the progress in the status bar.
import bpy

from . import task as form_task
from .targets import RESULT_TAG, target_objects


def _duration_text(context, settings):
    fps = form_task.scene_fps(context.scene)
    if settings.duration > 0:
        return f"{round(settings.duration * fps)} frames at {fps:g} fps"
    return "until formed"


class FLUIDFORM_PT_panel(bpy.types.Panel):
    bl_label = "Fluid Form"
    bl_idname = "FLUIDFORM_PT_panel"
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    bl_context = "object"

    @classmethod
    def poll(cls, context):
        return context.object is not None and context.object.type == "MESH"

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        layout.use_property_decorate = False
        settings = context.scene.fluidform
        obj = context.object
        if RESULT_TAG in obj:
            layout.label(text=f"Imported by Fluid Form ({obj[RESULT_TAG]})", icon="INFO")
        objs = target_objects(context)
        box = layout.box()
        if objs:
            names = ", ".join(o.name for o in objs[:4]) + (f" +{len(objs) - 4}" if len(objs) > 4 else "")
            box.label(text=f"{len(objs)} target{'s' if len(objs) > 1 else ''}: {names}", icon="MESH_DATA")
        else:
            box.label(text="Select the mesh objects to form", icon="ERROR")
        running = form_task.current()
        col = layout.column()
        col.enabled = running is None
        col.prop(settings, "particle_count")
        col.prop(settings, "controller")
        col.prop(settings, "device")
        col.prop(settings, "duration")
        row = col.row()
        row.alignment = "RIGHT"
        row.label(text=_duration_text(context, settings))
        col.prop(settings, "start_frame")
        if running is None:
            layout.operator("fluidform.form", icon="MOD_FLUIDSIM")
            t = form_task.last()
            if t is not None and t.message:
                icon = {"DONE": "CHECKMARK", "FAILED": "ERROR", "CANCELLED": "CANCEL"}.get(t.state, "INFO")
                layout.label(text=t.message, icon=icon)
        else:
            _f, text = running.progress()
            col = layout.column()
            col.use_property_split = False
            col.label(text=text, icon="TIME")
            row = col.row(align=True)
            sub = row.row()
            sub.enabled = False
            sub.prop(context.window_manager, "fluidform_progress", text="", slider=True)
            row.operator("fluidform.cancel", text="Cancel", icon="CANCEL")


def draw_status(self, context):
    """In the status bar, beside Blender's own job progress: the running Form's progress and a Cancel button."""
    if form_task.current() is None:
        return
    row = self.layout.row(align=True)
    sub = row.row()
    sub.enabled = False
    sub.ui_units_x = 8
    sub.prop(context.window_manager, "fluidform_progress", text="Fluid Form", slider=True)
    row.operator("fluidform.cancel", text="", icon="CANCEL")


classes = (FLUIDFORM_PT_panel,)


def register():
    for c in classes:
        bpy.utils.register_class(c)
    bpy.types.STATUSBAR_HT_header.prepend(draw_status)


def unregister():
    bpy.types.STATUSBAR_HT_header.remove(draw_status)
    for c in reversed(classes):
        bpy.utils.unregister_class(c)
