"""Sizes of one regeneration of docs/reproduction.md, and where its figures go."""

from __future__ import annotations

import dataclasses
from pathlib import Path

from uvms_jax import plotting


@dataclasses.dataclass(frozen=True)
class Preset:
    """Sizes of one regeneration.

    Attributes:
      face_step: docking pose grid step over the block's top face [m].
      z_values, psi_values: docking pose grid heights [m] and headings (count).
      map_n: w_max map resolution per side (paper: a dense map; we use 41).
      bound_n: grid points per joint of the w bound search (θ2, θ3, θ5).
      surrogate: overrides of the surrogate settings (mapping, see uvms_jax.surrogate).
      grasp_sweep: GRASP iteration counts of Figs 5.9–5.12; sweep_repeats: runs per count.
      plan_budget_s: planning budget per edge of the thesis cage (Tables 5.2–5.4) [s].
    """

    name: str
    face_step: float
    z_values: int
    psi_values: int
    map_n: int
    bound_n: int
    surrogate: dict
    grasp_sweep: tuple[int, ...]
    sweep_repeats: int
    plan_budget_s: float


PRESETS = {
    "fast": Preset("fast", face_step=0.05, z_values=4, psi_values=10, map_n=41, bound_n=91,
                   surrogate={"data": {"n_train": {"w": 1000, "kci": 1500}},
                              "ffbn": {"max_hidden": {"w": 30, "kci": 30}},
                              "rbfn": {"spread_start": 2.0, "max_centres": {"w": 150, "kci": 150}},
                              "timing": {"batches": [1000, 100000], "repeats": 3}},
                   grasp_sweep=(1, *range(50, 3001, 50)), sweep_repeats=10, plan_budget_s=1.0),
    # A smoke run of every code path (tests, quick checks): numbers of no meaning.
    "tiny": Preset("tiny", face_step=0.2, z_values=2, psi_values=3, map_n=11, bound_n=21,
                   surrogate={"data": {"n_train": {"w": 300, "kci": 300}, "n_test": 200},
                              "ffbn": {"max_hidden": {"w": 2, "kci": 2}},
                              "rbfn": {"spread_start": 9.0, "max_centres": {"w": 20, "kci": 20}},
                              "timing": {"batches": [1000], "repeats": 1}},
                   grasp_sweep=(1, 10), sweep_repeats=2, plan_budget_s=0.5),
    "paper": Preset("paper", face_step=0.025, z_values=7, psi_values=19, map_n=81, bound_n=181,
                    surrogate={}, grasp_sweep=(1, *range(50, 3001, 50)), sweep_repeats=20,
                    plan_budget_s=5.0),
}


def join_and(words: list[str]) -> str:
    """``a``, ``a and b``, ``a, b and c`` (the document's lists in prose)."""
    return " and ".join([", ".join(words[:-1]), words[-1]]) if len(words) > 1 else "".join(words)


def save_figure(fig, img: Path, name: str) -> str:
    """Save a figure as a small PNG ``img/name``; returns its path relative to docs/ (the
    document links ``img/papers/<name>``)."""
    plotting.save_figure(fig, img / name, dpi=100, bbox_inches="tight")
    return f"img/papers/{name}"
