"""Figures of the docking run (matplotlib imported lazily, Agg backend)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from uvms_jax.evo._wmax import WmaxMap
from uvms_jax.plotting import pyplot


def plot_wmax(m: WmaxMap, title: str, path: Path, vmax: float) -> None:
    """Heat map of ``w_max`` (eq. 16) over the task area, zero-w area shaded red, to ``path``."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(5, 4.2))
    im = ax.pcolormesh(m.x, m.y, m.w_max.T, shading="nearest", cmap="viridis", vmin=0.0, vmax=vmax)
    zero = np.ma.masked_where(m.w_max.T > 0, np.ones_like(m.w_max.T))
    ax.pcolormesh(m.x, m.y, zero, shading="nearest", cmap="Reds", vmin=0, vmax=1.5, alpha=0.6)
    fig.colorbar(im, ax=ax, label="$w_{max}$ (eq. 16)")
    ax.set(xlabel="x in G [m]", ylabel="y in G [m]", title=f"{title}\nzero-w area {100 * m.zero_fraction:.1f} %")
    ax.set_aspect("equal")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def plot_convergence(ga_hist, cma_hist, references: dict[str, float], path: Path) -> None:
    """Best fitness per generation of every GA (and CMA-ES) run, with reference lines."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(6.5, 4))
    for i, h in enumerate(ga_hist):
        ax.plot(np.arange(1, len(h) + 1), h, color="C0", alpha=0.8, label="GA runs" if i == 0 else None)
    for i, h in enumerate(cma_hist):
        ax.plot(np.arange(1, len(h) + 1), h, color="C1", alpha=0.6, label="CMA-ES runs" if i == 0 else None)
    for (name, f), ls in zip(references.items(), ("--", ":")):
        ax.axhline(f, color="k", ls=ls, label=name)
    top = max(references.values())
    finite = [v for h in list(ga_hist) + list(cma_hist) for v in np.asarray(h)[np.isfinite(h)]]
    lo = np.percentile(finite, 5) if finite else top - 1
    ax.set_ylim(min(lo, top - 0.5), top + 0.1 * abs(top - lo) + 0.05)
    ax.set(xlabel="generation", ylabel="best fitness (eq. 15)", title="Docking optimisation: convergence")
    ax.legend(loc="lower right")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
