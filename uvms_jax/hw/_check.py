"""The dry-run check that guards the hardware runner: a ``plan.json`` (:mod:`uvms_jax.planfile`)
is refused for another arm than the one it runs on (:func:`check_arm`), and, with every problem
listed, for wrong joint names, malformed rows, non-finite values, times not starting at 0 or not
increasing, positions or jaws outside limits, gripper steps for an arm without a gripper,
discontinuities between segments, and average speeds between waypoints above the velocity limit.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence

import numpy as np

from uvms_jax.motion import synchronised_move
from uvms_jax.planfile import Plan, PlanError

from ._settings import ExecutorSettings
from ._joints import JointSpec, joint_specs

__all__ = ["PlanSummary", "check_arm", "check_plan", "specs_of"]

_SPEED_TOL = 1e-6  # relative slack on the average-speed check (JSON round-off of times)


@dataclasses.dataclass(frozen=True)
class PlanSummary:
    """What the dry run found for an accepted plan.

    Attributes:
      n_segments, n_waypoints, n_gripper_steps: counts.
      planned_s: sum of the planned times [s].
      estimated_s: sum of the synchronised move durations the executor will use [s]
        (gates and gripper moves not included).
      max_speed_ratio: largest average speed between waypoints over the velocity limit.
    """

    n_segments: int
    n_waypoints: int
    n_gripper_steps: int
    planned_s: float
    estimated_s: float
    max_speed_ratio: float


def specs_of(robot) -> tuple[JointSpec, ...]:
    """``(n + 1,)`` joint specs (arm joints, then the jaws; ``(n,)`` without a gripper) of a
    robot, or the specs themselves."""
    if isinstance(robot, Sequence) and all(isinstance(j, JointSpec) for j in robot):
        return tuple(robot)
    if hasattr(robot, "chain") and hasattr(robot, "record"):
        return joint_specs(robot)
    raise TypeError(f"expected a uvms_jax.robot.Robot or its joint specs, got {type(robot).__name__}")


def _describe(arm: dict) -> str:
    return f"{arm['name']!r} (joints {list(arm['joint_names'])}, sha256 {arm['sha256'][:12] or '-'})"


def check_arm(plan: Plan, robot) -> None:
    """Refuse a plan made for another arm: its ``arm`` record must name ``robot`` (same name,
    joint names and description digest); a plan without a record must have the robot's joint
    names.

    Raises:
      PlanError: (a ValueError) one line naming both arms.
    """
    mine = robot.record()
    if plan.arm is None:
        if tuple(plan.joint_names) != tuple(mine["joint_names"]):
            raise PlanError(f"plan joint_names {list(plan.joint_names)} must be those of arm {_describe(mine)} "
                            "(in this order; the plan has no arm record)")
        return
    if any(plan.arm[k] != mine[k] for k in ("name", "joint_names", "sha256")):
        raise PlanError(f"plan was made for arm {_describe(plan.arm)}, not for arm {_describe(mine)}")


def _time_problems(where: str, t: np.ndarray) -> list[str]:
    """A segment's times ``(k,)`` [s]: finite, from 0, increasing (the first problem only)."""
    if not len(t):
        return []
    if not np.all(np.isfinite(t)):
        return [f"{where}: non-finite time"]
    if t[0] != 0.0:
        return [f"{where}: t[0] = {t[0]} s, must be 0"]
    if np.any(np.diff(t) <= 0):
        k = int(np.argmax(np.diff(t) <= 0))
        return [f"{where}: times not increasing at waypoint {k}->{k + 1}"]
    return []


def _limit_problems(where: str, q: np.ndarray, joints) -> list[str]:
    """Every waypoint of ``q (k, n)`` [rad] whose joint is not finite or outside its limits."""
    problems = []
    for k, row in enumerate(q):
        for j, spec in enumerate(joints):
            if not math.isfinite(row[j]):
                problems.append(f"{where} waypoint {k}: joint {spec.name} is {row[j]}")
            elif not spec.contains(row[j]):
                problems.append(f"{where} waypoint {k}: joint {spec.name} = {row[j]:.4f} rad "
                                f"outside [{spec.lower}, {spec.upper}]")
    return problems


def _jaws_problems(where: str, jaws_mm: float, jaws) -> list[str]:
    """A gripper step to ``jaws_mm`` [mm]: the arm has jaws (``jaws``, their spec) and the
    opening is within their limits."""
    if jaws is None:
        return [f"{where}: a gripper step ({jaws_mm} mm), but the arm has no gripper"]
    if not (math.isfinite(jaws_mm) and jaws.contains(jaws_mm)):
        return [f"{where}: jaws {jaws_mm} mm outside [{jaws.lower}, {jaws.upper}]"]
    return []


def check_plan(
    plan: Plan,
    robot,
    config: ExecutorSettings = ExecutorSettings(),
    max_problems: int = 20,
) -> PlanSummary:
    """Dry-run check: refuse a bad plan before any motion.

    Args:
      plan: the plan (joint angles [rad], jaws [mm]).
      robot: the arm it is to run on (a :class:`uvms_jax.robot.Robot`, whose plan record is
        checked first, :func:`check_arm`), or its ``(n + 1,)`` joint specs (arm, then jaws;
        ``(n,)`` for an arm without a gripper, which refuses every gripper step).
      config: speed scale and continuity tolerance.
      max_problems: most problems listed.

    Raises:
      PlanError: a plan for another arm (one line), or listing (up to ``max_problems``) every
        limit, continuity, timing and speed problem, with segment, waypoint and joint named.
    """
    specs = specs_of(robot)
    if not isinstance(robot, Sequence):
        check_arm(plan, robot)
    joints, jaws = (specs[:-1], specs[-1]) if specs[-1].unit == "mm" else (specs, None)
    problems: list[str] = []
    names = tuple(j.name for j in joints)
    if plan.joint_names != names:
        raise PlanError(f"plan joint_names {list(plan.joint_names)} must be {list(names)} (in this order)")
    vmax = np.array([j.max_velocity for j in joints]) * config.speed_scale
    amax = np.array([j.max_acceleration for j in joints]) * config.speed_scale
    prev_q: np.ndarray | None = None
    planned = estimated = 0.0
    ratio = 0.0
    n_wp = n_grip = 0
    for i, seg in enumerate(plan.segments):
        where = f"segment {i} ({seg.name})"
        t = np.asarray(seg.t, dtype=float)
        q = np.asarray(seg.q, dtype=float).reshape(len(seg.q), len(names))
        n_wp += len(q)
        problems += _time_problems(where, t) + _limit_problems(where, q, joints)
        if len(q) and prev_q is not None and np.all(np.isfinite(q[0])):
            jump = np.abs(q[0] - prev_q)
            if np.max(jump) > config.continuity_tol_rad:
                j = int(np.argmax(jump))
                problems.append(f"{where}: starts {jump[j]:.4f} rad away from the previous segment's end "
                                f"on joint {names[j]} (tolerance {config.continuity_tol_rad})")
        if len(q) > 1 and np.all(np.isfinite(q)) and np.all(np.isfinite(t)) and np.all(np.diff(t) > 0):
            dt = np.diff(t)
            speed = np.abs(np.diff(q, axis=0)) / dt[:, None] / vmax
            ratio = max(ratio, float(np.max(speed)))
            if np.any(speed > 1 + _SPEED_TOL):
                k, j = np.unravel_index(int(np.argmax(speed)), speed.shape)
                problems.append(f"{where} waypoint {k}->{k + 1}: joint {names[j]} needs "
                                f"{speed[k, j] * vmax[j]:.3f} rad/s > limit {vmax[j]:.3f} rad/s")
            planned += float(t[-1])
            for k in range(len(q) - 1):
                estimated += synchronised_move(q[k], q[k + 1], vmax, amax, float(dt[k])).duration
        if len(q):
            prev_q = q[-1]
        if seg.jaws_mm is not None:
            n_grip += 1
            problems += _jaws_problems(where, seg.jaws_mm, jaws)
    if n_wp == 0:
        problems.append("plan has no waypoints: the start position is unknown")
    if problems:
        more = f"\n  … and {len(problems) - max_problems} more" if len(problems) > max_problems else ""
        raise PlanError("plan refused:\n  " + "\n  ".join(problems[:max_problems]) + more)
    return PlanSummary(len(plan.segments), n_wp, n_grip, planned, estimated, ratio)
