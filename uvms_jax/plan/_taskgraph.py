"""The planning stage: IK targets, then every task-graph edge with every configured planner.

:func:`plan_task_graph` returns everything in memory (no files): the targets, every planned
edge, the raw metric tensors for ``uvms_jax.sched`` and their cost matrices. A schedule over
those edges becomes a ``plan.json`` object with :func:`plan_for_schedule`. Files and figures
come from :mod:`uvms_jax.plan._write`.
"""

from __future__ import annotations

import dataclasses
import logging
import time
from collections.abc import Mapping, Sequence

import jax
import numpy as np

from uvms_jax import planfile, sched
from uvms_jax import progress as progress_lines
from uvms_jax.plan._collision import CollisionChecker
from uvms_jax.plan._planning import seed_ompl
from uvms_jax.plan._scene import Scene
from uvms_jax.plan._settings import PlanSettings
from uvms_jax.plan._spheres import SphereChecker
from uvms_jax.plan._targets import NodeTarget, pick_place_targets
from uvms_jax.plan._tasks import EdgeResult, metric_tensor, plan_edge, plan_from_edges, task_edges

__all__ = ["PlannerSummary", "TaskGraphPlan", "plan_for_schedule", "plan_task_graph"]

log = logging.getLogger(__name__)


@dataclasses.dataclass(frozen=True)
class PlannerSummary:
    """How one planner did over the task graph.

    Attributes:
      edges: edges attempted.
      success: edges planned (path found and re-checked with margin 0).
      revalidated: edges whose time-parameterised trajectory passed the re-check (collision-
        free, in limits, within the velocity limits).
      median_planning_time_s, mean_planning_time_s, max_planning_time_s: over all edges [s].
      max_speed_ratio: largest sampled |q̇| / velocity limit over the trajectories.
      shortcuts: edges whose path is the straight segment taken in place of the planner's
        (``PlanSettings.straight_shortcut``).
    """

    edges: int
    success: int
    revalidated: int
    median_planning_time_s: float
    mean_planning_time_s: float
    max_planning_time_s: float
    max_speed_ratio: float
    shortcuts: int = 0


@dataclasses.dataclass(frozen=True)
class TaskGraphPlan:
    """The task graph planned with every configured planner.

    Attributes:
      scene: the scene planned in.
      checker: its collision checker (its queries take their context as an argument).
      targets: node → :class:`NodeTarget` of every object and base.
      by_planner: planner → its :class:`EdgeResult` of every edge, in :func:`task_edges` order.
      metrics: planner → ``(5, N, N)`` raw metrics in ``uvms_jax.sched.METRICS`` order, NaN
        where the move is forbidden or failed (N = goal node + 1).
      costs: planner → ``(N, N)`` cost matrix of the settings' weights (thesis eqs.
        4.15–4.17), NaN = forbidden.
      summary: planner → :class:`PlannerSummary`.
      ik_seconds: wall time of the IK targets, XLA compilation included [s].
    """

    scene: Scene
    checker: CollisionChecker
    targets: Mapping[int, NodeTarget]
    by_planner: Mapping[str, tuple[EdgeResult, ...]]
    metrics: Mapping[str, np.ndarray]
    costs: Mapping[str, np.ndarray]
    summary: Mapping[str, PlannerSummary]
    ik_seconds: float


def _summarise(results: Sequence[EdgeResult]) -> PlannerSummary:
    times = np.array([r.plan.planning_time_s for r in results])
    return PlannerSummary(
        edges=len(results),
        success=int(sum(r.success for r in results)),
        revalidated=int(sum(r.revalidated for r in results)),
        median_planning_time_s=float(np.median(times)),
        mean_planning_time_s=float(times.mean()),
        max_planning_time_s=float(times.max()),
        max_speed_ratio=float(max((r.check.get("max_speed_ratio", 0.0) for r in results), default=0.0)),
        shortcuts=int(sum(r.plan.shortcut for r in results)),
    )


def plan_task_graph(key: jax.Array, scene: Scene, settings: PlanSettings = PlanSettings(),
                    progress: bool = True) -> TaskGraphPlan:
    """Solve the IK targets of every node, then plan every task-graph edge with every planner.

    Each edge is planned, time-parameterised, re-checked and measured by :func:`plan_edge`.
    Deterministic for a given key and seed up to OMPL's time budget (a planner that runs out
    of time fails differently on a slower machine).

    OMPL has one process-wide RNG that takes a seed only before any planner exists: this
    function calls :func:`seed_ompl` with ``settings.seed``, which seeds the first time in a
    process; a later call in the same process (a second run, a Hydra multirun with the basic
    launcher) continues the first run's random stream. Run one seed per process to reproduce
    a run exactly. IK is best in float64: enable ``jax_enable_x64`` before calling.

    Args:
      key: PRNG key of the IK seeds (the experiments use ``jax.random.PRNGKey(settings.seed)``).
      scene: from :func:`build_scene`.
      settings: planning settings.
      progress: show a progress bar per planner.

    Raises:
      ValueError: a node has no valid IK target pair, or an edge's end is invalid.
    """
    seed_ompl(settings.seed)
    checker = CollisionChecker(scene, margin=settings.margin, clearance_max=settings.clearance_max)
    t0 = time.perf_counter()
    targets = pick_place_targets(key, scene, checker, settings.ik, resolution=settings.recheck_resolution)
    ik_seconds = time.perf_counter() - t0
    log.info("IK targets for %d nodes in %.1f s (compilation included)", len(targets), ik_seconds)
    fast = SphereChecker(checker) if settings.checker == "spheres" else None
    edges = task_edges(scene)
    weights = settings.weight_vector()
    by_planner, metrics, costs, summary = {}, {}, {}, {}
    for planner in settings.planners:
        results = []
        bar = progress_lines.bar(edges, desc=f"plan {planner}", unit="edge") if progress else edges
        for src, dst in bar:
            r = plan_edge(scene, checker, targets, src, dst, planner, settings, fast=fast)
            results.append(r)
            log.debug("%s %d->%d success=%s revalidated=%s %.3f s", planner, src, dst, r.success, r.revalidated,
                      r.plan.planning_time_s)
        by_planner[planner] = tuple(results)
        metrics[planner] = metric_tensor(scene, results)
        costs[planner] = sched.cost_matrix(sched.normalise_metrics(metrics[planner]), weights)
        summary[planner] = _summarise(results)
        log.info("%s: %s", planner, summary[planner])
    return TaskGraphPlan(scene, checker, targets, by_planner, metrics, costs, summary, ik_seconds)


def plan_for_schedule(task_plan: TaskGraphPlan, planner: str, sequence: Sequence[int],
                      settings: PlanSettings = PlanSettings()) -> planfile.Plan:
    """The :class:`uvms_jax.planfile.Plan` of a schedule from ``planner``'s trajectories.

    The node's down/up motions are time-parameterised with ``settings.max_velocity`` and
    ``max_acceleration`` and checked for collisions; the jaw openings (an arm without a
    gripper: the dwells) come from ``settings.plan_json``. ``planfile.plan_to_dict`` gives the ``plan.json`` object.

    Args:
      task_plan: from :func:`plan_task_graph`.
      planner: one of ``task_plan.by_planner``.
      sequence: node sequence, e.g. a schedule's path ``[0, 2, 5, …, 9]``.
      settings: as given to :func:`plan_task_graph`.

    Raises:
      ValueError: the planner was not run, a move has no successful edge, or a down/up
        motion collides.
    """
    if planner not in task_plan.by_planner:
        raise ValueError(f"planner {planner!r} was not run (planned: {list(task_plan.by_planner)})")
    edges = {(r.src, r.dst): r for r in task_plan.by_planner[planner]}
    jp = settings.plan_json
    plan = plan_from_edges(task_plan.scene, task_plan.targets, edges, [int(v) for v in sequence],
                           jaws_open_mm=jp.jaws_open_mm, jaws_closed_mm=jp.jaws_closed_mm, dwell_s=jp.dwell_s,
                           max_velocity=settings.joint_velocity(task_plan.scene.robot), max_acceleration=settings.max_acceleration,
                           checker=task_plan.checker)
    return plan
