"""What every block's renderer shares: the result files and the number formats."""

from __future__ import annotations

import json
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
RESULTS = ROOT / "benchmarks" / "results"


#: The H100 SXM's memory bandwidth, its datasheet figure [B/s].
H100_BANDWIDTH = 3.35e12


#: The H100 and H200 issue 132 SMs × 128 FP32 lanes at 1.98 GHz (datasheet boost clock) [instructions/s].
HOPPER_FP32 = 132 * 128 * 1.98e9


#: The H200's memory bandwidth, its datasheet figure [B/s].
H200_BANDWIDTH = 4.8e12


def _load(name: str) -> dict:
    return json.loads((RESULTS / name).read_text())


def _reproduction() -> dict:
    """The record of ``make papers`` (docs/reproduction.json)."""
    return json.loads((ROOT / "docs" / "reproduction.json").read_text(encoding="utf-8"))


def _rate(v: float) -> str:
    """``2.50e7`` style: three significant digits, no '+' or leading zero in the exponent."""
    mantissa, exponent = f"{v:.2e}".split("e")
    return f"{mantissa}e{int(exponent)}"


def _sci(v: float) -> str:
    """``2.4e-6`` style: two significant digits, no '+' or leading zero in the exponent."""
    mantissa, exponent = f"{v:.1e}".split("e")
    return f"{mantissa}e{int(exponent)}"


def _batch(n: int) -> str:
    mantissa, exponent = f"{n:.0e}".split("e")
    return f"{mantissa}e{int(exponent)}"


def _minutes(seconds: float) -> str:
    return f"{int(seconds // 60)} min {round(seconds % 60):02d} s"


def _int(n: float) -> str:
    """``2 430 252``: a whole number with spaces between thousands."""
    return f"{round(n):,}".replace(",", " ")


def _range(values, fmt: str = ".4f") -> str:
    lo, hi = min(values), max(values)
    return f"{lo:{fmt}}" if f"{lo:{fmt}}" == f"{hi:{fmt}}" else f"{lo:{fmt}}–{hi:{fmt}}"


def _ms(v: float) -> str:
    return f"{v:.1f}" if v < 100 else f"{v:.0f}"
