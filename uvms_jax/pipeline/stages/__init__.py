"""The pipeline's stages, one module each; every module's ``run(settings, out, flow)`` calls its
package's stage function and writer and returns the stage's :class:`~uvms_jax.pipeline.StageReport`
(its tables and notes in ``summary.md``, its key figures in ``results.json``).

- :mod:`.surrogate`: ``surrogate.run_reach_map``, the arm's dexterity map on its vehicle;
- :mod:`.docking`: ``evo.run_docking`` (and ``surrogate.dock_with_map``); its pose puts the
  arm's base into the planning scene (``plan.docked_scene``);
- :mod:`.plan`: ``plan.plan_task_graph``, a motion plan of every task-graph edge;
- :mod:`.schedule`: ``sched.run_schedule`` on the planning metrics, the winner's plan;
- :mod:`.execute`: the hw stage, ``hw.run_plan`` on the simulated arm;
- :mod:`.hover`: the plan on the hovering vehicle (``uvms_jax.hover``);
- :mod:`.baseline`: plan, schedule and hw again from the thesis's fixed mount.

:class:`Flow` carries what a stage hands to the later ones, in memory; :func:`chain` is the
intervention at a glance; :data:`STAGE_FNS` maps
each stage's name (``uvms_jax.pipeline.STAGES``) to its ``run``.
"""

from uvms_jax.pipeline.stages import baseline
from uvms_jax.pipeline.stages import docking
from uvms_jax.pipeline.stages import execute
from uvms_jax.pipeline.stages import hover
from uvms_jax.pipeline.stages import plan
from uvms_jax.pipeline.stages import schedule
from uvms_jax.pipeline.stages import surrogate
from uvms_jax.pipeline.stages._flow import Flow, chain

STAGE_FNS = {"surrogate": surrogate.run, "docking": docking.run, "plan": plan.run, "schedule": schedule.run,
             "hw": execute.run, "hover": hover.run, "baseline": baseline.run}

__all__ = ["STAGE_FNS", "Flow", "chain", "baseline", "docking", "execute", "hover", "plan", "schedule", "surrogate"]
