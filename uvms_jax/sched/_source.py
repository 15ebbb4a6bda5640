"""Where a scheduling problem comes from: a ready cost matrix, synthetic metrics, a planner's
``edges.csv``, or the planning stage's metrics in memory (thesis 4.7.4, docs/theory.md §5)."""

from __future__ import annotations

import csv
from dataclasses import dataclass
from pathlib import Path
from typing import Literal, Mapping, NamedTuple, Sequence

import jax
import numpy as np

from uvms_jax.sched._costs import EDGE_CSV_COLUMNS, METRICS, cost_matrix, metric_tensor, mirror_goal
from uvms_jax.sched._costs import normalise_metrics
from uvms_jax.sched._problem import PickPlaceProblem
from uvms_jax.sched._random import random_metrics
from uvms_jax.sched._thesis import THESIS_COMPAT, THESIS_EQ41
from uvms_jax.settings import setting


@dataclass(frozen=True)
class WeightSettings:
    """The five metric weights ``K`` (configs/sched/weights/*.yaml; default thesis Table 4.3),
    each ≥ 0."""

    name: str = "equal"
    planning_time: float = setting(0.2, ge=0)
    joint_movement: float = setting(0.2, ge=0)
    ee_distance: float = setting(0.2, ge=0)
    security: float = setting(0.2, ge=0)
    max_torque: float = setting(0.2, ge=0)

    def values(self) -> tuple[float, ...]:
        """``(5,)`` weights in ``METRICS`` order."""
        return tuple(float(getattr(self, m)) for m in METRICS)


@dataclass(frozen=True)
class SourceSettings:
    """Where the costs come from (configs/sched/source/*.yaml); each kind reads its own keys.

    Attributes:
      kind: ``"matrix"`` (a ready cost matrix, weights unused), ``"synthetic"``
        (``random_metrics`` on the thesis graph) or ``"edges_csv"`` (a planner's edges.csv).
      matrix: ``"thesis_eq41"`` (built in) or the path of an existing ``n × n`` .csv/.npy
        matrix (relative: to the working directory).
      path: an existing edges.csv (``edges_csv``; relative: to the working directory).
      planner: rows of this planner only (``edges_csv``).
      n_nodes: ≥ 1; ``None``: the largest node index + 1 (``edges_csv``).
      seed, object_mass_kg: synthetic metrics (``synthetic``; mass ≥ 0 [kg]).
      compat: object node → allowed base nodes; ``None``: the thesis's.
      start: start node (≥ 0); goal: goal node (≥ 0; ``None``: the last node).
      mirror_goal: moves into the goal missing → use the moves into the start (``edges_csv``).
    """

    kind: Literal["matrix", "synthetic", "edges_csv"] = "matrix"
    matrix: str = setting("thesis_eq41", choices=("thesis_eq41",), file=True)
    path: str | None = setting(None, file=True)
    planner: str = "RRTConnect"
    n_nodes: int | None = setting(None, ge=1)
    seed: int = 0
    object_mass_kg: float = setting(0.5, ge=0)
    compat: Mapping[int, tuple[int, ...]] | None = None
    start: int = setting(0, ge=0)
    goal: int | None = setting(None, ge=0)
    mirror_goal: bool = True


class Source(NamedTuple):
    """A loaded source: ``problem``; ``normalised`` ``(5, n, n)`` metrics or ``None`` for a
    ready matrix; ``note`` says where it came from."""

    problem: PickPlaceProblem
    normalised: np.ndarray | None
    note: str


def read_edges_csv(path: Path, planner: str, n_nodes: int | None = None) -> np.ndarray:
    """Raw ``(5, n, n)`` metrics (``METRICS`` order) from a planner's ``edges.csv``.

    Rows of other planners are skipped; failed plans (``success`` not true) become NaN.

    Raises:
      ValueError: no row for ``planner``, or bad edges (see ``metric_tensor``).
    """
    with open(path, newline="") as f:
        rows = [r for r in csv.DictReader(f) if r["planner"] == planner]
    if not rows:
        raise ValueError(f"{path}: no rows for planner {planner!r}")
    src = np.array([int(r["src"]) for r in rows])
    dst = np.array([int(r["dst"]) for r in rows])
    ok = np.array([r["success"].strip().lower() in ("1", "true", "yes") for r in rows])
    vals = np.array([[float(r[c]) if r[c] not in ("", "nan") else np.nan for c in EDGE_CSV_COLUMNS] for r in rows])
    vals[~ok] = np.nan
    n = int(max(src.max(), dst.max()) + 1) if n_nodes is None else int(n_nodes)
    return metric_tensor(src, dst, vals, n)


def problem_from_metrics(
    raw_metrics,
    compat: Mapping[int, Sequence[int]] | None = None,
    start: int = 0,
    goal: int | None = None,
    weights: Sequence[float] | WeightSettings = WeightSettings(),
    mirror_goal_moves: bool = True,
) -> tuple[PickPlaceProblem, np.ndarray]:
    """Raw per-move metrics → ``(problem, normalised metrics)`` (eqs. 4.15–4.17).

    Args:
      raw_metrics: ``(5, n, n)`` raw metrics in ``METRICS`` order, NaN = no move.
      compat: object node → allowed base nodes; ``None``: the thesis's.
      start, goal: nodes (goal ``None``: the last node).
      weights: 5 weights in ``METRICS`` order, or ``WeightSettings``.
      mirror_goal_moves: copy the moves into the start to the goal where those are missing
        (the thesis's goal is the start position, Table 5.1).
    """
    raw = np.asarray(raw_metrics, dtype=np.float64)
    if raw.ndim != 3:
        raise ValueError(f"metrics must have shape ({len(METRICS)}, n, n); got {raw.shape}")
    goal = raw.shape[1] - 1 if goal is None else goal
    if mirror_goal_moves:
        raw = mirror_goal(raw, start, goal)
    w = weights.values() if isinstance(weights, WeightSettings) else weights
    nm = normalise_metrics(raw)
    compat = THESIS_COMPAT if compat is None else compat
    return PickPlaceProblem.from_matrix(cost_matrix(nm, w), compat, start, goal), nm


def load_source(
    source: SourceSettings,
    weights: Sequence[float] | WeightSettings = WeightSettings(),
    root: Path | None = None,
) -> Source:
    """The problem of ``source``.

    Args:
      source: the source settings.
      weights: 5 weights in ``METRICS`` order, or ``WeightSettings`` (unused by a matrix).
      root: directory that relative file paths start from (default: the working directory).

    Raises:
      ValueError: an unknown kind, a missing path, or bad data (see ``from_matrix``).
    """
    w = weights.values() if isinstance(weights, WeightSettings) else tuple(weights)
    compat = THESIS_COMPAT if source.compat is None else {int(k): tuple(v) for k, v in source.compat.items()}
    if source.kind == "matrix":
        if source.matrix == "thesis_eq41":
            cost = np.array(THESIS_EQ41)
        else:
            path = _resolve(source.matrix, root)
            cost = np.load(path) if path.suffix == ".npy" else np.genfromtxt(path, delimiter=",")
        problem = PickPlaceProblem.from_matrix(cost, compat, start=source.start, goal=source.goal)
        return Source(problem, None, "ready cost matrix: weights not used")
    if source.kind == "synthetic":
        layout = PickPlaceProblem.from_matrix(_full_graph(compat), compat)
        raw = random_metrics(jax.random.key(source.seed), layout, object_mass_kg=source.object_mass_kg)
        nm = normalise_metrics(raw)
        problem = PickPlaceProblem.from_matrix(cost_matrix(nm, w), compat)
        return Source(problem, nm, f"synthetic metrics (seed {source.seed})")
    if source.kind == "edges_csv":
        if not source.path:
            raise ValueError("sched source edges_csv needs a path to the planner's edges.csv")
        raw = read_edges_csv(_resolve(source.path, root), source.planner, source.n_nodes)
        problem, nm = problem_from_metrics(raw, compat, source.start, source.goal, w, source.mirror_goal)
        return Source(problem, nm, f"{source.path} ({source.planner})")
    raise ValueError(f"unknown sched source kind {source.kind!r}: use matrix, synthetic or edges_csv")


def _full_graph(compat) -> np.ndarray:
    """A placeholder matrix (all moves 1) that only fixes the node layout."""
    n = 2 + len(compat) + len({b for bs in compat.values() for b in bs})
    return np.ones((n, n))


def _resolve(path: str, root: Path | None) -> Path:
    p = Path(path)
    return p if root is None or p.is_absolute() else Path(root) / p
