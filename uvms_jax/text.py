"""Numbers as text: Markdown tables of reports and the papers, number lists of URDF/MJCF files.

Bottom layer (NumPy only): every package that writes a table or a description takes its
formatting from here, so that one number reads the same everywhere.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

__all__ = ["cell", "md_table", "numbers"]

#: Significant digits of a float in a Markdown table.
TABLE_DIGITS = 4


def cell(v: Any, digits: int = TABLE_DIGITS) -> str:
    """One table cell: a float with ``digits`` significant digits, None or NaN as an em dash,
    anything else as ``str``."""
    if v is None or (isinstance(v, float) and math.isnan(v)):
        return "—"
    if isinstance(v, float):
        return f"{v:.{digits}g}"
    return str(v)


def md_table(header: Sequence[str], rows: Sequence[Sequence[Any]]) -> str:
    """A Markdown table of ``rows`` under ``header``; each value through :func:`cell`."""
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(cell(v) for v in r) + " |" for r in rows]
    return "\n".join(lines)


def numbers(values) -> str:
    """An array's values, flattened, as space-separated numbers (an XML attribute:
    ``"0 0.1 -0.25"``), each the shortest text that reads back as the same float64: a model
    written and read again is the model built, to the last bit (a pose's quaternion rounded to
    10 digits moved an arm's base by 5e-12 m)."""
    return " ".join(repr(float(v)) for v in np.ravel(values))
