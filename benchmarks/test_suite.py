"""How long CI's test run takes: `bash .ci/run` (`make test`, then `make test-slow`) in a fresh
clone of the current commit, as CI runs it; prints one JSON object.

The clone starts without a virtual environment or a JAX compilation cache. ``make setup``
(installing the pinned wheels from PyPI) is timed first and apart, then each make target of
`.ci/run` in its order, with every compilation in it; pytest's summary line gives its counts.

    python benchmarks/test_suite.py > benchmarks/results/test_suite_cpu.json

Usage: python benchmarks/test_suite.py [--keep DIR]   # DIR: clone there and keep it
       python benchmarks/test_suite.py --isa AVX --targets test > benchmarks/results/test_suite_avx_cpu.json
           # the fast suite with XLA's CPU code generation held to an older instruction set
           # (XLA_FLAGS=--xla_cpu_max_isa=AVX): results must not depend on the CPU's rounding
"""

from __future__ import annotations

import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from uvms_jax.files import json_text

ROOT = Path(__file__).resolve().parents[1]
#: The make targets of .ci/run, in its order.
TARGETS = ("test", "test-slow")
#: pytest's summary line, e.g. "810 passed, 1 skipped in 300.12s (0:05:00)" (-q leaves out the rules).
SUMMARY = re.compile(r"^=*\s*(?P<counts>\d+ \w+(?:, \d+ \w+)*) in (?P<seconds>[\d.]+)s", re.M)


def pytest_counts(output: str) -> dict:
    """``{"passed": 810, "skipped": 1, ...}`` and pytest's own seconds from its last summary line."""
    line = SUMMARY.findall(output)
    if not line:
        raise SystemExit("no pytest summary line in the output of make")
    counts, seconds = line[-1]
    return {word: int(n) for n, word in re.findall(r"(\d+) (\w+)", counts)} | {"pytest_s": float(seconds)}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--keep", type=Path, default=None, help="clone into this (new) folder and keep it")
    ap.add_argument("--targets", nargs="+", choices=TARGETS, default=list(TARGETS), help="make targets to time")
    ap.add_argument("--isa", default=None, help="XLA's highest CPU instruction set (--xla_cpu_max_isa), e.g. AVX")
    args = ap.parse_args()
    commit = subprocess.run(["git", "rev-parse", "HEAD"], cwd=ROOT, capture_output=True, text=True, check=True).stdout.strip()
    where = args.keep or Path(tempfile.mkdtemp(prefix="uvms_ci_")) / "clone"
    subprocess.run(["git", "clone", "-q", str(ROOT), str(where)], check=True)
    env = {k: v for k, v in os.environ.items() if not k.startswith(("JAX_", "XLA_", "VIRTUAL_ENV", "PYTHONPATH"))}
    env["JAX_PLATFORMS"] = "cpu"  # as .ci/run sets it
    if args.isa:
        env["XLA_FLAGS"] = f"--xla_cpu_max_isa={args.isa}"
    command = " ".join(["python benchmarks/test_suite.py", *(["--isa", args.isa] if args.isa else []),
                        *(["--targets", *args.targets] if args.targets != list(TARGETS) else [])])
    record = {"benchmark": "test_suite", "command": command, "commit": commit, "xla_flags": env.get("XLA_FLAGS", ""),
              "cpu_count": os.cpu_count(), "load_average_start": os.getloadavg(), "targets": {}}
    start = time.perf_counter()
    for target in ("setup", *args.targets):  # setup apart: the tests' times leave the installation out
        t0 = time.perf_counter()
        run = subprocess.run(["make", target], cwd=where, env=env, capture_output=True, text=True)
        seconds = time.perf_counter() - t0
        if run.returncode != 0:
            sys.stderr.write(run.stdout[-4000:] + run.stderr[-4000:])
            raise SystemExit(f"make {target} failed (exit {run.returncode}) in {where}")
        record["targets"][target] = {"seconds": seconds, **(pytest_counts(run.stdout) if target in TARGETS else {})}
        print(f"make {target}: {seconds:.0f} s", file=sys.stderr)
    record["seconds"] = time.perf_counter() - start
    record["load_average_end"] = os.getloadavg()
    if args.keep is None:
        shutil.rmtree(where.parent)
    print(json_text(record))


if __name__ == "__main__":
    main()
