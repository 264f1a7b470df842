#!/usr/bin/env python3
"""Every arrow points down: each folder of src/ may include only the folders it is declared to depend on (and
itself), and the declared graph has no circle. Fails, naming the file, the line and the arrow, on an #include of a
higher stage or of an undeclared folder. docs/ARCHITECTURE.md draws the same graph; src/CMakeLists.txt links it.

usage: check_includes.py [SRC_DIR]     (default: the src/ beside this script's tests/)
"""
import pathlib
import re
import sys

# folder -> the folders it may include (besides itself). The link graph of src/*/CMakeLists.txt, one level each.
ALLOWED = {
    "core": set(),
    "io": {"core"},
    "sampling": {"core", "io"},
    "sim": {"core"},
    "surface": {"core", "io"},
    "metrics": {"core", "io", "sampling"},
    "pose": {"core", "io", "sampling"},
    "control": {"core", "io", "sampling", "sim", "pose"},
    "gpu": {"core", "io", "sampling", "sim", "pose", "control"},
    "scene": {"core", "io", "sampling", "sim", "surface", "pose", "control"},
    "pipeline": {"core", "io", "sampling", "sim", "gpu", "surface", "metrics", "pose", "control", "scene"},
    # The front doors go through the pipeline: they include pipeline/, scene/ and the plain types of core/ and io/,
    # never a stage (sampling, sim, surface, metrics, pose, control), so a stage's entry point changes in one place.
    "server": {"core", "io", "scene", "pipeline"},
    "app": {"core", "io", "scene", "pipeline", "server"},
    "python": {"core", "io", "scene", "pipeline"},
}
FRONT_DOORS = {"server", "app", "python"}
STAGES = {"sampling", "sim", "gpu", "surface", "metrics", "pose", "control"}
INCLUDE = re.compile(r'^\s*#\s*include\s*"([a-z_]+)/[^"]+"')


def find_circle(graph):
    """A list of folders forming a circle in `graph`, or None."""
    state = {}

    def visit(node, path):
        state[node] = "open"
        for nxt in sorted(graph.get(node, ())):
            if state.get(nxt) == "open":
                return path[path.index(nxt):] + [nxt] if nxt in path else [node, nxt]
            if nxt not in state:
                found = visit(nxt, path + [nxt])
                if found:
                    return found
        state[node] = "done"
        return None

    for node in sorted(graph):
        if node not in state:
            found = visit(node, [node])
            if found:
                return found
    return None


def main():
    src = pathlib.Path(sys.argv[1]) if len(sys.argv) > 1 else pathlib.Path(__file__).resolve().parents[2] / "src"
    problems = []
    circle = find_circle(ALLOWED)
    if circle:
        problems.append("the declared folder graph has a circle: " + " -> ".join(circle))
    folders = sorted(p.name for p in src.iterdir() if p.is_dir())
    for folder in folders:
        if folder not in ALLOWED:
            problems.append(f"src/{folder}/: a folder with no place in the layer graph (add it to {__file__})")
    used = {f: set() for f in folders}
    files = 0
    for path in sorted(src.rglob("*")):
        if path.suffix not in (".h", ".cpp") or not path.is_file():
            continue
        files += 1
        folder = path.relative_to(src).parts[0]
        for n, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
            m = INCLUDE.match(line)
            if not m or m.group(1) == folder:
                continue
            used.setdefault(folder, set()).add(m.group(1))
            if folder in FRONT_DOORS and m.group(1) in STAGES:
                problems.append(f"{path.relative_to(src.parent)}:{n}: the front door {folder} includes the stage "
                                f"{m.group(1)} directly: call a pipeline/ entry point (pipeline/front_doors.h)")
            elif m.group(1) not in ALLOWED.get(folder, set()):
                problems.append(f"{path.relative_to(src.parent)}:{n}: {folder} -> {m.group(1)} points up or sideways "
                                f"({folder} may include: {', '.join(sorted(ALLOWED.get(folder, ()))) or 'nothing'})")
    circle = find_circle(used)
    if circle:
        problems.append("the includes form a folder circle: " + " -> ".join(circle))
    for p in problems:
        print("FAIL", p)
    print(f"check_includes: {files} files in {len(folders)} folders, {len(problems)} problems")
    return 1 if problems else 0


def self_test():
    """The check can fail: a copy of src/ with an upward include planted (core -> scene) must fail, and so must one
    with a folder the graph does not know."""
    import shutil
    import subprocess
    import tempfile
    src = pathlib.Path(__file__).resolve().parents[2] / "src"
    ok = main_on(src) == 0
    print(f"{'ok  ' if ok else 'FAIL'} src/ as it is passes")
    with tempfile.TemporaryDirectory() as tmp:
        copy = pathlib.Path(tmp) / "src"
        shutil.copytree(src, copy)
        planted = copy / "core" / "kernels.h"
        planted.write_text('#include "scene/scene.h"\n' + planted.read_text(encoding="utf-8"), encoding="utf-8")
        up = subprocess.run([sys.executable, __file__, str(copy)], capture_output=True, text=True)
        caught = up.returncode != 0 and "core -> scene points up" in up.stdout
        print(f"{'ok  ' if caught else 'FAIL'} a planted core -> scene include fails the check")
        planted.write_text(planted.read_text(encoding="utf-8").split("\n", 1)[1], encoding="utf-8")
        (copy / "extra").mkdir()
        (copy / "extra" / "x.h").write_text('#include "core/types.h"\n', encoding="utf-8")
        stray = subprocess.run([sys.executable, __file__, str(copy)], capture_output=True, text=True)
        caught_stray = stray.returncode != 0 and "no place in the layer graph" in stray.stdout
        print(f"{'ok  ' if caught_stray else 'FAIL'} an undeclared folder fails the check")
        shutil.rmtree(copy / "extra")
        front = copy / "app" / "cli.cpp"
        front.write_text('#include "sampling/samplers.h"\n' + front.read_text(encoding="utf-8"), encoding="utf-8")
        door = subprocess.run([sys.executable, __file__, str(copy)], capture_output=True, text=True)
        caught_door = door.returncode != 0 and "the front door app includes the stage sampling" in door.stdout
        print(f"{'ok  ' if caught_door else 'FAIL'} a front door including a stage (app -> sampling) fails the check")
    return 0 if ok and caught and caught_stray and caught_door else 1


def main_on(src):
    sys.argv = [sys.argv[0], str(src)]
    return main()


if __name__ == "__main__":
    if len(sys.argv) > 1 and sys.argv[1] == "--self-test":
        sys.exit(self_test())
    sys.exit(main())
