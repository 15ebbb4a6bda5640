"""What the stages need of the run's arm, checked before the first stage (:func:`check_stages`):
a run that cannot finish is refused in one line (a :class:`~uvms_jax.settings.SettingsError`,
exit status 2 on the command line) instead of failing after minutes of docking and planning,
and a baseline that the arm cannot do from the fixed mount is skipped with the reason."""

from __future__ import annotations

import dataclasses
import logging
from typing import Any

import numpy as np

from uvms_jax import hw, planfile
from uvms_jax import plan as planning
from uvms_jax import robot as robots
from uvms_jax.pipeline._settings import PipelineSettings
from uvms_jax.settings import SettingsError

log = logging.getLogger(__name__)

# What a card adds for an arm without a gripper (docs/robots.md), for the messages.
GRIPPER_LINE = "gripper: {joint: jaws, lower: 0.0, upper: 0.1, velocity: 0.1}"


@dataclasses.dataclass(frozen=True)
class Checked:
    """What the checks found, for the stages.

    Attributes:
      robot: the run's arm (the scenario's); None without a scenario.
      gripper_steps: how the run's plans take their gripper steps
        (:func:`uvms_jax.plan.gripper_steps`); None without an arm.
      baseline_scene: the baseline stage's scene (the arm at the fixed mount with its start),
        built here; None where the baseline does not run or is skipped.
      baseline_skipped: why the baseline stage is skipped (the arm cannot do the task from
        the fixed mount), or None.
    """

    robot: robots.Robot | None = None
    gripper_steps: dict | None = None
    baseline_scene: planning.Scene | None = None
    baseline_skipped: str | None = None

    def arm_record(self) -> dict | None:
        """results.json's ``arm``: the robot's record and how it takes the gripper steps."""
        return None if self.robot is None else {**self.robot.record(), **self.gripper_steps}

    def log_findings(self, stages) -> None:
        """Say once what the run does differently for this arm (one log line each)."""
        gs = self.gripper_steps or {}
        if gs.get("gripper_steps") == "dwell" and {"plan", "schedule"} <= set(stages):
            log.info("arm %r has no gripper: each gripper step of the plan is a %g s dwell, the arm holding still "
                     "(plan.plan_json.dwell_s)", self.robot.name, gs["dwell_s"])
        if self.baseline_skipped is not None:
            log.warning("baseline stage skipped: %s", self.baseline_skipped)


def baseline_scenario(s: PipelineSettings) -> dict[str, Any]:
    """The baseline stage's scene: ``s.baseline`` (its tables, objects and fixed mount) with the
    run's arm (the scenario's) and the run's start (the scenario's ``start_q``; None: found at
    the fixed mount, as the plan stage finds it)."""
    arm = {k: v for k, v in s.scenario["arm"].items() if k not in planning.MOUNT_KEYS}
    mount = {k: v for k, v in (s.baseline.get("arm") or {}).items() if k in planning.MOUNT_KEYS}
    return {**s.baseline, "arm": {**arm, **mount}, "start_q": s.scenario.get("start_q")}


def vehicle_hull(scene) -> Any:
    """The docking scene's one hull box centred on the vehicle frame, as the hover stage models
    the vehicle; raises ValueError for any other vehicle."""
    hull = scene.vehicle_boxes[0]
    if len(scene.vehicle_boxes) != 1 or any(hull.pos) or any(hull.rpy):
        raise ValueError("the hover stage models the vehicle as one hull box centred on the vehicle frame; "
                         f"the docking scene has {[b.name for b in scene.vehicle_boxes]}")
    return hull


def check_stages(s: PipelineSettings) -> Checked:
    """Check what every configured stage needs of the run's arm, before any stage runs.

    Refused (every problem, in one line): a ``start_q`` of another length than the arm's
    joints; a runner stage (hw, hover) for an arm the runner cannot drive (prismatic joints), a
    plan whose jaw openings are outside the arm's gripper, or a plan file (``hw.plan``) made
    for another arm or with gripper steps for an arm without a gripper (the message names the
    card's ``gripper:`` line to add); a hover stage whose vehicle is not one hull box.

    An arm without a gripper takes its plans' gripper steps as dwells
    (:func:`uvms_jax.plan.gripper_steps`). The baseline (the same task from the fixed mount of
    ``s.baseline``, :func:`baseline_scenario`) is skipped, with the reason, when the arm cannot
    work there: no collision-free start, or a target beyond its reach.

    Raises:
      SettingsError: one line naming every problem.
    """
    robot = planning.scenario_robot(s.scenario) if s.scenario else None
    stages = set(s.stages)
    problems = []
    if robot is not None:
        if {"plan", "baseline"} & stages:
            problems += _start_problems(s.scenario.get("start_q"), robot)
        if {"hw", "hover"} & stages:
            problems += _runner_problems(s, robot)
    if "hover" in stages:
        try:
            vehicle_hull(s.docking.scene)
        except ValueError as e:
            problems.append(f"stages: {e}")
    if problems:
        raise SettingsError("; ".join(problems))
    if robot is None:
        return Checked()
    checked = Checked(robot, planning.gripper_steps(robot, s.plan.plan_json.dwell_s))
    if "baseline" in stages and s.baseline is not None:
        scene, why = _baseline_scene(s, robot)
        checked = dataclasses.replace(checked, baseline_scene=scene, baseline_skipped=why)
    return checked


def _start_problems(start_q, robot: robots.Robot) -> list[str]:
    if start_q is None or len(start_q) == robot.n_joints:
        return []
    return [f"scenario.start_q: {len(start_q)} values for the {robot.n_joints} joints of arm {robot.name!r} "
            f"({', '.join(robot.joint_names)}); null finds a start"]


def _runner_problems(s: PipelineSettings, robot: robots.Robot) -> list[str]:
    """What keeps the hw and hover stages from running the arm."""
    try:
        hw.joint_specs(robot)
    except ValueError as e:
        return [f"stages: the hw and hover stages cannot run arm {robot.name!r}: {e}"]
    g, jp = robot.gripper, s.plan.plan_json
    problems = []
    if g is not None and "plan" in s.stages:
        for key in ("jaws_open_mm", "jaws_closed_mm"):
            mm = getattr(jp, key)
            if not g.lower * 1e3 <= mm <= g.upper * 1e3:
                problems.append(f"plan.plan_json.{key}: {mm} mm is outside the travel [{g.lower * 1e3:g}, "
                                f"{g.upper * 1e3:g}] mm of arm {robot.name!r}'s gripper {g.joint!r}")
    if s.hw.plan is not None and "hw" in s.stages:
        problems += _plan_file_problems(s.hw.plan, robot, s.hw.executor)
    return problems


def _plan_file_problems(path: str, robot: robots.Robot, config: hw.ExecutorSettings) -> list[str]:
    """``hw.plan``: made for this arm, within its limits; gripper steps need a gripper."""
    try:
        the_plan = planfile.load_plan(path)
        hw.check_arm(the_plan, robot)
        if robot.gripper is None and any(seg.jaws_mm is not None for seg in the_plan.segments):
            return [f"hw.plan: {path} has gripper steps and arm {robot.name!r} has no gripper: add "
                    f"`{GRIPPER_LINE}` (its jaws) to the arm's card"]
        hw.check_plan(the_plan, robot, config)
    except planfile.PlanError as e:
        return [f"hw.plan: {' '.join(str(e).split())}"]
    return []


def _baseline_scene(s: PipelineSettings, robot: robots.Robot) -> tuple[planning.Scene | None, str | None]:
    """``(scene, None)`` of the baseline with the arm at the fixed mount, or ``(None, why)``
    when the arm cannot work there."""
    where = "from the fixed mount of the baseline scene"
    try:
        scene = planning.build_scene(robot, baseline_scenario(s))
    except ValueError as e:  # no collision-free start near the arm's home
        return None, f"arm {robot.name!r} cannot start {where}: {e}"
    checker = planning.CollisionChecker(scene, margin=s.plan.margin, clearance_max=s.plan.clearance_max)
    if not checker.is_valid(scene.start_q, planning.Context()):
        contact = checker.contacts(scene.start_q, planning.Context()) or "outside the limits"
        return None, (f"arm {robot.name!r}'s start {np.round(scene.start_q, 3).tolist()} is invalid {where}: "
                      f"{contact} (scenario.start_q=null finds one)")
    base = scene.T_world_base[:3, 3]
    for node in sorted(scene.objects) + sorted(scene.bases):
        at = planning.tool_poses(scene, node, s.plan.ik.n_yaw_continuous)[1]
        distance = float(np.min(np.linalg.norm(at[:, :3, 3] - base, axis=-1)))
        if distance > robot.max_reach:
            name = (scene.objects.get(node) or scene.bases[node]).name
            return None, (f"arm {robot.name!r} cannot reach node {node} ({name}) {where}: its grasp pose is "
                          f"{distance:.3f} m from the arm's base, beyond the arm's longest reach "
                          f"({robot.max_reach:.3f} m)")
    return scene, None
