"""Pick-and-place scheduling (thesis ch. 4–5, docs/theory.md §5).

Build a ``PickPlaceProblem`` (from a ready cost matrix, or from per-edge metrics through
``normalise_metrics`` and ``cost_matrix``), then solve it with ``greedy`` (the thesis's
"Dijkstra"), ``grasp`` (all iterations in one jitted call), ``astar`` (thesis heuristic,
optimal) or ``exact`` (dynamic programming, the ground truth); ``score`` checks and costs a
batch of schedules in one jitted call. Example::

    from uvms_jax import sched
    problem = sched.thesis_problem()          # eq. 4.1 matrix, Table 5.1 nodes
    sched.greedy(problem).path_str()          # '0-2-5-4-8-0-1-6-3-7-9'
    best = sched.exact(problem)
    sched.schedule_edges(problem, best.path)  # moves to plan and execute

The move rules live in one place (``_rules.allowed_next``). The stage as a whole:
``run_schedule(key, SchedSettings(...))`` → ``ScheduleRun`` → ``write_schedule(run, out)``.
The stage runs the solvers named in its settings from the registry ``SOLVERS``; a new solver is
one ``register_solver(name, run, label=..., line=...)`` call (``Solver``).
"""

from uvms_jax.sched._astar import astar
from uvms_jax.sched._costs import EDGE_CSV_COLUMNS
from uvms_jax.sched._costs import HIGHER_IS_BETTER
from uvms_jax.sched._costs import METRICS
from uvms_jax.sched._costs import cost_matrix
from uvms_jax.sched._costs import metric_tensor
from uvms_jax.sched._costs import mirror_goal
from uvms_jax.sched._costs import normalise_metrics
from uvms_jax.sched._costs import path_metric_sums
from uvms_jax.sched._costs import path_totals
from uvms_jax.sched._edges import ScheduleEdge
from uvms_jax.sched._edges import schedule_edges
from uvms_jax.sched._exact import exact
from uvms_jax.sched._greedy import greedy
from uvms_jax.sched._grasp import DEFAULT_ROUNDS as GRASP_ROUNDS
from uvms_jax.sched._grasp import LOCAL_SEARCHES
from uvms_jax.sched._grasp import THESIS_ALPHAS
from uvms_jax.sched._grasp import THESIS_NEIGHBOURHOOD
from uvms_jax.sched._grasp import GraspBatch
from uvms_jax.sched._grasp import GraspOptions
from uvms_jax.sched._grasp import grasp
from uvms_jax.sched._grasp import grasp_batch
from uvms_jax.sched._grasp import thesis_local_search
from uvms_jax.sched._problem import PAD_NODE
from uvms_jax.sched._problem import PickPlaceProblem
from uvms_jax.sched._problem import as_padded_paths
from uvms_jax.sched._problem import path_cost
from uvms_jax.sched._random import random_metrics
from uvms_jax.sched._random import random_problem
from uvms_jax.sched._schedule import Schedule
from uvms_jax.sched._source import Source
from uvms_jax.sched._source import SourceSettings
from uvms_jax.sched._source import WeightSettings
from uvms_jax.sched._source import load_source
from uvms_jax.sched._source import problem_from_metrics
from uvms_jax.sched._source import read_edges_csv
from uvms_jax.sched._solvers import SOLVERS
from uvms_jax.sched._solvers import Solver
from uvms_jax.sched._solvers import register_solver
from uvms_jax.sched._stage import GraspSettings
from uvms_jax.sched._stage import SchedSettings
from uvms_jax.sched._stage import ScheduleRun
from uvms_jax.sched._stage import SweepPoint
from uvms_jax.sched._stage import grasp_sweep
from uvms_jax.sched._stage import run_schedule
from uvms_jax.sched._stage import solve
from uvms_jax.sched._stage import solve_all
from uvms_jax.sched._stage import table_rows
from uvms_jax.sched._score import Reason
from uvms_jax.sched._score import Scores
from uvms_jax.sched._score import score
from uvms_jax.sched._thesis import THESIS_COMPAT
from uvms_jax.sched._thesis import THESIS_EQ41
from uvms_jax.sched._thesis import THESIS_EQ41_GREEDY_PATH
from uvms_jax.sched._thesis import THESIS_NODE_NAMES
from uvms_jax.sched._thesis import THESIS_SOLVER_MS
from uvms_jax.sched._thesis import thesis_problem
from uvms_jax.sched._write import schedule_results
from uvms_jax.sched._write import write_schedule

__all__ = [
    "EDGE_CSV_COLUMNS",
    "GRASP_ROUNDS",
    "HIGHER_IS_BETTER",
    "LOCAL_SEARCHES",
    "METRICS",
    "PAD_NODE",
    "SOLVERS",
    "THESIS_ALPHAS",
    "THESIS_COMPAT",
    "THESIS_EQ41",
    "THESIS_EQ41_GREEDY_PATH",
    "THESIS_NEIGHBOURHOOD",
    "THESIS_NODE_NAMES",
    "THESIS_SOLVER_MS",
    "GraspBatch",
    "GraspOptions",
    "GraspSettings",
    "PickPlaceProblem",
    "Reason",
    "SchedSettings",
    "Schedule",
    "ScheduleEdge",
    "ScheduleRun",
    "Scores",
    "Solver",
    "Source",
    "SourceSettings",
    "SweepPoint",
    "WeightSettings",
    "as_padded_paths",
    "astar",
    "cost_matrix",
    "exact",
    "grasp",
    "grasp_batch",
    "grasp_sweep",
    "greedy",
    "load_source",
    "metric_tensor",
    "mirror_goal",
    "normalise_metrics",
    "path_cost",
    "path_metric_sums",
    "path_totals",
    "problem_from_metrics",
    "random_metrics",
    "random_problem",
    "read_edges_csv",
    "register_solver",
    "run_schedule",
    "schedule_edges",
    "schedule_results",
    "score",
    "solve",
    "solve_all",
    "table_rows",
    "thesis_local_search",
    "thesis_problem",
    "write_schedule",
]
