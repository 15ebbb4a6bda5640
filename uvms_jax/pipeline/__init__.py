"""The end-to-end run (``make demo``): docking → surrogates → planning → scheduling → execution.

Each stage is its package's stage function (``evo.run_docking``, ``surrogate.run_surrogates``,
``plan.plan_task_graph``, ``sched.run_schedule``, ``hw.run_plan``) followed by its writer;
results pass between stages in memory. :func:`run_pipeline` runs the configured stages and
writes ``summary.md`` (every stage's tables beside the papers') and ``results.json``.
"""

from uvms_jax.pipeline._report import StageReport
from uvms_jax.pipeline._report import md_table
from uvms_jax.pipeline._run import run_pipeline
from uvms_jax.pipeline._settings import STAGES
from uvms_jax.pipeline._settings import HwStageSettings
from uvms_jax.pipeline._settings import PipelineSettings

__all__ = ["STAGES", "HwStageSettings", "PipelineSettings", "StageReport", "md_table", "run_pipeline"]
