#!/usr/bin/env python3
"""CTest character_asset_test: the demo character's recipe (scripts/make_character.py) still makes a good asset.

  character_asset_test.py [--keep DIR]

Runs the generator into a temporary folder with --check (its own read-back checks: closed outward parts, weights,
inverse bind matrices, looping clips, skinning without tearing), checks its summary (size, triangles, joints, a
1.0-1.2 s "walk"), that a second run writes the same bytes, and that the Khronos glTF validator (npm gltf-validator,
through node) reports 0 errors. Then it shows that the checks can fail: a flipped part, weights that no longer sum to
1, a broken loop and an index out of range must each be caught (the last by the validator).
Exit 0: passed; 1: failed, with one line per failure. Needs numpy (re-runs itself under Debian's /usr/bin/python3
when this interpreter lacks it), node and node_modules/gltf-validator (scripts/setup installs them)."""
import argparse
import json
import os
import shutil
import struct
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
DEBIAN_PYTHON = "/usr/bin/python3"

try:
    import numpy as np
except ImportError:
    if os.path.exists(DEBIAN_PYTHON) and os.path.realpath(sys.executable) != os.path.realpath(DEBIAN_PYTHON):
        os.execv(DEBIAN_PYTHON, [DEBIAN_PYTHON, os.path.abspath(__file__)] + sys.argv[1:])
    print("FAIL: numpy is missing (scripts/setup installs python3-numpy)", flush=True)
    sys.exit(1)

sys.path.insert(0, os.path.join(ROOT, "scripts"))
import make_character  # noqa: E402

VALIDATE = r"""
const fs = require('fs');
const validator = require(process.argv[1]);
(async () => {
  const out = {};
  for (const f of process.argv.slice(2)) {
    const r = await validator.validateBytes(new Uint8Array(fs.readFileSync(f)), { maxIssues: 50 });
    out[f] = { errors: r.issues.numErrors, warnings: r.issues.numWarnings,
               first: r.issues.messages.slice(0, 3).map((m) => `${m.code} ${m.pointer || ''}: ${m.message}`) };
  }
  console.log(JSON.stringify(out));
})().catch((e) => { console.error(String(e)); process.exit(2); });
"""

failures = []


def expect(ok, what):
    print(("ok    " if ok else "FAIL  ") + what, flush=True)
    if not ok:
        failures.append(what)


def validate(paths):
    node = shutil.which("node")
    module = os.path.join(ROOT, "node_modules", "gltf-validator")
    if node is None or not os.path.isdir(module):
        expect(False, "node and node_modules/gltf-validator are installed (scripts/setup installs them)")
        return None
    r = subprocess.run([node, "-e", VALIDATE, module, *paths], capture_output=True, text=True, timeout=120)
    if r.returncode != 0:
        expect(False, f"the validator ran (exit {r.returncode}: {r.stderr.strip()[:300]})")
        return None
    return json.loads(r.stdout)


def accessor_offset(data, doc, index):
    """Byte offset in the GLB of accessor `index`'s first element."""
    json_len = struct.unpack_from("<I", data, 12)[0]
    a = doc["accessors"][index]
    view = doc["bufferViews"][a["bufferView"]]
    return 20 + json_len + 8 + view.get("byteOffset", 0) + a.get("byteOffset", 0)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--keep", help="work in this folder and keep it (default: a temporary one, removed)")
    args = ap.parse_args()
    work = args.keep or tempfile.mkdtemp(prefix="fluidform-character-test-")
    os.makedirs(work, exist_ok=True)
    try:
        run(work)
    finally:
        if not args.keep:
            shutil.rmtree(work, ignore_errors=True)
    print("PASS" if not failures else f"FAILED: {len(failures)} check(s)", flush=True)
    return 1 if failures else 0


def run(work):
    script = os.path.join(ROOT, "scripts", "make_character.py")
    glb = os.path.join(work, "character.glb")
    r = subprocess.run([sys.executable, script, "--out", glb, "--check"], capture_output=True, text=True, timeout=120)
    sys.stdout.write(r.stdout)
    sys.stderr.write(r.stderr)
    expect(r.returncode == 0, "make_character.py --check exits 0")
    if not os.path.isfile(glb):
        expect(False, "the generator wrote the file")
        return
    info = json.loads(r.stdout.strip().splitlines()[-1])
    expect(info.get("check") == "ok", "its read-back check passed")
    expect(info["bytes"] < 300_000, f"under 300 KB ({info['bytes']} bytes)")
    expect(1000 <= info["triangles"] <= 10_000, f"a few thousand triangles ({info['triangles']})")
    expect(15 <= info["joints"] <= 20, f"~15 joints ({info['joints']})")
    expect(info["parts"] >= 12, f"built of closed parts ({info['parts']})")
    walk = info.get("clips", {}).get("walk")
    expect(walk is not None and 1.0 <= walk["duration"] <= 1.2 and walk["keys"] >= 24,
           f"a 1.0-1.2 s walk of >= 24 keys ({walk})")
    leftovers = [f for f in os.listdir(work) if f != "character.glb"]
    expect(not leftovers, f"no temporary file left beside it ({leftovers})")

    again = os.path.join(work, "again.glb")
    subprocess.run([sys.executable, script, "--out", again], capture_output=True, check=True, timeout=120)
    with open(glb, "rb") as f:
        data = f.read()
    with open(again, "rb") as f:
        expect(f.read() == data, "a second run writes the same bytes (deterministic)")

    # The checks can fail: each corruption must be caught.
    doc, acc = make_character.read_glb(data)
    prim = doc["meshes"][0]["primitives"][0]
    idx_at = accessor_offset(data, doc, prim["indices"])
    flipped = bytearray(data)  # swap two corners of the first triangle: that part's winding is no longer consistent
    a, b = struct.unpack_from("<HH", flipped, idx_at)
    struct.pack_into("<HH", flipped, idx_at, b, a)
    expect(bool(make_character.check(bytes(flipped))[0]), "check catches a triangle wound the wrong way")
    heavy = bytearray(data)  # the first vertex's first weight doubled
    w_at = accessor_offset(data, doc, prim["attributes"]["WEIGHTS_0"])
    struct.pack_into("<f", heavy, w_at, 2 * struct.unpack_from("<f", heavy, w_at)[0])
    expect(bool(make_character.check(bytes(heavy))[0]), "check catches weights that do not sum to 1")
    broken = bytearray(data)  # the walk's first rotation key no longer equal to its last
    walk_doc = next(x for x in doc["animations"] if x["name"] == "walk")
    rot = next(c for c in walk_doc["channels"] if c["target"]["path"] == "rotation")
    q_at = accessor_offset(data, doc, walk_doc["samplers"][rot["sampler"]]["output"])
    struct.pack_into("<4f", broken, q_at, 0.6, 0.0, 0.0, 0.8)  # a unit quaternion, 74° about X
    expect(bool(make_character.check(bytes(broken))[0]), "check catches a walk that does not loop")
    bad_index = os.path.join(work, "bad_index.glb")
    out_of_range = bytearray(data)
    struct.pack_into("<H", out_of_range, idx_at, 65000)
    with open(bad_index, "wb") as f:
        f.write(out_of_range)
    expect(bool(make_character.check(bytes(out_of_range))[0]), "check catches an index out of range")

    report = validate([glb, bad_index])
    if report is not None:
        good, bad = report[glb], report[bad_index]
        expect(good["errors"] == 0, f"the Khronos validator: 0 errors ({good['errors']} errors, "
                                    f"{good['warnings']} warnings {good['first']})")
        expect(bad["errors"] > 0, f"the validator catches an index out of range ({bad['errors']} errors)")


if __name__ == "__main__":
    sys.exit(main())
