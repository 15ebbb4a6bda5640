"""The scheduling stage: solvers by name, timed comparisons, the GRASP sweep, one whole run.

``run_schedule`` is what the Hydra experiment (``experiments/schedule.py``) and the
end-to-end pipeline call; ``write_schedule`` (``_write.py``) turns its result into files.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping, Sequence

import jax
import numpy as np

from uvms_jax.sched._costs import METRICS, path_metric_sums
from uvms_jax.sched._grasp import DEFAULT_ROUNDS, LOCAL_SEARCHES, THESIS_ALPHAS, THESIS_NEIGHBOURHOOD, grasp
from uvms_jax.sched._problem import PickPlaceProblem
from uvms_jax.sched._schedule import Schedule
from uvms_jax.sched._solvers import SOLVERS
from uvms_jax.sched._source import SourceSettings, WeightSettings, load_source, problem_from_metrics
from uvms_jax.settings import setting

log = logging.getLogger(__name__)

@dataclass(frozen=True)
class GraspSettings:
    """GRASP settings (``sched.grasp`` of configs/schedule.yaml); ``None``: the default.

    Attributes:
      iterations: GRASP iterations, ≥ 1 (thesis 5.3: 1000).
      alphas: α values, each in [0, 1] (``None``: thesis eq. 4.6, ``THESIS_ALPHAS``).
      neighbourhood: local-search neighbourhood, ≥ 1 (``None``: thesis 4.7.2.2, three).
      rounds: local-search rounds, ≥ 0 (``None``: ``GRASP_ROUNDS``).
      local_search: ``"deliveries"`` (ours, default) or ``"thesis"`` (Algorithm 4: node swaps).
    """

    iterations: int = setting(1000, ge=1)
    alphas: tuple[float, ...] | None = setting(None, ge=0, le=1)
    neighbourhood: int | None = setting(None, ge=1)
    rounds: int | None = setting(None, ge=0)
    local_search: str = setting("deliveries", choices=LOCAL_SEARCHES)

    def kwargs(self, iterations: int | None = None) -> dict[str, Any]:
        """Keyword arguments of ``grasp`` (``iterations`` overrides the setting)."""
        return {
            "iterations": int(iterations or self.iterations),
            "alphas": THESIS_ALPHAS if self.alphas is None else tuple(float(a) for a in self.alphas),
            "neighbourhood": THESIS_NEIGHBOURHOOD if self.neighbourhood is None else int(self.neighbourhood),
            "rounds": DEFAULT_ROUNDS if self.rounds is None else int(self.rounds),
            "local_search": self.local_search,
        }


@dataclass(frozen=True)
class SchedSettings:
    """The ``sched:`` section of configs/schedule.yaml (with its source and weights groups).

    Attributes:
      source: where the costs come from (default: the thesis's eq. 4.1 matrix).
      weights: metric weights (default: thesis Table 4.3, all 1/5).
      solvers: solver names, keys of ``SOLVERS`` (default: those built in).
      grasp: GRASP settings.
      timing_repeats: each solver is timed this often (median reported), after a warm-up; ≥ 1.
      iterations_sweep: GRASP iteration counts of the sweep (thesis Figs 5.9–5.12), each ≥ 1;
        empty: none.
      sweep_repeats: GRASP runs (different keys) per sweep point, ≥ 1.
      plots: whether ``write_schedule`` draws the figures.
    """

    source: SourceSettings = field(default_factory=SourceSettings)
    weights: WeightSettings = field(default_factory=WeightSettings)
    solvers: tuple[str, ...] = setting(tuple(SOLVERS), choices=SOLVERS)
    grasp: GraspSettings = field(default_factory=GraspSettings)
    timing_repeats: int = setting(20, ge=1)
    iterations_sweep: tuple[int, ...] = setting((1, 10, 50, 100, 250, 500, 1000, 2000, 3000), ge=1)
    sweep_repeats: int = setting(10, ge=1)
    plots: bool = True

    def __post_init__(self):
        if not self.solvers:
            raise ValueError(f"solvers: name at least one of {list(SOLVERS)}")


@dataclass(frozen=True)
class SweepPoint:
    """GRASP at one iteration count: schedule cost over the repeats (mean, min, max) and the
    median wall time [ms]."""

    iterations: int
    cost_mean: float
    cost_min: float
    cost_max: float
    time_ms: float


@dataclass(frozen=True)
class ScheduleRun:
    """One scheduling run (``run_schedule``).

    Attributes:
      problem: the instance solved.
      normalised: ``(5, n, n)`` normalised metrics, or ``None`` for a ready cost matrix.
      note: where the costs came from.
      weights: the weights (used only when ``weights_used``).
      solved: solver name → its schedule (wall time: median over the timing repeats).
      best: the cheapest schedule of ``solved`` (the exact one on a tie).
      rows: per solver, the table row (solver, path, cost, time_ms, then ``K_<metric>`` and
        ``N_<metric>`` for each metric: weight and normalised sum along the schedule).
      sweep: GRASP sweep points (empty when no sweep was asked for).
      weights_used: whether the costs came from metrics (so the weights matter).
      optimal_cost: the exact solver's cost, or ``None`` when it was not run.
    """

    problem: PickPlaceProblem
    normalised: np.ndarray | None
    note: str
    weights: WeightSettings
    solved: Mapping[str, Schedule]
    best: Schedule
    rows: tuple[dict, ...]
    sweep: tuple[SweepPoint, ...]
    weights_used: bool
    optimal_cost: float | None


def solve(
    key: jax.Array,
    problem: PickPlaceProblem,
    solver: str,
    grasp_settings: GraspSettings = GraspSettings(),
) -> Schedule:
    """Solves ``problem`` with the solver registered as ``solver`` (``key``: for randomised
    solvers such as GRASP).

    Raises:
      ValueError: no solver of that name is registered.
    """
    if solver not in SOLVERS:
        raise ValueError(f"unknown solver {solver!r}; choose from {list(SOLVERS)}")
    return SOLVERS[solver].run(key, problem, grasp_settings.kwargs())


def solve_all(key: jax.Array, problem: PickPlaceProblem, settings: SchedSettings) -> dict[str, Schedule]:
    """Each solver of ``settings.solvers``, timed ``timing_repeats`` times after a warm-up.

    Run ``i`` uses the ``i``-th key of ``jax.random.split(key, timing_repeats)``; the
    schedule returned is the first run's, its ``wall_time_s`` the median over the runs.
    """
    for name in settings.solvers:
        if name not in SOLVERS:
            raise ValueError(f"unknown solver {name!r}; choose from {list(SOLVERS)}")
    if settings.timing_repeats < 1:
        raise ValueError(f"timing_repeats must be >= 1; got {settings.timing_repeats}")
    out = {}
    for name in settings.solvers:
        solve(key, problem, name, settings.grasp)  # warm-up (GRASP compiles here)
        runs = [solve(k, problem, name, settings.grasp) for k in jax.random.split(key, settings.timing_repeats)]
        first = runs[0]
        t = float(np.median([r.wall_time_s for r in runs]))
        out[name] = Schedule(first.path, first.cost, t, name, dict(first.info))
        log.info("%-6s %-28s cost %.4f  %.4f ms", name, first.path_str(), first.cost, t * 1e3)
    return out


def grasp_sweep(key: jax.Array, problem: PickPlaceProblem, settings: SchedSettings) -> list[SweepPoint]:
    """GRASP cost (mean, min, max over ``sweep_repeats`` keys) and median time per
    iteration count of ``settings.iterations_sweep`` (thesis Figs 5.9–5.12)."""
    points = []
    for it in settings.iterations_sweep:
        kw = settings.grasp.kwargs(it)
        grasp(key, problem, **kw)  # compile this iteration count
        keys = jax.random.split(jax.random.fold_in(key, it), settings.sweep_repeats)
        runs = [grasp(k, problem, **kw) for k in keys]
        costs = [r.cost for r in runs]
        points.append(SweepPoint(
            iterations=int(it),
            cost_mean=float(np.mean(costs)),
            cost_min=float(np.min(costs)),
            cost_max=float(np.max(costs)),
            time_ms=float(np.median([r.wall_time_s for r in runs]) * 1e3),
        ))
        p = points[-1]
        log.info("GRASP %5d it: cost %.4f (min %.4f)  %.3f ms", it, p.cost_mean, p.cost_min, p.time_ms)
    return points


def table_rows(solved: Mapping[str, Schedule], normalised, weights: WeightSettings) -> list[dict]:
    """Per solver, the thesis Table 5.2 row: path, cost, time [ms], and per metric its weight
    ``K_<metric>`` and normalised sum ``N_<metric>`` along the schedule (NaN without metrics)."""
    rows = []
    for name, s in solved.items():
        row = {"solver": name, "path": s.path_str(), "cost": s.cost, "time_ms": s.wall_time_s * 1e3}
        feasible = normalised is not None and s.feasible
        sums = path_metric_sums(normalised, s.path) if feasible else [math.nan] * len(METRICS)
        for m, k, v in zip(METRICS, weights.values(), sums):
            row[f"K_{m}"] = k
            row[f"N_{m}"] = float(v)
        rows.append(row)
    return rows


def run_schedule(
    key: jax.Array,
    settings: SchedSettings = SchedSettings(),
    raw_metrics=None,
    *,
    note: str = "planner metrics",
    root: Path | None = None,
    compat: Mapping[int, Sequence[int]] | None = None,
) -> ScheduleRun:
    """The scheduling stage: source → problem → every solver (timed) → GRASP sweep.

    Args:
      key: PRNG key (GRASP runs).
      settings: the stage settings.
      raw_metrics: ``(5, n, n)`` raw per-move metrics (``METRICS`` order, NaN = no move), e.g.
        from the planning stage; they replace ``settings.source``'s costs (its compat, start,
        goal and mirror_goal still apply). ``None``: load ``settings.source``.
      note: the source note when ``raw_metrics`` is given.
      root: directory that the source's relative file paths start from (default: the
        working directory).
      compat: object node → the base nodes it fits, with ``raw_metrics`` (e.g. the planning
        scene's); None: the source's.
    """
    src, weights = settings.source, settings.weights
    if raw_metrics is None:
        problem, nm, note = load_source(src, weights, root)
    else:
        problem, nm = problem_from_metrics(raw_metrics, src.compat if compat is None else compat, src.start,
                                           src.goal, weights, src.mirror_goal)
    if nm is None:
        log.info("%s; the weights %s are ignored", note, weights.name)
    solved = solve_all(key, problem, settings)
    # The exact solution wins ties: it is the reference the other solvers are measured against.
    best = min(solved.values(), key=lambda s: (s.cost, s.solver != "exact"))
    sweep = grasp_sweep(key, problem, settings) if settings.iterations_sweep else []
    return ScheduleRun(
        problem=problem,
        normalised=nm,
        note=note,
        weights=weights,
        solved=solved,
        best=best,
        rows=tuple(table_rows(solved, nm, weights)),
        sweep=tuple(sweep),
        weights_used=nm is not None,
        optimal_cost=solved["exact"].cost if "exact" in solved else None,
    )
