"""Run log: commanded vs measured joint states, written as CSV and plotted as PNG."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from uvms_jax.files import write_csv
from uvms_jax.plotting import pyplot, save_figure

__all__ = ["RunLog"]


@dataclasses.dataclass
class RunLog:
    """Rows of ``(t [s] since the run started, segment, waypoint, phase, commanded (n,), measured (n,))``.

    ``measured`` is NaN where a state did not arrive. Units per joint: rad, jaws mm.
    Mutable by design: it is filled while the arm moves.
    """

    joint_names: tuple[str, ...]
    rows: list[tuple] = dataclasses.field(default_factory=list)

    def add(self, t: float, segment: int, waypoint: int, phase: str,
            commanded: Sequence[float], measured: Sequence[float] | None) -> None:
        """Append one tick."""
        meas = tuple(measured) if measured is not None else (math.nan,) * len(self.joint_names)
        self.rows.append((t, segment, waypoint, phase, *map(float, commanded), *map(float, meas)))

    def header(self) -> list[str]:
        """CSV column names."""
        return (["t_s", "segment", "waypoint", "phase"] + [f"cmd_{n}" for n in self.joint_names]
                + [f"meas_{n}" for n in self.joint_names])

    def write_csv(self, path: str | Path) -> Path:
        """Write the log to ``path`` (parent folders created), atomically: a run stopped while
        writing leaves the previous file or none, never a truncated one."""
        return write_csv(path, self.rows, header=self.header())

    def measured(self, joints: Sequence[str]) -> tuple[np.ndarray, np.ndarray]:
        """Times ``(k,)`` [s] and measured states ``(k, len(joints))`` of the rows in which
        every joint of ``joints`` (a subset of ``joint_names``, e.g. the arm's without the
        jaws) was measured: a state that did not arrive is NaN in the log."""
        n = len(self.joint_names)
        cols = [4 + n + self.joint_names.index(j) for j in joints]
        rows = np.asarray([[r[0], *(r[c] for c in cols)] for r in self.rows], dtype=float).reshape(-1, 1 + len(cols))
        rows = rows[np.all(np.isfinite(rows), axis=1)]
        return rows[:, 0], rows[:, 1:]

    def plot(self, path: str | Path, title: str = "arm run: commanded vs measured") -> Path:
        """One panel per joint, commanded (dashed) over measured (solid); PNG at ``path``."""
        plt = pyplot()
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        n = len(self.joint_names)
        t = [r[0] for r in self.rows]
        fig, axes = plt.subplots(n, 1, figsize=(9, 1.6 * n + 1.2), sharex=True, squeeze=False, layout="constrained")
        for j, name in enumerate(self.joint_names):
            ax = axes[j, 0]
            ax.plot(t, [r[4 + j] for r in self.rows], "k--", lw=1, label="commanded")
            ax.plot(t, [r[4 + n + j] for r in self.rows], "C0", lw=1, label="measured")
            ax.set_ylabel(f"{name} [{'mm' if name == 'A' else 'rad'}]")
            ax.grid(alpha=0.3)
        axes[-1, 0].set_xlabel("time [s]")
        fig.suptitle(title)
        # one legend for all panels, above them: never over the data
        fig.legend(*axes[0, 0].get_legend_handles_labels(), loc="outside upper right", ncols=2, fontsize=8)
        return save_figure(fig, path, dpi=100)
