"""Settings of the end-to-end run: one section per stage, each its package's own settings."""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from typing import Any, Literal

from uvms_jax import evo, hw, sched, surrogate
from uvms_jax import plan as planning

STAGES = ("docking", "surrogate", "plan", "schedule", "hw")


@dataclasses.dataclass(frozen=True)
class HwStageSettings:
    """The execution stage.

    Attributes:
      link: ``"loopback"`` (simulated arm in-process, virtual clock) or ``"udp"`` (simulated
        arm behind a UDP socket, real time).
      plan: a plan.json to execute instead of the scheduled plan (None: the schedule's).
      plot: write run.png.
      executor, sim: the executor's and the simulated arm's settings.
    """

    link: Literal["loopback", "udp"] = "loopback"
    plan: str | None = None
    plot: bool = True
    executor: hw.HwConfig = hw.HwConfig()
    sim: hw.SimConfig = hw.SimConfig()


@dataclasses.dataclass(frozen=True)
class PipelineSettings:
    """Every stage's settings.

    Attributes:
      seed: the seed of the schedule stage's keys (each stage's own settings carry theirs).
      stages: stages to run; they always run in data-flow order (:data:`STAGES`).
      docking, surrogate, plan, sched: the stages' settings.
      scenario: the scene (``plan.build_scene``'s mapping: tables, objects, bases, arm mount).
      sched_planner: whose metrics become the cost matrix (None: ``plan.planners[0]``).
      hw: the execution stage.
    """

    seed: int = 0
    stages: tuple[str, ...] = STAGES
    docking: evo.DockingSettings = evo.DockingSettings()
    surrogate: surrogate.SurrogateSettings = surrogate.SurrogateSettings()
    scenario: Mapping[str, Any] = dataclasses.field(default_factory=dict)
    plan: planning.PlanSettings = planning.PlanSettings()
    sched: sched.SchedSettings = sched.SchedSettings()
    sched_planner: str | None = None
    hw: HwStageSettings = HwStageSettings()

    def __post_init__(self) -> None:
        unknown = [s for s in self.stages if s not in STAGES]
        if unknown:
            raise ValueError(f"unknown stages {unknown}; choose from {list(STAGES)}")
        if "plan" in self.stages and not self.scenario:
            raise ValueError("the plan stage needs a scenario (tables, objects, bases, arm mount)")
