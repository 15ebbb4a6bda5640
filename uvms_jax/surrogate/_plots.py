"""Figures of the surrogate design run (dexterity paper Figs. 8–15); matplotlib is imported lazily."""

from __future__ import annotations

from pathlib import Path
from typing import Mapping

import numpy as np

from uvms_jax.plotting import pyplot, save_figure
from uvms_jax.surrogate._design import Design


def _design_error_axes(name: str, x: list, design: Design, error_goal: float, xlabel: str, width: float):
    """A design loop's max relative test error over ``x`` (sizes or spreads), with the goal line."""
    fig, ax = pyplot().subplots(figsize=(width, 3.8), layout="constrained")
    ax.semilogy(x, [s.test_error for s in design.steps], "o-", label="max relative test error")
    ax.axhline(error_goal, color="r", ls="--", label=f"E = {error_goal:g}")
    ax.set(xlabel=xlabel, ylabel="max |(T − S)/T|", title=f"{name.upper()} design process")
    return fig, ax


def _save(fig, path: Path) -> None:
    save_figure(fig, path, dpi=120)


def plot_ffbn_design(name: str, design: Design, error_goal: float, path: Path) -> None:
    """Max relative test error vs hidden neurons of an FFBN design loop (Figs. 10/14) → PNG."""
    fig, ax = _design_error_axes(name, [s.size for s in design.steps], design, error_goal, "hidden neurons", 5.5)
    from matplotlib.ticker import MaxNLocator  # after pyplot(): matplotlib is imported lazily
    ax.xaxis.set_major_locator(MaxNLocator(integer=True))
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8)
    _save(fig, path)


def plot_rbfn_design(name: str, design: Design, error_goal: float, path: Path) -> None:
    """Max relative test error and RBF units vs spread of an RBFN design loop (Figs. 8/12) → PNG."""
    spreads = [s.spread for s in design.steps]
    fig, ax = _design_error_axes(name, spreads, design, error_goal, "spread [normalised input units]", 6.5)
    from matplotlib.ticker import MaxNLocator  # after pyplot(): matplotlib is imported lazily
    ax2 = ax.twinx()
    ax2.plot(spreads, [s.size for s in design.steps], "s:", color="gray", label="RBF units")
    ax2.set_ylabel("RBF units")
    ax2.yaxis.set_major_locator(MaxNLocator(integer=True))
    lines = ax.get_legend_handles_labels()[0] + ax2.get_legend_handles_labels()[0]
    ax.legend(lines, [h.get_label() for h in lines], loc="upper left", bbox_to_anchor=(1.15, 1.0), fontsize=8)
    _save(fig, path)


def plot_training(designs: Mapping[str, Design], path: Path) -> None:
    """Training mse [index units²] of each selected network, per epoch or added unit (Figs. 9/11/13/15) → PNG."""
    plt = pyplot()
    from matplotlib.ticker import MaxNLocator  # after pyplot(): matplotlib is imported lazily
    fig, ax = plt.subplots(figsize=(7, 4), layout="constrained")
    for name, d in designs.items():
        label = "unit" if name.startswith("rbfn") else "epoch"
        ax.semilogy(np.arange(len(d.history)), d.history, label=f"{name} (per {label})")
    ax.xaxis.set_major_locator(MaxNLocator(integer=True))
    ax.set(xlabel="epoch / added unit", ylabel="training mse [index units²]", title="Training of the selected networks")
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8)
    save_figure(fig, path, dpi=120)
