"""Figures: matplotlib on its file-only backend, imported on first use.

Library modules that draw call :func:`pyplot` inside their plotting functions, so importing the
package never imports matplotlib, and figures render on machines without a display.
"""

from __future__ import annotations

__all__ = ["pyplot"]


def pyplot():
    """``matplotlib.pyplot`` with the Agg backend (PNG files, no window)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt
