"""The README's weight-sensitivity sweep, run as the README writes it, with its time.

Runs the two commands that README.md's "Sweeps" section shows (generated from this record) (five weight sets of the scheduling
experiment on synthetic metrics as one Hydra multirun, then ``experiments/gather.py``) in a
temporary sweep folder and prints one JSON object: the commands, the gathered table
(``gathered.md``) and the wall time of both commands together [s].

    python benchmarks/weights_sweep.py > benchmarks/results/weights_sweep_cpu.json
"""

from __future__ import annotations

import os
import platform
import shlex
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from uvms_jax.files import json_text

ROOT = Path(__file__).resolve().parent.parent
SWEEP = ["experiments/schedule.py", "--multirun", "sched/source=synthetic",
         "sched/weights=equal,speed,security,planning_time,only_max_torque", "sched.iterations_sweep=[]"]
GATHER = ["experiments/gather.py", "--columns", "solvers.*.cost", "solvers.exact.path"]


def main() -> None:
    with tempfile.TemporaryDirectory() as tmp:
        sweep_dir = Path(tmp) / "weights"
        start = time.perf_counter()
        subprocess.run([sys.executable, *SWEEP, f"hydra.sweep.dir={sweep_dir}"], cwd=ROOT, check=True,
                       stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        subprocess.run([sys.executable, GATHER[0], str(sweep_dir), *GATHER[1:]], cwd=ROOT, check=True,
                       stdout=subprocess.DEVNULL)
        wall = time.perf_counter() - start
        table = (sweep_dir / "gathered.md").read_text()
    # The commands as a user types them (shell-quoted): README.md shows these.
    print(json_text({"commands": [shlex.join([".venv/bin/python", *SWEEP, "hydra.sweep.dir=multirun/weights"]),
                                   shlex.join([".venv/bin/python", GATHER[0], "multirun/weights", *GATHER[1:]])],
                      "cpu_count": os.cpu_count(), "machine": platform.machine(), "wall_s": wall,
                      "gathered_md": table}))


if __name__ == "__main__":
    main()
