"""Console entry points above the packages they join.

``uvms-hw`` (:func:`uvms_hw`) is :mod:`uvms_jax.hw.cli` with :mod:`uvms_jax.hover` for
``run --hover`` (the plan on the simulated arm of a hovering vehicle): the hardware runner sits
below the vehicle's package and never imports it, so the command that joins them lives here.
"""

from __future__ import annotations

import sys
from collections.abc import Sequence

from uvms_jax import hover
from uvms_jax.hw import cli as hw_cli

__all__ = ["uvms_hw"]


def uvms_hw(argv: Sequence[str] | None = None) -> int:
    """The ``uvms-hw`` command (:func:`uvms_jax.hw.cli.main` with the hovering vehicle); returns
    the exit status."""
    return hw_cli.main(argv, hovering=hover)


if __name__ == "__main__":
    sys.exit(uvms_hw())
