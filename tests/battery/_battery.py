"""Helpers of the bad-input battery: refusals of the command lines, each checked for its exit
status and its one line, many in one child process (the imports once), each case timed and the
child's peak memory measured."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
USAGE_EXIT = 2  # a refused input: experiments/_cli.py, uvms-hw
# No input may hang (each case ends within this) or grow the process past this.
CASE_LIMIT_S = 10.0
MEMORY_LIMIT_B = 1 << 30  # 1 GiB peak resident memory of the child (a JAX process starts near 0.4)

# The child: loads `experiments/<script>` once (its imports), then runs it once per case as its
# own __main__ (runpy), each with its stdout and stderr captured, and reports exit status,
# output, time, and finally its peak RSS: VmHWM of its own address space where Linux says it
# (getrusage's ru_maxrss also keeps the peak of the pytest worker that spawned it, across exec).
_DRIVER = r"""
import contextlib, io, json, resource, runpy, sys, time
script, cases = sys.argv[1], json.loads(sys.argv[2])
sys.path.insert(0, str(__import__("pathlib").Path(script).parent))
runpy.run_path(script, run_name="__imports__")  # the script's imports, outside every case's time
out = []
for args in cases:
    sys.argv = [script, *args]
    buf = io.StringIO()
    t = time.perf_counter()
    try:
        with contextlib.redirect_stdout(buf), contextlib.redirect_stderr(buf):
            runpy.run_path(script, run_name="__main__")
        code = 0
    except SystemExit as e:
        code = e.code if isinstance(e.code, int) else 1
    out.append({"code": code, "output": buf.getvalue(), "seconds": time.perf_counter() - t})
status = __import__("pathlib").Path("/proc/self/status")
hwm = [line.split()[1] for line in status.read_text().splitlines() if line.startswith("VmHWM:")] if status.exists() else []
peak = int(hwm[0]) * 1024 if hwm else resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
print(json.dumps({"cases": out, "max_rss_b": peak}))
"""


def run_cases(script: str, cases: list[list[str]]) -> list[dict]:
    """Each case (the command-line arguments of ``experiments/<script>``) run in one child
    process: ``{"code", "output", "seconds"}`` per case; asserts every case's time and the
    child's peak memory within the battery's limits."""
    proc = subprocess.run([sys.executable, "-c", _DRIVER, str(ROOT / "experiments" / script), json.dumps(cases)],
                          cwd=ROOT, capture_output=True, text=True, timeout=60 + CASE_LIMIT_S * len(cases))
    assert proc.returncode == 0, proc.stderr[-3000:]
    report = json.loads(proc.stdout.strip().splitlines()[-1])
    assert report["max_rss_b"] < MEMORY_LIMIT_B, report["max_rss_b"]
    for case, result in zip(cases, report["cases"]):
        assert result["seconds"] < CASE_LIMIT_S, (case, result)
    return report["cases"]


def one_line(result: dict, code: int = USAGE_EXIT) -> str:
    """The single line of a refusal (exit status ``code``), without a traceback."""
    lines = [line for line in result["output"].splitlines() if line.strip()]
    assert result["code"] == code, result["output"][-3000:]
    assert "Traceback" not in result["output"]
    assert len(lines) == 1, lines
    return lines[0]
