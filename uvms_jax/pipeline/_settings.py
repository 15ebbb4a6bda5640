"""Settings of the end-to-end run: one section per stage, each its package's own settings."""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from typing import Any, Literal

from uvms_jax import evo, hw, sched, surrogate
from uvms_jax import plan as planning
from uvms_jax.settings import setting

STAGES = ("surrogate", "docking", "plan", "schedule", "hw", "baseline")


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
    executor: hw.HwConfig = hw.HwConfig()
    sim: hw.SimConfig = hw.SimConfig()


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
        if "baseline" in self.stages and self.baseline is None:
            raise ValueError("the baseline stage needs a baseline scenario")
