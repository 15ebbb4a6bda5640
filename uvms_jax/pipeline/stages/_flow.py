"""What the stages hand to one another in memory (:class:`Flow`), the little they share, and
the intervention at a glance (:func:`chain`, the head of ``summary.md``)."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np

from uvms_jax import evo, planfile, surrogate
from uvms_jax import plan as planning
from uvms_jax import robot as robots
from uvms_jax.pipeline._report import StageReport
from uvms_jax.pipeline._settings import PipelineSettings

__all__ = ["VIDEO_FPS", "VIDEO_SIZE", "Flow", "chain", "docking_problem", "film_scene", "rounded"]

# hw/run.mp4: the ~92 s demo run → ~730 frames, 22–25 s of software (Mesa) rendering on 2 cores.
VIDEO_FPS = 8.0
VIDEO_SIZE = (480, 360)  # width, height [pixels]


@dataclasses.dataclass
class Flow:
    """What a stage hands to the later ones, in memory.

    Attributes:
      robot: the arm of every stage (the scenario's).
      task: the scenario's grasp and place poses and tables, as the docking stage's task.
      problem: the docking problem of the arm on its vehicle over the scenario's task.
      reach: the surrogate stage's learned map.
      pose: the docking stage's vehicle pose ``(4,)`` [m, rad]; T_world_vehicle, T_world_base:
        ``(4, 4)`` the vehicle and the arm's base there.
      scene_spec: the planning scene (the scenario with the arm under the docked vehicle).
      scene: the planning scene built already, else None: the plan stage builds it from
        ``scene_spec``.
      baseline_scene, baseline_skipped: the baseline's scene (the arm at the fixed mount),
        built by the checks before the first stage, or why the baseline stage is skipped
        (:func:`~uvms_jax.pipeline.check_stages`).
      task_plan, plan, plan_source: planning → schedule → execution.
      reports: the reports of the stages run so far, by name.
    """

    robot: robots.Robot | None = None
    task: evo.ArmTask | None = None
    problem: evo.ArmDockingProblem | None = None
    reach: surrogate.ReachMapRun | None = None
    pose: np.ndarray | None = None
    T_world_vehicle: np.ndarray | None = None
    T_world_base: np.ndarray | None = None
    scene_spec: planning.SceneSpec | None = None
    scene: planning.Scene | None = None
    baseline_scene: planning.Scene | None = None
    baseline_skipped: str | None = None
    task_plan: planning.TaskGraphPlan | None = None
    plan: planfile.Plan | None = None
    plan_source: str = ""
    reports: dict[str, StageReport] = dataclasses.field(default_factory=dict)


def rounded(p) -> list[float]:
    """A pose or a point as a list of floats rounded to the millimetre (no ``-0.0``)."""
    return [round(float(v), 3) + 0.0 for v in p]


def docking_problem(s: PipelineSettings, flow: Flow) -> evo.ArmDockingProblem:
    """The arm-on-vehicle docking problem over the scenario's grasp and place poses (built once)."""
    if flow.problem is None:
        flow.task = planning.docking_task(planning.build_scene(flow.robot, s.scenario), vehicle=s.docking.scene,
                                          margin=s.plan.margin)
        flow.problem = evo.docking_problem(s.docking.scene, s.docking.dtype, flow.task, flow.robot)
    return flow.problem


def film_scene(s: PipelineSettings, flow: Flow) -> planning.Scene | None:
    """The scene the videos of the hw and hover stages are drawn in: the planning stage's, else
    the scenario's (the example plan was planned in the thesis cage of
    ``configs/scenario/thesis_cage.yaml``), else None."""
    if flow.task_plan is not None:
        return flow.task_plan.scene
    return planning.build_scene(flow.robot, s.scenario) if s.scenario else None


def chain(flow: Flow, out: Path) -> str:
    """The intervention at a glance (markdown): pose → base in the scene → schedule → run, and
    the planning stage's picture of the scene (``out/plan/scene.png``)."""
    r = {k: v.results for k, v in flow.reports.items()}
    steps = []
    if "docking" in r:
        d = r["docking"]
        steps.append(f"**dock** the vehicle at x, y, z, ψ = {rounded(d['pose'])} ({d['pose_source']}, M_a "
                     f"{d['pose_M_a']:.4f})")
    if "plan" in r:
        steps.append(f"**arm base** in the planning scene at {r['plan']['base_xyz']} m; "
                     + ", ".join(f"{k.removesuffix('_success')} {v} edges" for k, v in r["plan"].items()
                                 if k.endswith("_success")))
    if "schedule" in r:
        steps.append(f"**schedule** {r['schedule']['winner_path']} ({r['schedule']['winner']}, cost "
                     f"{r['schedule']['winner_cost']:.4f})")
    if "hw" in r:
        h = r["hw"]
        steps.append(f"**run** on the simulated {flow.robot.name}: {h.get('reason')}, {h.get('gates')} gates, "
                     f"{h.get('duration_s')} s")
    picture = out / "plan" / "scene.png"
    return " → ".join(steps) + ("\n\n![the arm in the planning scene](plan/scene.png)" if picture.exists() else "")
