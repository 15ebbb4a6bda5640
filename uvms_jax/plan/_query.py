"""One planning query: a robot in a world, start → goal, a named planner and a hard budget.

:func:`plan_query` plans with the compiled sphere checker (:class:`~uvms_jax.plan.VectorChecker`):
``RRTConnect`` runs compiled end to end (:mod:`uvms_jax.plan._rrtc`), any other OMPL geometric
planner runs in OMPL with the same checker as its state and motion validator. The path is then
shortened within what is left of the budget, its segments made free for the spheres at
``check_resolution`` (re-planned where a finer sample hits), and — the last word — by MuJoCo with the robot's exact geometry (:class:`~uvms_jax.plan.ExactChecker`) at the
same samples. Times are reported per phase; the budget covers planning and simplification.
"""

from __future__ import annotations

import dataclasses
import time

import numpy as np

from uvms_jax.plan._collision import densify
from uvms_jax.plan._planners import joint_space, make_planner
from uvms_jax.plan._rrtc import FULL, SOLVED, TIMEOUT, rrt_connect, shortcut
from uvms_jax.plan._vector import VectorChecker, check_in_limits
from uvms_jax.plan._worlds import World
from uvms_jax.robot import Robot

__all__ = ["QueryResult", "plan_query"]

_OUTCOMES = {SOLVED: "solved", TIMEOUT: "timeout", FULL: "tree full"}
# Random shortcuts per query: on MotionBenchMaker problems five shorten paths nearly as much as
# ten (and most of what a hundred do) at a fraction of the checks.
_SHORTCUT_TRIES = 5


@dataclasses.dataclass(frozen=True)
class QueryResult:
    """Outcome of :func:`plan_query`.

    Attributes:
      success: a path was found, simplified and passed both checks.
      reason: ``"solved"``, ``"timeout"``, ``"tree full"``, ``"start in collision"``,
        ``"goal in collision"`` or ``"failed the exact check"`` (the spheres did not contain
        the geometry: a defect of the sphere model).
      path: ``(k, n)`` waypoints [rad] from start to goal (empty unless ``success``).
      plan_s: planning wall time [s]; simplify_s: shortcutting and the re-planning of segments
        that fail at ``check_resolution`` [s]; exact_s: MuJoCo's check of the path densified
        to ``check_resolution`` [s] (0 when not run).
      iterations: planner iterations (0: the straight motion was free).
      exact_contacts: contacts MuJoCo found on the path (name pairs), empty when it passed.
    """

    success: bool
    reason: str
    path: np.ndarray
    plan_s: float = 0.0
    simplify_s: float = 0.0
    exact_s: float = 0.0
    iterations: int = 0
    exact_contacts: tuple[tuple[str, str], ...] = ()

    @property
    def time_s(self) -> float:
        """Planning and simplification [s]: the budgeted part."""
        return self.plan_s + self.simplify_s


def _ompl_path(checker: VectorChecker, start, goal, planner: str, deadline: float, resolution: float, seed: int):
    """Plan with an OMPL planner on the sphere checker; ``(path or None, iterations = 0)``."""
    from ompl import base as ob

    from uvms_jax.plan._planning import seed_ompl

    seed_ompl(seed)
    n = len(start)
    space, ss, si = joint_space(checker.lower, checker.upper)
    ss.setStateValidityChecker(lambda s: checker.state_free(s[0:n]))

    class Motions(ob.MotionValidator):
        def checkMotion(self, s1, s2) -> bool:  # noqa: N802 — OMPL's name
            return checker.motion_free(np.array(s1[0:n]), np.array(s2[0:n]), resolution)

    validator = Motions(si)
    si.setMotionValidator(validator)
    ss.setPlanner(make_planner(planner, si, None))
    a, b = space.allocState(), space.allocState()
    a[0:n], b[0:n] = list(start), list(goal)
    ss.setStartAndGoalStates(a, b)
    solved = ss.solve(max(0.0, deadline - time.perf_counter()))
    path = None
    if solved and ss.haveExactSolutionPath():
        path = np.array([[s[i] for i in range(n)] for s in ss.getSolutionPath().getStates()])
    del ss, si, validator
    return path


def _repair(checker: VectorChecker, path: np.ndarray, resolution: float, step: float, max_nodes: int,
            deadline: float, seed: int) -> tuple[np.ndarray, str]:
    """The path with every segment free at the final ``resolution`` [rad]: a segment that the
    planner's coarser checks passed but a finer sample hits is re-planned at ``resolution``
    (compiled RRT-Connect between its ends, then shortcut) within the same deadline. All
    samples are first checked in one threaded call: most paths pass whole."""
    if checker.states_free(densify(path, resolution)[1:]).all():  # the samples motion_free visits
        return path, "solved"
    out = [path[:1]]
    for a, b in zip(path[:-1], path[1:]):
        if checker.motion_free(a, b, resolution):
            out.append(b[None])
            continue
        piece, outcome, _ = rrt_connect(a, b, checker.lower, checker.upper, float(step), float(resolution),
                                        int(max_nodes), deadline, int(seed), checker.model)
        if outcome != SOLVED:
            return path, _OUTCOMES[int(outcome)]
        out.append(shortcut(piece, float(resolution), deadline, _SHORTCUT_TRIES, int(seed), checker.model)[1:])
    return np.concatenate(out), "solved"


def plan_query(robot: Robot, world: World, start, goal, *, planner: str = "RRTConnect", budget_s: float = 1.0,
               opening: float | None = None, resolution: float = 0.05, check_resolution: float = 0.01,
               step: float = 0.5, seed: int = 0, margin: float = 0.0, exact: bool = True,
               checker: VectorChecker | None = None, max_nodes: int = 1 << 15) -> QueryResult:
    """Plan a collision-free joint path ``start → goal`` for ``robot`` in ``world``.

    Args:
      robot, world: the robot and its world (obstacles in the robot's base frame).
      start, goal: ``(n,)`` joint values [rad or m], within the limits up to
        :data:`~uvms_jax.plan.LIMIT_TOL` (an error names the joint, its value and its limit).
      planner: ``"RRTConnect"`` (compiled) or any OMPL geometric planner's name.
      budget_s: wall time for planning and simplification together [s], hard.
      opening: the gripper joint's value the fingers hold [m] (default: its largest).
      resolution: motion-check step while planning [rad]; check_resolution: the step of the
        final checks (spheres, then MuJoCo) [rad]: a segment that fails it is re-planned at it.
      step: RRT-Connect's largest tree extension [rad] (0.5: of 0.2 … 2 rad, the shortest median
        and p95 times on a sample of the MotionBenchMaker problems).
      seed: the sampler's seed.
      margin: safety distance of the sphere checks [m].
      exact: run MuJoCo's check of the final path (recommended; off only to time the planner).
      checker: a :class:`VectorChecker` of this robot, world, opening and margin to reuse.
      max_nodes: capacity of each RRT-Connect tree.
    """
    if not (np.isfinite(budget_s) and budget_s > 0):
        raise ValueError(f"budget_s must be a finite number > 0 [s], got {budget_s}")
    for label, v in (("resolution", resolution), ("check_resolution", check_resolution), ("step", step)):
        if not (np.isfinite(v) and v > 0):
            raise ValueError(f"{label} must be a finite number > 0 [rad], got {v}")
    t0 = time.perf_counter()
    deadline = t0 + budget_s
    start = np.clip(check_in_limits(robot, start, "start"), robot.lower, robot.upper)  # within LIMIT_TOL
    goal = np.clip(check_in_limits(robot, goal, "goal"), robot.lower, robot.upper)
    if checker is None:
        checker = VectorChecker(robot, world, opening, margin)
    n = robot.n_joints
    free = checker.states_free(np.stack([start, goal]))
    if not free.all():
        return QueryResult(False, "start in collision" if not free[0] else "goal in collision", np.zeros((0, n)))
    t0 = time.perf_counter()
    if planner == "RRTConnect":
        path, outcome, iterations = rrt_connect(start, goal, checker.lower, checker.upper, float(step),
                                                float(resolution), int(max_nodes), deadline, int(seed),
                                                checker.model)
        reason = _OUTCOMES[int(outcome)]
    else:
        path, iterations = _ompl_path(checker, start, goal, planner, deadline, resolution, seed), 0
        reason = "solved" if path is not None else "timeout"
    t1 = time.perf_counter()
    if reason != "solved":
        return QueryResult(False, reason, np.zeros((0, n)), plan_s=t1 - t0, iterations=int(iterations))
    path = shortcut(path, float(resolution), deadline, _SHORTCUT_TRIES, int(seed), checker.model)
    path, reason = _repair(checker, path, check_resolution, step, max_nodes, deadline, seed)
    t2 = time.perf_counter()
    if reason != "solved":
        return QueryResult(False, reason, np.zeros((0, n)), plan_s=t1 - t0, simplify_s=t2 - t1,
                           iterations=int(iterations))
    contacts: tuple = ()
    if exact:  # every segment is free at check_resolution for the spheres: MuJoCo has the last word
        found = checker.exact.contacts(densify(path, check_resolution))
        contacts = tuple(sorted({(a, b) for _, a, b, _ in found}))
    t3 = time.perf_counter()
    times = dict(plan_s=t1 - t0, simplify_s=t2 - t1, exact_s=t3 - t2 if exact else 0.0, iterations=int(iterations))
    if contacts:
        return QueryResult(False, "failed the exact check", np.zeros((0, n)), exact_contacts=contacts, **times)
    return QueryResult(True, "solved", path, **times)
