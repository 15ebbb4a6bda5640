"""Runs of an experiment script's command line, many in one child process: the script's imports
(most of a refusal's time) once, then each case as the script's own ``__main__`` (runpy) with
its own arguments, exit status and captured output. The command-line tests and the bad-input
battery (tests/battery) use it; ``tests/`` is on ``sys.path`` (its conftest's folder).

A case that must start a process of its own (a signal, a backend's first start) runs as a
subprocess instead.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

# The child: loads the script once (its imports), then runs it once per case as its own
# __main__, each with stdout and stderr captured (together as "output", and stderr alone),
# and reports exit status, output, time, and finally its peak RSS: VmHWM of its own address
# space where Linux says it (getrusage's ru_maxrss also keeps the peak of the pytest worker
# that spawned it, across exec).
_DRIVER = r"""
import contextlib, io, json, resource, runpy, sys, time
script, cases = sys.argv[1], json.loads(sys.argv[2])
sys.path.insert(0, str(__import__("pathlib").Path(script).parent))
runpy.run_path(script, run_name="__imports__")  # the script's imports, outside every case's time


class Tee(io.StringIO):
    def __init__(self, both):
        super().__init__()
        self.both = both

    def write(self, s):
        self.both.write(s)
        return super().write(s)


out = []
for args in cases:
    sys.argv = [script, *args]
    buf = io.StringIO()
    err = Tee(buf)
    t = time.perf_counter()
    try:
        with contextlib.redirect_stdout(buf), contextlib.redirect_stderr(err):
            runpy.run_path(script, run_name="__main__")
        code = 0
    except SystemExit as e:
        code = e.code if isinstance(e.code, int) else (0 if e.code is None else 1)
    out.append({"code": code, "output": buf.getvalue(), "stderr": err.getvalue(), "seconds": time.perf_counter() - t})
status = __import__("pathlib").Path("/proc/self/status")
hwm = [line.split()[1] for line in status.read_text().splitlines() if line.startswith("VmHWM:")] if status.exists() else []
peak = int(hwm[0]) * 1024 if hwm else resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
print(json.dumps({"cases": out, "max_rss_b": peak}))
"""


def run_script_cases(script: str, cases: list[list[str]], timeout: float) -> dict:
    """Each case (the command-line arguments of ``experiments/<script>``) run in one child
    process, from the repository root: ``{"cases": [{"code", "output", "stderr", "seconds"}, ...],
    "max_rss_b": peak resident memory [B]}``."""
    proc = subprocess.run([sys.executable, "-c", _DRIVER, str(ROOT / "experiments" / script), json.dumps(cases)],
                          cwd=ROOT, capture_output=True, text=True, timeout=timeout)
    assert proc.returncode == 0, proc.stderr[-3000:]
    return json.loads(proc.stdout.strip().splitlines()[-1])
