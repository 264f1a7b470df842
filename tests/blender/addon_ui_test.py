# The add-on's modal path in Blender's real UI (run under Xvfb by tests/blender/run_addon_test.py when xvfb-run is
# there): Form invoked from the panel's context keeps the event loop running (a timer keeps ticking), shows its
# progress in the status bar and the panel, imports the result; a second Form is ended with Esc and leaves nothing.
#   xvfb-run blender --factory-startup -noaudio --enable-event-simulate -P tests/blender/addon_ui_test.py -- \
#       --zip ADDON.zip --cli FLUIDFORM --work TMPDIR
# Prints "FLUIDFORM_ADDON_UI_TEST {...}" and quits with 0 when every check held, else 1.
import json
import os
import sys
import time

import bpy

args = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
opt = {args[i].lstrip("-"): args[i + 1] for i in range(0, len(args) - 1, 2)}
bpy.context.preferences.view.show_splash = False
bpy.ops.preferences.addon_install(filepath=opt["zip"], overwrite=True)
bpy.ops.preferences.addon_enable(module="fluidform")
prefs = bpy.context.preferences.addons["fluidform"].preferences
prefs.cli_path = opt["cli"]
prefs.output_dir = os.path.join(opt["work"], "ui_runs")
for o in list(bpy.data.objects):
    bpy.data.objects.remove(o)
bpy.ops.mesh.primitive_ico_sphere_add(radius=0.3, subdivisions=3, location=(0, 0, 0.5))
settings = bpy.context.scene.fluidform
settings.particle_count, settings.duration, settings.start_frame = 1500, 0.5, 1
failures, report = [], {"ticks": 0}
state = {"phase": "start", "t0": time.monotonic()}


def check(cond, what):
    if not cond:
        failures.append(what)
        print(f"FAIL: {what}", flush=True)


def ids():
    return {k: len(getattr(bpy.data, k)) for k in ("objects", "meshes", "materials", "collections", "actions",
                                                    "node_groups")}


def invoke_form(win):
    area = next(a for a in win.screen.areas if a.type == "PROPERTIES")
    area.spaces[0].context = "OBJECT"
    region = next(r for r in area.regions if r.type == "WINDOW")
    with bpy.context.temp_override(window=win, area=area, region=region):
        return bpy.ops.fluidform.form("INVOKE_DEFAULT")


def finish():
    report["failed"] = failures
    report["seconds"] = time.monotonic() - state["t0"]
    print("FLUIDFORM_ADDON_UI_TEST " + json.dumps(report, default=str), flush=True)
    os._exit(1 if failures else 0)  # quit_blender's exit code is always 0


def tick():
    import fluidform.job as job
    import fluidform.task as ft
    report["ticks"] += 1
    win = bpy.context.window_manager.windows[0]
    phase = state["phase"]
    t = ft.last()
    if time.monotonic() - state["t0"] > 300:
        check(False, f"timed out in phase {phase}")
        finish()
    if phase == "start":  # two seconds idle first: the timer's rate without a Form, for comparison
        state.update(phase="idle", idle_t=time.monotonic(), idle_ticks=report["ticks"])
    elif phase == "idle" and time.monotonic() - state["idle_t"] >= 2.0:
        report["idle_ticks_per_s"] = (report["ticks"] - state["idle_ticks"]) / (time.monotonic() - state["idle_t"])
        state["form_t"] = time.monotonic()
        r = invoke_form(win)
        check(r == {"RUNNING_MODAL"}, f"Form invoked: {r}")
        state.update(phase="form", ticks=report["ticks"])
    elif phase == "form":
        if t.state == "RUNNING":
            state["progress_seen"] = max(state.get("progress_seen", 0.0), bpy.context.window_manager.fluidform_progress)
        elif t.state != "IMPORTING":
            report["form"] = t.message
            report["ticks_while_running"] = report["ticks"] - state["ticks"]
            report["running_ticks_per_s"] = report["ticks_while_running"] / (time.monotonic() - state["form_t"])
            check(t.state == "DONE", f"Form ended {t.state}: {t.message}")
            # A Form that blocked the event loop would let no timer run until it had ended.
            check(report["ticks_while_running"] >= 2, "the event loop stalled while the Form ran")
            check(state.get("progress_seen", 0.0) > 0.0, "no progress was shown")
            check(bpy.context.window_manager.fluidform_progress == 0.0, "the progress was not reset")
            colls = [c for c in bpy.data.collections if c.name.startswith("Fluid Form:")]
            check(len(colls) == 1 and len(colls[0].children) == 3, f"imported collections {[c.name for c in colls]}")
            state.update(phase="cancel", before=ids())
            check(invoke_form(win) == {"RUNNING_MODAL"}, "second Form not invoked")
    elif phase == "cancel":
        if t.state == "RUNNING" and t.run.progress.stage in ("simulating", "forming") and "esc" not in state:
            state.update(esc=time.monotonic(), pgid=t.run.pgid, out=t.out_dir)
            win.event_simulate(type="ESC", value="PRESS")
            win.event_simulate(type="ESC", value="RELEASE")
        elif t.state != "RUNNING":
            report["esc"] = t.message
            check("esc" in state and t.state == "CANCELLED", f"after Esc: {t.state} {t.message}")
            check("pgid" in state and not job.process_group_alive(state["pgid"]), "a process of the run is left")
            check("out" in state and not os.path.exists(state["out"]), "the run's folder was left")
            check(ids() == state["before"], "the cancelled Form added data")
            check(ft.current() is None, "a Form is still current")
            finish()
    return 0.2


bpy.app.timers.register(tick, first_interval=1.0)
