"""`make demo` as a newcomer runs it: a fresh clone of this repository in a temporary folder,
then `make demo` there, which creates the virtual environment, installs the package (from pip's
cache where the packages are already downloaded) and runs the demo with an empty compilation
cache. Times the clone, the setup (the `make` output before the pipeline's first line) and the
whole command; writes one JSON result file.

    .venv/bin/python benchmarks/fresh_demo.py [--out benchmarks/results/fresh_demo_cpu.json]
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=ROOT / "benchmarks" / "results" / "fresh_demo_cpu.json")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        clone = Path(tmp) / "uvms_jax"
        t0 = time.perf_counter()
        subprocess.run(["git", "clone", "-q", str(ROOT), str(clone)], check=True)
        t_clone = time.perf_counter() - t0
        env = {k: v for k, v in os.environ.items() if not k.startswith(("JAX_", "XLA_", "VIRTUAL_ENV"))}
        env["PATH"] = os.pathsep.join(p for p in env.get("PATH", "").split(os.pathsep) if ".venv" not in p)
        first_line, t1 = None, time.perf_counter()
        proc = subprocess.Popen(["make", "demo"], cwd=clone, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                                text=True)
        tail = []
        for line in proc.stdout:
            if first_line is None and "experiments/pipeline.py" in line:
                first_line = time.perf_counter() - t1  # make has installed and starts the pipeline
            tail = (tail + [line.rstrip()])[-20:]
        code = proc.wait()
        t_make = time.perf_counter() - t1
        runs = [json.loads(f.read_text()) for f in clone.rglob("results.json") if ".venv" not in f.parts]
        outcome = next((r for r in runs if "total_seconds" in r), {})
    result = {
        "benchmark": "fresh_demo", "command": "python benchmarks/fresh_demo.py", "exit_status": code,
        "cpus": os.cpu_count(), "machine": platform.machine(), "python": platform.python_version(),
        "clone_s": t_clone, "setup_s": first_line, "make_demo_s": t_make, "total_s": t_clone + t_make,
        "pipeline_s": outcome.get("total_seconds"), "stage_seconds": outcome.get("stage_seconds"),
        "pose": (outcome.get("docking") or {}).get("pose"), "tail": tail if code else [],
    }
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(result, indent=1) + "\n")
    print(json.dumps(result, indent=1))
    return code


if __name__ == "__main__":
    sys.exit(main())
