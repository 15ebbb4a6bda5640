"""`make demo` as a newcomer runs it: a fresh clone of this repository in a temporary folder,
then `make demo` there, which creates the virtual environment, installs the package (from pip's
cache where the packages are already downloaded) and runs the demo with an empty compilation
cache. Times the clone, the setup (the `make` output before the pipeline's first line) and the
whole command; writes one JSON result file.

The planner's Numba kernels are cached per machine by their source (docs/planning.md): with
``--numba-cache user`` (the default, what ``make demo`` does) a clone of source already run on
this machine loads them; ``--numba-cache empty`` gives the run an empty cache folder, as on a
machine that never ran the demo. The result file says which, and whether the user's cache held
the kernels of this source before the run.

    .venv/bin/python benchmarks/fresh_demo.py [--out benchmarks/results/fresh_demo_cpu.json] [--numba-cache empty]
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

from uvms_jax.files import json_text, write_json

ROOT = Path(__file__).resolve().parents[1]


def _kernels_cached(clone: Path, env: dict) -> bool:
    """Whether the Numba cache the run will use holds kernels compiled from the clone's source."""
    probe = ("import glob, os; from uvms_jax.plan._kernel_cache import cache_folder; "
             "print(bool(glob.glob(os.path.join(cache_folder(), '*.nbi'))))")
    out = subprocess.run([sys.executable, "-c", probe], cwd=clone, env={**env, "PYTHONPATH": str(clone)},
                         capture_output=True, text=True, check=True)
    return out.stdout.strip().splitlines()[-1] == "True"


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=ROOT / "benchmarks" / "results" / "fresh_demo_cpu.json")
    ap.add_argument("--numba-cache", choices=("user", "empty"), default="user",
                    help="the user's Numba cache (default) or an empty one for this run")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        clone = Path(tmp) / "uvms_jax"
        t0 = time.perf_counter()
        subprocess.run(["git", "clone", "-q", str(ROOT), str(clone)], check=True)
        t_clone = time.perf_counter() - t0
        env = {k: v for k, v in os.environ.items() if not k.startswith(("JAX_", "XLA_", "VIRTUAL_ENV"))}
        env["PATH"] = os.pathsep.join(p for p in env.get("PATH", "").split(os.pathsep) if ".venv" not in p)
        if args.numba_cache == "empty":
            env["NUMBA_CACHE_DIR"] = str(Path(tmp) / "numba")
        kernels_cached = _kernels_cached(clone, env)
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
    flag = f" --numba-cache {args.numba_cache}" if args.numba_cache != "user" else ""
    result = {
        "benchmark": "fresh_demo", "command": f"python benchmarks/fresh_demo.py{flag}", "exit_status": code,
        "cpus": os.cpu_count(), "machine": platform.machine(), "python": platform.python_version(),
        "clone_s": t_clone, "setup_s": first_line, "make_demo_s": t_make, "total_s": t_clone + t_make,
        "pipeline_s": outcome.get("total_seconds"), "stage_seconds": outcome.get("stage_seconds"),
        "pose": (outcome.get("docking") or {}).get("pose"), "numba_cache": args.numba_cache,
        "numba_kernels_cached_before": kernels_cached, "tail": tail if code else [],
    }
    args.out.parent.mkdir(parents=True, exist_ok=True)
    write_json(args.out, result)
    print(json_text(result))
    return code


if __name__ == "__main__":
    sys.exit(main())
