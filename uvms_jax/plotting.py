"""Figures: matplotlib on its file-only backend, imported on first use.

Library modules that draw call :func:`pyplot` inside their plotting functions, so importing the
package never imports matplotlib, and figures render on machines without a display.
:func:`save_figure` writes a figure as every result is written: atomically
(:func:`uvms_jax.files.atomic_path`).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from uvms_jax.files import atomic_path

__all__ = ["pyplot", "save_figure"]


def pyplot():
    """``matplotlib.pyplot`` with the Agg backend (PNG files, no window)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def save_figure(fig: Any, path: Path | str, **savefig_kwargs: Any) -> Path:
    """Save the matplotlib figure ``fig`` to ``path`` atomically (the format from its suffix,
    e.g. ``.png``; ``savefig_kwargs`` such as ``dpi`` go to ``fig.savefig``), then close it.
    Returns ``path``."""
    path = Path(path)
    try:
        with atomic_path(path) as tmp:
            fig.savefig(tmp, format=path.suffix.lstrip(".") or None, **savefig_kwargs)
    finally:
        pyplot().close(fig)
    return path
