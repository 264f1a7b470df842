# One Form: export the targets, run the CLI in the background, import the result. The operators drive it (a modal
# timer in the UI, a blocking loop in background Blender); scripts can too:
#     task = fluidform.task.start(bpy.context)          # raises FormError when it cannot start
#     while not task.step(bpy.context): time.sleep(0.1)  # or task.cancel()
import datetime
import os
import re
import shutil
import tempfile
import time
import traceback

import bpy

from . import job, result, targets

_current = None  # the running Form (one at a time)


class FormError(Exception):
    """A Form that cannot start or did not finish, in one line."""


def current():
    """The running Form, or None."""
    return _current if _current is not None and _current.state in ("RUNNING", "IMPORTING") else None


def cli_path(context):
    """The fluidform executable: the add-on preference, then $FLUIDFORM_BIN, then `fluidform` on PATH."""
    prefs = addon_prefs(context)
    for p in (prefs.cli_path if prefs else "", os.environ.get("FLUIDFORM_BIN", "")):
        if p:
            p = bpy.path.abspath(p)
            if os.path.isfile(p) and os.access(p, os.X_OK):
                return p
            raise FormError(f"the fluidform executable {p} does not exist or cannot run (add-on preferences)")
    found = shutil.which("fluidform")
    if not found:
        raise FormError("fluidform was not found: set its path in the add-on preferences (or $FLUIDFORM_BIN)")
    return found


def addon_prefs(context):
    addon = context.preferences.addons.get(__package__)
    return addon.preferences if addon is not None else None


def output_root(context):
    """Where runs go: the preference, else `fluidform/` next to the saved .blend, else the system temp folder."""
    prefs = addon_prefs(context)
    if prefs is not None and prefs.output_dir:
        return bpy.path.abspath(prefs.output_dir)
    if bpy.data.filepath:
        return os.path.join(os.path.dirname(bpy.data.filepath), "fluidform")
    return os.path.join(tempfile.gettempdir(), "fluidform")


def _safe(name):
    return re.sub(r"[^A-Za-z0-9._-]+", "_", name).strip("_") or "form"


def scene_fps(scene):
    return scene.render.fps / scene.render.fps_base


class FormTask:
    """A Form in progress. state: RUNNING → IMPORTING → DONE, or FAILED / CANCELLED."""

    def __init__(self, context, objects, settings):
        scene = context.scene
        self.scene_name = scene.name
        self.name = objects[0].name if len(objects) == 1 else f"{objects[0].name} +{len(objects) - 1}"
        self.target_names = [o.name for o in objects]
        self.start_frame = settings.start_frame
        self.fps = scene_fps(scene)
        self.state = "RUNNING"
        self.message = ""
        self.warnings = []
        self.collection = None
        self.started = time.monotonic()
        self.finished = None
        self.frames = max(1, round(settings.duration * self.fps)) if settings.duration > 0 else None
        root = output_root(context)
        os.makedirs(root, exist_ok=True)
        stamp = datetime.datetime.now().strftime("%Y%m%d-%H%M%S")
        self.out_dir = tempfile.mkdtemp(prefix=f"{_safe(self.name)}-{stamp}-", dir=root)
        self.input_dir = os.path.join(self.out_dir, "input")
        os.makedirs(self.input_dir)
        try:
            end = self.start_frame + self.frames if self.frames else None
            tlist, self.warnings, last_key = targets.export_targets(context, objects, self.input_dir,
                                                                    self.start_frame, end)
            if self.frames is None and last_key is not None:
                # "Until formed" does not know about keyframes: run to the last one and three seconds past it.
                self.frames = round((last_key + 3.0) * self.fps)
            self.scene_path = os.path.join(self.input_dir, "scene.json")
            targets.write_scene(self.scene_path, tlist, settings.particle_count, self.fps)
            argv = [cli_path(context), "run", self.scene_path, "--out", self.out_dir,
                    "--controller", settings.controller, "--device", settings.device]
            if self.frames:
                argv += ["--frames", str(self.frames)]
            self.argv = argv
            self.run = job.Run(argv, os.path.join(self.input_dir, "fluidform.log"))
            self.timings = {"export": time.monotonic() - self.started}  # s: export, run (the CLI), import
            self.run.start()
        except BaseException:
            shutil.rmtree(self.out_dir, ignore_errors=True)
            raise

    # Progress ------------------------------------------------------------------------------------------------
    def progress(self):
        """(fraction 0–1, one-line text)."""
        if self.state == "IMPORTING":
            return 0.98, "importing"
        if self.state == "DONE":
            return 1.0, self.message
        if self.state in ("FAILED", "CANCELLED"):
            return 0.0, self.message
        return self.run.snapshot()

    def status_text(self):
        f, text = self.progress()
        return f"Fluid Form {self.name}: {text} ({100 * f:.0f} %)"

    # Driving ---------------------------------------------------------------------------------------------------
    def step(self, context):
        """Advances the Form; True once it has ended (DONE, FAILED or CANCELLED)."""
        if self.state != "RUNNING":
            return True
        rc = self.run.poll()
        if rc is None:
            return False
        if rc != 0:
            self._fail(self.run.failure())
            return True
        self.state = "IMPORTING"
        imported = time.monotonic()
        self.timings["run"] = imported - self.run.started
        try:
            self.collection = result.import_run(context, self.out_dir, self.name, self.start_frame, self.fps)
        except Exception as e:  # the import removed what it had made
            first = (str(e).strip().splitlines() or [""])[0]
            self._fail(f"import failed: {type(e).__name__}: {first}")
            return True
        shutil.rmtree(os.path.join(self.out_dir, "checkpoint"), ignore_errors=True)
        prefs = addon_prefs(context)
        if prefs is None or not prefs.keep_particle_frames:
            # Every frame is in particles.pc2, which the Mesh Cache modifier reads.
            shutil.rmtree(os.path.join(self.out_dir, "particles"), ignore_errors=True)
        self.finished = time.monotonic()
        self.timings["import"] = self.finished - imported
        self.state = "DONE"
        frames = self.collection.get("fluidform_frames", 0)
        self.message = (f"Formed: frames {self.start_frame}–{self.start_frame + frames - 1} "
                        f"in {self.finished - self.started:.0f} s")
        return True

    def _fail(self, message):
        self.state = "FAILED"
        self.message = message
        self.finished = time.monotonic()
        self.run.cancel(grace=1.0)  # nothing of the group stays behind
        shutil.rmtree(self.out_dir, ignore_errors=True)

    def cancel(self):
        """Kills the CLI's process group and removes the run's folder; nothing was imported yet."""
        if self.state not in ("RUNNING",):
            return
        self.run.cancel()
        shutil.rmtree(self.out_dir, ignore_errors=True)
        self.state = "CANCELLED"
        self.message = "cancelled"
        self.finished = time.monotonic()


def start(context, objects=None, settings=None):
    """Starts a Form of `objects` (default: the selected mesh objects) with `settings` (default: the scene's
    Fluid Form settings)."""
    global _current
    if current() is not None:
        raise FormError("a Form is already running")
    objects = objects if objects is not None else targets.target_objects(context)
    if not objects:
        raise FormError("select the mesh objects to form")
    settings = settings if settings is not None else context.scene.fluidform
    try:
        _current = FormTask(context, objects, settings)
    except targets.TargetError as e:
        raise FormError(str(e)) from None
    except OSError as e:
        raise FormError(f"could not start fluidform: {e}") from None
    except FormError:
        raise
    except Exception as e:  # a bug: the traceback goes to the console, the report says what it was
        traceback.print_exc()
        raise FormError(f"could not start: {type(e).__name__}: {e}") from None
    return _current


def last():
    """The most recent Form (running or ended), or None."""
    return _current


def cancel_all():
    """Cancels the running Form (on file load and exit)."""
    t = current()
    if t is not None and t.state == "RUNNING":
        t.cancel()
