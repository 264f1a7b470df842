#!/usr/bin/env python3
"""Packages the Blender add-on (blender/fluidform) as an installable zip:
    scripts/package_blender_addon.py [-o OUT.zip]      (default: build/fluidform-blender-VERSION.zip)
Blender: Edit → Preferences → Add-ons → Install… → the zip, then enable "Physics: Fluid Form" (or headless:
bpy.ops.preferences.addon_install(filepath=ZIP); bpy.ops.preferences.addon_enable(module="fluidform")).
The zip holds the package folder fluidform/ (sources only, sorted, fixed timestamps: the same sources give the
same bytes). Prints the zip's path."""
import argparse
import ast
import os
import sys
import zipfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PACKAGE = os.path.join(ROOT, "blender", "fluidform")


def version():
    with open(os.path.join(PACKAGE, "__init__.py"), encoding="utf-8") as f:
        tree = ast.parse(f.read())
    for node in tree.body:
        if isinstance(node, ast.Assign) and any(getattr(t, "id", None) == "bl_info" for t in node.targets):
            return ".".join(str(v) for v in ast.literal_eval(node.value)["version"])
    raise SystemExit("package_blender_addon: no bl_info in blender/fluidform/__init__.py")


def sources():
    for folder, dirs, files in os.walk(PACKAGE):
        dirs[:] = sorted(d for d in dirs if d != "__pycache__" and not d.startswith("."))
        for name in sorted(files):
            if name.endswith((".py", ".md", ".txt", ".json")):
                yield os.path.join(folder, name)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("-o", "--out", help="the zip to write")
    args = ap.parse_args()
    out = args.out or os.path.join(ROOT, "build", f"fluidform-blender-{version()}.zip")
    os.makedirs(os.path.dirname(os.path.abspath(out)), exist_ok=True)
    tmp = out + ".tmp"
    with zipfile.ZipFile(tmp, "w", compression=zipfile.ZIP_DEFLATED) as z:
        for path in sources():
            arc = os.path.join("fluidform", os.path.relpath(path, PACKAGE)).replace(os.sep, "/")
            info = zipfile.ZipInfo(arc, date_time=(1980, 1, 1, 0, 0, 0))
            info.compress_type = zipfile.ZIP_DEFLATED
            info.external_attr = 0o644 << 16
            with open(path, "rb") as f:
                z.writestr(info, f.read())
    os.replace(tmp, out)
    print(out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
