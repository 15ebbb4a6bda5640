"""Helpers of the pipeline tests: the repository root and the experiments as importable modules.

The experiment scripts are Hydra entry points, not package modules; the tests put
``experiments/`` on ``sys.path`` (as running a script there does) and import them by name.
"""

from __future__ import annotations

import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
CONFIG_DIR = ROOT / "configs"
EXPERIMENTS = ROOT / "experiments"
if str(EXPERIMENTS) not in sys.path:
    sys.path.insert(0, str(EXPERIMENTS))
