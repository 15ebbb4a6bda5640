"""OMPL planning over the six arm joints, and trajectories.

A plan is: ``solve`` (RRTConnect, BKPIECE1, PRM or any other OMPL geometric planner, with its
parameters) within a time budget; ``simplifySolution`` (or, with the straight-segment shortcut,
the straight segment when it is free); then a check of the path at ``recheck_resolution`` [rad] with MuJoCo and
the true geometry (margin 0). States are checked with MuJoCo; motions either by OMPL state by
state (MuJoCo, ``resolution``) or by one :class:`~uvms_jax.plan.SphereChecker` call each,
sampled like the re-check. The planner works with the checker's safety margin, so the re-check
passes unless OMPL's own motion checks skipped a thin obstacle (with the sphere checker it
passes by construction). A path that fails the re-check is re-planned while budget is left.
Time parameterisation follows the arm's controller (thesis 4.6,
:func:`uvms_jax.motion.synchronised_move`): rest to rest between consecutive waypoints, all
joints arriving together, within the velocity and acceleration limits.
"""
from __future__ import annotations

import dataclasses
import logging
import time
from collections.abc import Mapping
from typing import Any

import numpy as np
from ompl import base as ob
from ompl import util as ou

from uvms_jax.motion import synchronised_move
from uvms_jax.plan._collision import CollisionChecker, densify
from uvms_jax.plan._planners import check_parameters, joint_space, make_planner
from uvms_jax.plan._scene import Context
from uvms_jax.plan._spheres import SphereChecker

__all__ = ["PLANNERS", "PlanResult", "Trajectory", "check_ends", "plan_motion", "seed_ompl", "time_parameterize"]

PLANNERS = ("RRTConnect", "BKPIECE1", "PRM")  # the thesis's three (any of ompl_planners() works)
# Planners that can grow trees from the valid part of a rejected motion (OMPL's checkMotion
# with ``lastValid``). The Python bindings never fill ``lastValid`` from a Python motion
# validator: with the sphere checker these planners drop a rejected motion whole (as OMPL does
# for a valid part shorter than ``min_valid_path_fraction``); on the thesis task graph that
# halves BKPIECE1's planning time against OMPL's state-by-state MuJoCo checks, every edge solved.
PARTIAL_MOTIONS = ("KPIECE1", "BKPIECE1", "LBKPIECE1")
log = logging.getLogger(__name__)
_ompl_seed: int | None = None  # the seed OMPL's process-wide RNG took, None before seed_ompl


def seed_ompl(seed: int) -> None:
    """Seed OMPL's process-wide RNG with ``seed + 1`` (OMPL refuses 0) and silence its logging.

    OMPL takes a seed only before any planner or sampler exists in the process; later seeds
    are refused. So the first call seeds, a repeated call with the same seed does nothing, and
    a call with another seed logs a warning and leaves OMPL on the first seed's stream (one
    seed per process reproduces a run; Hydra's basic launcher runs a multirun in one process).
    """
    global _ompl_seed
    if seed < 0:
        raise ValueError(f"seed must be >= 0, got {seed}")
    ou.setLogLevel(ou.LogLevel.LOG_WARN)
    if _ompl_seed is None:
        ou.RNG.setSeed(int(seed) + 1)
        _ompl_seed = int(seed)
    elif seed != _ompl_seed:
        log.warning("OMPL was seeded with %d in this process; seed %d is not applied (one seed per process)",
                    _ompl_seed, seed)


@dataclasses.dataclass(frozen=True)
class PlanResult:
    """Outcome of one planning query.

    Attributes:
      success: a path was found and passed the dense re-check with margin 0.
      path: ``(k, n)`` simplified waypoints [rad] (empty when not successful).
      planning_time_s: wall time of solve + simplify over all attempts [s].
      attempts: solve calls made.
      shortcut: the path is the straight segment, taken in place of the planner's own
        (``straight_shortcut``).
    """

    success: bool
    path: np.ndarray
    planning_time_s: float
    attempts: int
    shortcut: bool = False


@dataclasses.dataclass(frozen=True)
class Trajectory:
    """A time-parameterised joint path: waypoints and the times the arm reaches them.

    Attributes:
      t: ``(k,)`` waypoint times [s], t[0] = 0.
      q: ``(k, n)`` waypoints [rad].
      max_velocity, max_acceleration: ``(n,)`` limits used [rad/s, rad/s²].
    """

    t: np.ndarray
    q: np.ndarray
    max_velocity: np.ndarray
    max_acceleration: np.ndarray

    def sample(self, dt: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Positions and velocities every ``dt`` [s] (and at every waypoint): ``t (m,)``,
        ``q (m, n)``, ``qd (m, n)``."""
        ts, qs, vs = [], [], []
        for i in range(len(self.t) - 1):
            mv = synchronised_move(self.q[i], self.q[i + 1], self.max_velocity, self.max_acceleration,
                                   self.t[i + 1] - self.t[i])
            n = max(2, int(np.ceil(mv.duration / dt)) + 1)
            for tau in np.linspace(0.0, mv.duration, n)[(1 if i else 0):]:
                q, v = mv.sample(tau)
                ts.append(self.t[i] + tau)
                qs.append(q)
                vs.append(v)
        if not ts:
            return np.zeros(1), self.q[:1].copy(), np.zeros_like(self.q[:1])
        return np.array(ts), np.array(qs), np.array(vs)


def time_parameterize(path, max_velocity, max_acceleration) -> Trajectory:
    """Times of a waypoint path for a controller that stops at every waypoint and makes all
    joints arrive together (thesis 4.6): each leg is the shortest synchronised trapezoidal
    move within the limits.

    Args:
      path: ``(k, n)`` waypoints [rad].
      max_velocity, max_acceleration: ``(n,)`` positive limits [rad/s, rad/s²].
    """
    path = np.asarray(path, dtype=float)
    v = np.broadcast_to(np.asarray(max_velocity, dtype=float), path.shape[1:]).copy()
    a = np.broadcast_to(np.asarray(max_acceleration, dtype=float), path.shape[1:]).copy()
    t = [0.0]
    for q0, q1 in zip(path[:-1], path[1:]):
        t.append(t[-1] + synchronised_move(q0, q1, v, a).duration)
    return Trajectory(np.array(t), path, v, a)


class _SegmentValidator(ob.MotionValidator):
    """OMPL motion validator checking a whole segment in one :class:`SphereChecker` call, in
    the context of its planning query (bound once)."""

    def __init__(self, si, fast: SphereChecker, context: Context, resolution: float, n: int):
        super().__init__(si)
        self._motion_is_valid = fast.motion_is_valid
        self._context, self._resolution, self._n = context, resolution, n

    def checkMotion(self, s1, s2) -> bool:  # noqa: N802 — OMPL's name
        n = self._n
        return self._motion_is_valid(s1[0:n], s2[0:n], self._context, self._resolution)


def check_ends(checker: CollisionChecker, q_start, q_goal, context: Context) -> tuple[np.ndarray, np.ndarray]:
    """``q_start``, ``q_goal`` ``(n,)`` [rad] as float arrays, both valid in ``context`` with the
    checker's safety margin; a ValueError naming the contacts (or the limits) otherwise."""
    q_start, q_goal = np.asarray(q_start, dtype=float), np.asarray(q_goal, dtype=float)
    for label, q in (("start", q_start), ("goal", q_goal)):
        if not checker.is_valid(q, context):
            raise ValueError(f"{label} {np.round(q, 4).tolist()} is invalid: "
                             f"{checker.contacts(q, context) or 'outside the limits'}")
    return q_start, q_goal


def _query_setup(checker: CollisionChecker, context: Context, planner: str, params, resolutions: tuple[float, float],
                 fast: SphereChecker | None, ends: tuple[np.ndarray, np.ndarray]) -> tuple:
    """OMPL's ``SimpleSetup`` of one query (:func:`plan_motion`'s arguments): the joint space,
    MuJoCo's state checks at ``resolutions[0]`` [rad], ``fast``'s motion checks at
    ``resolutions[1]`` [rad] when given, the planner and the start and goal states. Returns
    ``(ss, si, validator, (space, start, goal))``: the caller keeps them while OMPL plans."""
    resolution, recheck_resolution = resolutions
    n = len(ends[0])
    space, ss, si = joint_space(checker.lower, checker.upper)
    # States: MuJoCo (one call per state is what it is fastest at). Motions: OMPL's state-by-
    # state checks, or one SphereChecker call per motion.
    ss.setStateValidityChecker(checker.state_validator(n, context))
    si.setStateValidityCheckingResolution(resolution / space.getMaximumExtent())
    validator = None
    if fast is not None:
        if fast.reference is not checker:
            raise ValueError("fast must be a SphereChecker built on the given checker")
        fast._pairs(context)  # the context's pair tables (built once, ~2 ms): now, not in the timed solve
        validator = _SegmentValidator(si, fast, context, recheck_resolution, n)
        si.setMotionValidator(validator)
    ss.setPlanner(make_planner(planner, si, params))
    start, goal = space.allocState(), space.allocState()
    start[0:n] = ends[0].tolist()
    goal[0:n] = ends[1].tolist()
    ss.setStartAndGoalStates(start, goal)
    return ss, si, validator, (space, start, goal)


def plan_motion(
    checker: CollisionChecker,
    q_start,
    q_goal,
    context: Context,
    planner: str = "RRTConnect",
    budget_s: float = 5.0,
    resolution: float = 0.02,
    recheck_resolution: float = 0.01,
    simplify_s: float = 0.2,
    fast: SphereChecker | None = None,
    params: Mapping[str, Any] | None = None,
    straight_shortcut: bool = False,
) -> PlanResult:
    """Plan a collision-free joint path from ``q_start`` to ``q_goal`` in ``context``.

    Args:
      checker: collision checker of the scene.
      q_start, q_goal: ``(n,)`` joint angles [rad]; both must be valid in ``context``.
      context: the :class:`~uvms_jax.plan.Context` of the whole query (held object, ignored
        obstacles): bound once into OMPL's state and motion validators and the re-check, so
        every check of the query is in it whatever other queries did to the checker.
      planner: any OMPL geometric planner (:func:`ompl_planners`), e.g. the thesis's
        ``RRTConnect``, ``BKPIECE1`` or ``PRM``.
      budget_s: total planning time allowed for this query, all attempts together [s].
      resolution: planner's motion-check step [rad] (converted to OMPL's fraction of the
        space's extent).
      recheck_resolution: joint step of the re-check of the result [rad].
      simplify_s: time given to path simplification per attempt [s].
      fast: a :class:`SphereChecker` on ``checker``: it checks whole motions (MuJoCo confirms
        its rejections), sampled at ``recheck_resolution`` like the re-check (planners of
        :data:`PARTIAL_MOTIONS` then get no partial motions). None: OMPL checks motions state
        by state with MuJoCo at ``resolution``.
      params: the planner's parameters (:func:`planner_parameters`), e.g. ``{"range": 1.0}``.
      straight_shortcut: once the planner has a path, return the straight segment instead
        whenever it is free (one motion check, where simplification would shortcut its way
        there): fast, but every planner then returns the same path wherever the straight
        segment is free. False: the planner's path, simplified.

    Raises:
      ValueError: unknown planner or parameter (the valid ones are listed), or an invalid
        start or goal (the contacts are named).
    """
    ou.setLogLevel(ou.LogLevel.LOG_WARN)
    if not isinstance(context, Context):  # e.g. a planner name where the context goes
        raise TypeError(f"context must be a plan.Context, got {context!r}")
    check_parameters(planner, params or {})
    q_start, q_goal = check_ends(checker, q_start, q_goal, context)
    n = len(q_start)
    ss, si, validator, (space, start, goal) = _query_setup(checker, context, planner, params, (resolution, recheck_resolution),
                                                    fast, (q_start, q_goal))
    spent, attempts = 0.0, 0
    result = PlanResult(False, np.zeros((0, n)), 0.0, 0)
    while spent < budget_s:
        t0 = time.perf_counter()
        solved = ss.solve(budget_s - spent)
        exact = bool(solved) and ss.haveExactSolutionPath()
        shortcut = False
        if exact:
            if straight_shortcut and ss.getSolutionPath().getStateCount() > 2 and si.checkMotion(start, goal):
                path, shortcut = np.stack([q_start, q_goal]), True
            else:
                ss.simplifySolution(simplify_s)
                path = np.array([[s[i] for i in range(n)] for s in ss.getSolutionPath().getStates()])
        spent += time.perf_counter() - t0
        attempts += 1
        if not exact:
            break
        path[0], path[-1] = q_start, q_goal
        ok = checker.path_is_valid(path, context, recheck_resolution, margin=0.0)
        result = PlanResult(ok, path if ok else np.zeros((0, n)), spent, attempts, shortcut and ok)
        if ok:
            break
        ss.clear()
    del ss, si, validator, space
    return dataclasses.replace(result, planning_time_s=spent, attempts=attempts)


def check_trajectory(checker: CollisionChecker, traj: Trajectory, context: Context, resolution: float = 0.01,
                     collision_free: bool | None = None) -> dict[str, bool | float]:
    """Re-check a trajectory: every point of a ``resolution`` [rad] interpolation is
    collision-free (margin 0) and inside the joint limits, and no joint exceeds its velocity
    limit.

    Args:
      checker: the reference checker.
      traj: the trajectory.
      context: the trajectory's :class:`~uvms_jax.plan.Context`.
      resolution: joint step of the interpolation [rad].
      collision_free: the result of that same check when the caller already has it (e.g.
        :func:`plan_motion`'s re-check of the same waypoints at the same resolution); None
        runs it.

    Returns:
      ``collision_free``, ``in_limits``, ``within_velocity`` (bools) and ``max_speed_ratio``:
      the largest joint speed over its limit, at the cruise speed of each leg (the peak of
      its trapezoidal scaling, ``ṡ = 1/((1 − f)T)``, see :mod:`uvms_jax.motion`).
    """
    dense = densify(traj.q, resolution)
    inside = bool(np.all((dense >= checker.lower) & (dense <= checker.upper)))
    if collision_free is None:
        collision_free = bool(np.all(checker.is_valid_batch(dense, context, margin=0.0)))
    ratio = 0.0
    for i in range(len(traj.t) - 1):
        mv = synchronised_move(traj.q[i], traj.q[i + 1], traj.max_velocity, traj.max_acceleration,
                               traj.t[i + 1] - traj.t[i])
        if mv.duration > 0:
            peak = np.abs(mv.q1 - mv.q0) / ((1.0 - mv.accel_fraction) * mv.duration)
            ratio = max(ratio, float(np.max(peak / traj.max_velocity)))
    return {"collision_free": bool(collision_free), "in_limits": inside, "within_velocity": ratio <= 1.0 + 1e-6,
            "max_speed_ratio": ratio}
