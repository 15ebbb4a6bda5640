"""Settings of the end-to-end run: one section per stage, each its package's own settings."""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from typing import Any, Literal

from uvms_jax import evo, hover, hw, sched, surrogate
from uvms_jax import plan as planning
from uvms_jax.settings import setting

STAGES = ("surrogate", "docking", "plan", "schedule", "hw", "hover", "baseline")


@dataclasses.dataclass(frozen=True)
class HwStageSettings:
    """The execution stage.

    Attributes:
      link: ``"loopback"`` (simulated arm in-process, virtual clock) or ``"udp"`` (simulated
        arm behind a UDP socket, real time).
      plan: an existing plan.json to execute instead of the scheduled plan (None: the
        schedule's); relative: to the working directory.
      plot: write run.png.
      executor, sim: the executor's and the simulated arm's settings.
    """

    link: Literal["loopback", "udp"] = "loopback"
    plan: str | None = setting(None, file=True)
    plot: bool = True
    executor: hw.ExecutorSettings = hw.ExecutorSettings()
    sim: hw.SimSettings = hw.SimSettings()


@dataclasses.dataclass(frozen=True)
class HoverStageSettings:
    """The hover stage: the scheduled plan executed over BPL with the vehicle hovering at the
    docked pose (:func:`uvms_jax.hover.run_hover`: the hw stage's executor and settings on the
    simulated arm mounted on the vehicle), in still water and in ``current``.

    Attributes:
      current: the water's velocity in the world frame [m/s]; (0, 0, 0): still water only.
      vehicle: hull mass, water, thrusters (its hull box and arm mount are the docking scene's).
      controller: the station keeping on (x, y, z, ψ), and the control period (the executor's
        tick with the whole-body controller).
      tool_tolerance_m: a gate counts as kept by the tool when it is within this of where the
        docked arm holds it [m].
      coordinate: also run the current with the whole-body controller (``whole_body``: the tool
        on its docked path first, station keeping in that task's null space) between the
        executor's plan and the arm; its gates are judged on the tool's pose, within
        ``tool_tolerance_m`` and ``tool_tolerance_deg`` [°].
      navigation: the whole-body controller sees the vehicle's pose through this navigation
        (rate, latency, noise; :class:`uvms_jax.hover.NavigationSettings`), or exactly (None).
      frame_png: also write the video's frame at the gate of the largest tool error here (with
        ``hw.plot``; relative: to the working directory), e.g. ``docs/img/hover_frame.png``.
    """

    current: tuple[float, float, float] = (0.0, 0.0, 0.0)
    vehicle: hover.VehicleSettings = hover.VehicleSettings()
    controller: hover.ControllerSettings = hover.ControllerSettings()
    tool_tolerance_m: float = setting(0.01, gt=0)
    coordinate: bool = True
    whole_body: hover.WholeBodySettings = hover.WholeBodySettings()
    navigation: hover.NavigationSettings | None = None
    tool_tolerance_deg: float = setting(2.0, gt=0)
    frame_png: str | None = None


@dataclasses.dataclass(frozen=True)
class PipelineSettings:
    """Every stage's settings.

    Attributes:
      seed: the seed of the schedule stage's and the map GA's keys (each stage's own settings
        carry theirs).
      stages: stages to run; they always run in data-flow order (:data:`STAGES`).
      reach: the surrogate stage (the arm's learned dexterity map on its vehicle).
      docking: the docking stage: an arm scene (``evo.ArmSceneSettings``) whose task is the
        scenario's grasp and place poses.
      docking_fitness: whose GA pose goes on to planning: ``"analytic"`` or ``"surrogate"``
        (the GA on the learned map; needs the surrogate stage).
      plan, sched: the stages' settings.
      scenario: the scene (``plan.build_scene``'s mapping: tables, objects, bases, and ``arm``:
        the arm, :func:`uvms_jax.plan.scenario_robot`, and its mount; the docking stage
        replaces the mount by the docked vehicle's). Every stage uses this one arm.
      baseline: the baseline stage's scenario (the thesis's fixed mount), or None; the arm is
        the scenario's (the baseline's ``arm`` gives only the mount).
      sched_planner: whose metrics become the cost matrix (None: ``plan.planners[0]``).
      hw: the execution stage.
      hover: the hover stage (the docked pose held on thrusters instead).
    """

    seed: int = 0
    stages: tuple[str, ...] = STAGES
    reach: surrogate.ReachMapSettings = surrogate.ReachMapSettings()
    docking: evo.DockingSettings = evo.DockingSettings()
    docking_fitness: Literal["analytic", "surrogate"] = "analytic"
    scenario: Mapping[str, Any] = dataclasses.field(default_factory=dict)
    baseline: Mapping[str, Any] | None = None
    plan: planning.PlanSettings = planning.PlanSettings()
    sched: sched.SchedSettings = sched.SchedSettings()
    sched_planner: str | None = None
    hw: HwStageSettings = HwStageSettings()
    hover: HoverStageSettings = HoverStageSettings()

    def __post_init__(self) -> None:
        unknown = [s for s in self.stages if s not in STAGES]
        if unknown:
            raise ValueError(f"unknown stages {unknown}; choose from {list(STAGES)}")
        if {"plan", "docking", "surrogate"} & set(self.stages) and not self.scenario:
            raise ValueError("the surrogate, docking and plan stages need a scenario (tables, objects, bases, arm mount)")
        if {"docking", "surrogate"} & set(self.stages) and not isinstance(self.docking.scene, evo.ArmSceneSettings):
            raise ValueError("the docking and surrogate stages dock an arm: docking.scene must be an arm scene "
                             "(configs/docking/scene/); the paper's scene: experiments/docking.py")
        if self.docking_fitness == "surrogate" and "surrogate" not in self.stages:
            raise ValueError("docking_fitness=surrogate needs the surrogate stage")
        if "hover" in self.stages and not {"docking", "schedule"} <= set(self.stages):
            raise ValueError("the hover stage needs the docking and schedule stages (a docked pose and a plan)")
        if "baseline" in self.stages and self.baseline is None:
            raise ValueError("the baseline stage needs a baseline scenario")
        # The scenes against the scenario schema (SettingsError naming the key), before any stage.
        if self.scenario:
            planning.SceneSpec.from_mapping(self.scenario, "scenario")
        if self.baseline is not None:
            planning.SceneSpec.from_mapping(self.baseline, "baseline")
