"""The three papers: what they print, and the analysis that sets our numbers beside theirs.

This package's top level is data (NumPy only, no JAX), written once for the analysis and the
tests; no stage imports it (a stage's defaults are its own literals, and tests/papers compares
them with these tables):

- the transcribed tables and constants (``D11_*`` docking [D11], ``D16_*`` dexterity [D16],
  ``T22_*`` thesis [T22]; :mod:`uvms_jax.papers._data`);
- :class:`Preset` and :data:`PRESETS`, the sizes of one regeneration of docs/reproduction.md.

The analysis sits in submodules above every stage, imported by name (importing this package
does not import the stages): :mod:`uvms_jax.papers.docking` (Tables 3–4, the
bound on w, the readings, Figs 9–10 of [D11]), :mod:`uvms_jax.papers.docking_views` (its
Figs 5–8, 11 and 12–15: the arm at the corners and the final pose), :mod:`uvms_jax.papers.dexterity` (Tables 3–5
and the design figures of [D16]) and :mod:`uvms_jax.papers.thesis` (Tables 5.2–5.9, A.1–A.5,
Figs 5.8–5.12 of [T22]). Each ``*_fields`` function returns the placeholders of its section's
Markdown template (experiments/papers_templates/), which experiments/papers.py fills.
"""

from uvms_jax.papers._data import D11_ARM_LENGTHS
from uvms_jax.papers._data import D11_BLOCK_SIZE
from uvms_jax.papers._data import D11_ILL_PLACED_POSE
from uvms_jax.papers._data import D11_P_BP
from uvms_jax.papers._data import D11_P_INIT
from uvms_jax.papers._data import D11_TABLE3
from uvms_jax.papers._data import D11_TABLE4
from uvms_jax.papers._data import D11_TASK_SIZE
from uvms_jax.papers._data import D16_NETWORKS
from uvms_jax.papers._data import D16_TABLE3
from uvms_jax.papers._data import T22_PLANNER_TABLES
from uvms_jax.papers._data import T22_SCENARIO_TABLES
from uvms_jax.papers._data import T22_TABLES
from uvms_jax.papers._preset import PRESETS
from uvms_jax.papers._preset import Preset
from uvms_jax.papers._preset import join_and
