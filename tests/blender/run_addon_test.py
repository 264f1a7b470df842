#!/usr/bin/env python3
"""CTest driver of the Blender add-on test (tests/blender/addon_test.py):
    run_addon_test.py --cli BUILD/src/app/fluidform [--blender blender] [--keep DIR]
Packages the add-on with scripts/package_blender_addon.py into a temporary folder, then runs the test in Debian's
Blender headless, with its user scripts and config in that folder (the add-on is installed from the zip there,
nothing in $HOME changes); then, where xvfb-run is installed, the modal path in Blender's UI on a virtual X server
(tests/blender/addon_ui_test.py; skipped with a line saying so otherwise). Exit 0: passed; 1: failed; 77: skipped (no Blender, or Blender's Python lacks numpy),
with a line saying why."""
import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
SKIP = 77


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--cli", required=True, help="the fluidform executable")
    ap.add_argument("--blender", default="blender")
    ap.add_argument("--keep", help="work in this folder and keep it (default: a temporary one, removed)")
    args = ap.parse_args()
    # Debian's blender, with /usr/bin first so that its bundled Python is not confused by another python3.
    env = dict(os.environ)
    env["PATH"] = "/usr/bin:" + env.get("PATH", "")
    blender = shutil.which(args.blender, path=env["PATH"])
    if blender is None:
        print("SKIP: Blender is not installed (apt-get install blender python3-numpy; scripts/test installs them): "
              "the add-on test did not run", flush=True)
        return SKIP
    bunny = os.path.join(ROOT, "examples", "bunny.obj")
    if not os.path.isfile(bunny):
        print("FAIL: examples/bunny.obj is missing (scripts/setup writes it)", flush=True)
        return 1
    work = args.keep or tempfile.mkdtemp(prefix="fluidform-addon-test-")
    os.makedirs(work, exist_ok=True)
    try:
        zip_path = os.path.join(work, "fluidform-blender.zip")
        subprocess.run([sys.executable, os.path.join(ROOT, "scripts", "package_blender_addon.py"), "-o", zip_path],
                       check=True, stdout=subprocess.DEVNULL)
        env["BLENDER_USER_SCRIPTS"] = os.path.join(work, "user_scripts")
        env["BLENDER_USER_CONFIG"] = os.path.join(work, "user_config")
        env.pop("FLUIDFORM_BIN", None)
        cmd = [blender, "-b", "--factory-startup", "-noaudio", "--python-exit-code", "1",
               "-P", os.path.join(ROOT, "tests", "blender", "addon_test.py"), "--",
               "--zip", zip_path, "--cli", os.path.abspath(args.cli), "--bunny", bunny, "--work", work]
        p = subprocess.run(cmd, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=900)
        print(p.stdout, flush=True)
        if p.returncode == SKIP:
            return SKIP
        line = next((l for l in p.stdout.splitlines() if l.startswith("FLUIDFORM_ADDON_TEST ")), None)
        if line is None:
            print(f"FAIL: the Blender test printed no result (exit code {p.returncode})", flush=True)
            return 1
        result = json.loads(line.split(" ", 1)[1])
        if p.returncode != 0 or result.get("failed"):
            print(f"FAIL: {len(result.get('failed', []))} check(s) failed, Blender exit code {p.returncode}", flush=True)
            return 1
        print("PASS: the add-on installed from its zip formed the bunny and the two-object scene, cancelled cleanly "
              "and failed cleanly", flush=True)
        # The modal path (timer, status bar, Esc) needs Blender's UI: under a virtual X server where there is one.
        xvfb = shutil.which("xvfb-run", path=env["PATH"])
        if xvfb is None:
            print("SKIP (UI part): xvfb-run is not installed (apt-get install xvfb): the modal Form and Esc did not "
                  "run", flush=True)
            return 0
        ui = [xvfb, "-a", "-s", "-screen 0 1280x900x24", blender, "--factory-startup", "-noaudio",
              "--enable-event-simulate", "-P", os.path.join(ROOT, "tests", "blender", "addon_ui_test.py"), "--",
              "--zip", zip_path, "--cli", os.path.abspath(args.cli), "--work", work]
        p = subprocess.run(ui, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=600)
        print(p.stdout, flush=True)
        line = next((l for l in p.stdout.splitlines() if l.startswith("FLUIDFORM_ADDON_UI_TEST ")), None)
        if line is None or p.returncode != 0 or json.loads(line.split(" ", 1)[1]).get("failed"):
            print(f"FAIL: the UI part failed (Blender exit code {p.returncode})", flush=True)
            return 1
        print("PASS (UI part): the modal Form kept the event loop running, imported, and Esc cancelled cleanly",
              flush=True)
        return 0
    finally:
        if not args.keep:
            shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    sys.exit(main())
