# The fluidform CLI as a child process: started in a process group of its own, its stderr read by a thread and
# turned into progress, cancelled by killing the whole group. Plain Python (no bpy), so that it can be tested and
# reused outside Blender.
import os
import re
import signal
import subprocess
import threading
import time

# `[16:09:24] info: forming: 60/600 (10%)  ETA 56s` (the CLI's non-tty progress lines).
PROGRESS_LINE = re.compile(r"info: (?P<stage>[^:]+): (?P<done>\d+)/(?P<total>\d+) \((?P<pct>\d+)%\)(?:\s+ETA (?P<eta>\S+))?")
# `fluidform: error: targets[0]: /tmp/nope.obj: no such file` (one line, then a non-zero exit).
ERROR_LINE = re.compile(r"error: (?P<message>.*)$")

# How much of the whole run each stage stands for (the rest, 0.97–1, is the import into Blender).
STAGE_SPANS = {
    "sample elimination": (0.00, 0.04),
    "blue-noise relaxation": (0.04, 0.10),
    "forming": (0.10, 0.85),
    "simulating": (0.10, 0.85),
    "meshing": (0.85, 0.97),
}


class Progress:
    """The latest progress the run reported."""

    def __init__(self):
        self.stage = "starting"
        self.done = 0
        self.total = 0
        self.eta = ""
        self.fraction = 0.0  # of the whole Form, 0–1

    def text(self):
        if self.total:
            eta = f", ETA {self.eta}" if self.eta and self.fraction < 0.97 else ""
            return f"{self.stage} {self.done}/{self.total}{eta}"
        return self.stage


def parse_progress(line, progress):
    """Updates `progress` from one stderr line; True when the line was a progress line."""
    m = PROGRESS_LINE.search(line)
    if not m:
        return False
    stage = m.group("stage").strip()
    done, total = int(m.group("done")), int(m.group("total"))
    lo, hi = STAGE_SPANS.get(stage, (progress.fraction, progress.fraction))
    f = lo + (hi - lo) * (done / total if total else 0.0)
    progress.stage, progress.done, progress.total, progress.eta = stage, done, total, m.group("eta") or ""
    progress.fraction = max(progress.fraction, min(f, 0.97))
    return True


def process_group_alive(pgid):
    """Whether any process of the group `pgid` is still there (zombies excluded)."""
    try:
        os.killpg(pgid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    # killpg also succeeds for a group whose only members are zombies: look at /proc where there is one.
    if not os.path.isdir("/proc"):
        return True
    for pid in os.listdir("/proc"):
        if not pid.isdigit():
            continue
        try:
            with open(f"/proc/{pid}/stat") as f:
                stat = f.read()
        except OSError:
            continue
        fields = stat[stat.rindex(")") + 2:].split()
        if int(fields[2]) == pgid and fields[0] != "Z":
            return True
    return False


class Run:
    """One `fluidform run`: start(), poll() until it returns the exit code, or cancel()."""

    def __init__(self, argv, log_path, env=None):
        self.argv = list(argv)
        self.log_path = log_path
        self.env = env
        self.progress = Progress()
        self.error = ""  # the CLI's one-line error, if it printed one
        self.tail = []  # the last stderr lines (for a failure without an error line)
        self.proc = None
        self.pgid = None
        self.returncode = None
        self.started = None
        self._reader = None
        self._lock = threading.Lock()

    def start(self):
        self.started = time.monotonic()
        log = open(self.log_path, "w", encoding="utf-8")
        try:
            # A session (and so a process group) of its own: cancel kills everything the CLI started, and a
            # Ctrl+C in Blender's terminal does not reach it.
            if os.name == "nt":  # no process groups to kill: a group of its own for Ctrl+C, terminate() on cancel
                self.proc = subprocess.Popen(self.argv, stdin=subprocess.DEVNULL, stdout=log, stderr=subprocess.PIPE,
                                             env=self.env, creationflags=subprocess.CREATE_NEW_PROCESS_GROUP)
            else:
                self.proc = subprocess.Popen(self.argv, stdin=subprocess.DEVNULL, stdout=log, stderr=subprocess.PIPE,
                                             env=self.env, start_new_session=True)
        finally:
            log.close()
        self.pgid = self.proc.pid  # the session leader's pid is the group id
        self._reader = threading.Thread(target=self._read_stderr, name="fluidform-stderr", daemon=True)
        self._reader.start()

    def _read_stderr(self):
        with open(self.log_path, "a", encoding="utf-8") as log:
            for raw in iter(self.proc.stderr.readline, b""):
                line = raw.decode("utf-8", "replace").rstrip("\r\n")
                log.write(line + "\n")
                with self._lock:
                    if not parse_progress(line, self.progress):
                        m = ERROR_LINE.search(line)
                        if m:
                            self.error = m.group("message")
                        self.tail = (self.tail + [line])[-8:]
        self.proc.stderr.close()

    def snapshot(self):
        """(fraction 0–1, text) of the latest progress, safe to call from any thread."""
        with self._lock:
            return self.progress.fraction, self.progress.text()

    def poll(self):
        """None while the CLI runs, else its exit code (after its stderr has been read to the end)."""
        if self.returncode is not None:
            return self.returncode
        rc = self.proc.poll()
        if rc is None:
            return None
        self._reader.join()
        self.returncode = rc
        return rc

    def failure(self):
        """One line saying why the run failed."""
        with self._lock:
            if self.error:
                return self.error
            last = next((t for t in reversed(self.tail) if t.strip()), "")
        rc = self.returncode
        if rc is not None and rc < 0:
            return f"fluidform was killed by signal {-rc}" + (f" ({last})" if last else "")
        return f"fluidform exited with code {rc}" + (f": {last}" if last else "")

    def cancel(self, grace=3.0):
        """Ends the CLI and everything in its process group: SIGTERM, then SIGKILL after `grace` seconds."""
        if self.proc is None:
            return
        if os.name == "nt":
            if self.returncode is None:
                self.proc.terminate()
                self.proc.wait()
                self.returncode = self.proc.returncode
        elif self.returncode is None:
            for sig in (signal.SIGTERM, signal.SIGKILL):
                try:
                    os.killpg(self.pgid, sig)
                except ProcessLookupError:
                    break
                deadline = time.monotonic() + grace
                while time.monotonic() < deadline and process_group_alive(self.pgid):
                    self.proc.poll()
                    time.sleep(0.02)
                if not process_group_alive(self.pgid):
                    break
            self.proc.wait()
            self.returncode = self.proc.returncode
        elif os.name != "nt":
            # The CLI has exited; anything it left in its group goes too.
            try:
                os.killpg(self.pgid, signal.SIGKILL)
            except ProcessLookupError:
                pass
        if self._reader is not None:
            self._reader.join(timeout=5.0)
