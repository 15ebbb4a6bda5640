"""The end-to-end run (``make demo``): one intervention with one arm under one vehicle.

surrogate → docking → planning → scheduling → execution (→ the hovering vehicle, the
fixed-mount baseline). Each stage is a module of :mod:`uvms_jax.pipeline.stages` that calls its
package's stage function (``surrogate.run_reach_map``, ``evo.run_docking`` and
``surrogate.dock_with_map``, ``plan.plan_task_graph``, ``sched.run_schedule``,
``hw.run_plan``, ``hover.execute_plan_hovering``) and writer and returns a
:class:`StageReport`; results pass between stages in memory: the docked pose puts the arm's
base into the planning scene (``plan.docked_scene``), the planning metrics become the cost
matrix, the winning schedule's plan is executed. :func:`run_pipeline` runs the configured
stages and writes ``summary.md`` (the chain at a glance, every stage's tables) and
``results.json``, after :func:`check_stages` has checked what every stage needs of the arm.
"""

from uvms_jax.pipeline import stages
from uvms_jax.pipeline._precheck import Checked
from uvms_jax.pipeline._precheck import baseline_scenario
from uvms_jax.pipeline._precheck import check_stages
from uvms_jax.pipeline._report import StageReport
from uvms_jax.pipeline._run import RETRY, RUN_FILES, run_pipeline
from uvms_jax.pipeline._settings import STAGES
from uvms_jax.pipeline._settings import HoverStageSettings
from uvms_jax.pipeline._settings import HwStageSettings
from uvms_jax.pipeline._settings import PipelineSettings

__all__ = ["RETRY", "RUN_FILES", "STAGES", "Checked", "HoverStageSettings", "HwStageSettings", "PipelineSettings", "StageReport", "baseline_scenario", "check_stages", "run_pipeline", "stages"]
