"""README's "Your own robot" example, run as a user runs it: what it prints and how long it takes.

Runs ``python examples/own_arm.py`` in a fresh process (imports and compilation included) and
prints one JSON object: the command, the lines the example printed and its wall time [s].

    python benchmarks/own_arm.py > benchmarks/results/own_arm_cpu.json
"""

from __future__ import annotations

import os
import platform
import subprocess
import sys
import time
from pathlib import Path

from uvms_jax.files import json_text

ROOT = Path(__file__).resolve().parent.parent
EXAMPLE = "examples/own_arm.py"


def main() -> None:
    start = time.perf_counter()
    out = subprocess.run([sys.executable, EXAMPLE], cwd=ROOT, check=True, capture_output=True, text=True).stdout
    wall = time.perf_counter() - start
    print(json_text({"command": f"python {EXAMPLE}", "cpu_count": os.cpu_count(), "machine": platform.machine(),
                      "wall_s": wall, "printed": out.splitlines()}, ensure_ascii=False))


if __name__ == "__main__":
    main()
