"""Docking-pose optimisation (docs/theory.md §3; Sotiropoulos, Aspragathos & Andritsos 2011).

The docking problem (area manipulability M_a, eq. 1; distance D, eq. 3; fitness eq. 15 over
the search set Wd, eq. 14; its terms a registry, :func:`register_fitness_term`, summed behind
the :class:`Problem` protocol), the paper's binary GA (Table 2) as pure ``init/ask/tell``
functions with whole runs in one jitted loop, a chunked dense grid search and CMA-ES
(evosax) as baselines, and the ``w_max`` map of eq. 16. The same optimisers dock any arm
under a vehicle (:class:`ArmDockingProblem`: targets as tool poses, batched multi-seed
numerical IK checked for limits and collisions in the planner's world, :class:`SphereWorld`;
docs/docking.md). :func:`run_docking` is the
whole docking experiment as one stage (settings in, :class:`DockingRun` out) and
:func:`write_docking` writes its files and figures.
"""

from uvms_jax.evo._arm import ArmDockingProblem
from uvms_jax.evo._arm import ArmReport
from uvms_jax.evo._arm import arm_report
from uvms_jax.evo._arm import arm_solutions
from uvms_jax.evo._arm import arm_terms
from uvms_jax.evo._arm import arm_tool_poses
from uvms_jax.evo._arm import arm_solutions_jit
from uvms_jax.evo._arm import evaluate_arm
from uvms_jax.evo._arm import evaluate_arm_traced
from uvms_jax.evo._arm import fixed_base_M_a
from uvms_jax.evo._arm import make_arm_docking_problem
from uvms_jax.evo._arm import target_w
from uvms_jax.evo._arm import vehicle_clear
from uvms_jax.evo._binary import BinaryCodec
from uvms_jax.evo._binary import make_codec
from uvms_jax.evo._cmaes import CMAESResult
from uvms_jax.evo._cmaes import run_cmaes
from uvms_jax.evo._docking import BestPose
from uvms_jax.evo._docking import CMAESRuns
from uvms_jax.evo._docking import DockingRun
from uvms_jax.evo._docking import GridOptimum
from uvms_jax.evo._docking import PoseMap
from uvms_jax.evo._docking import docking_problem
from uvms_jax.evo._docking import evaluate_any
from uvms_jax.evo._docking import grid_periodicity
from uvms_jax.evo._docking import make_ga
from uvms_jax.evo._docking import pose_checks
from uvms_jax.evo._docking import run_docking
from uvms_jax.evo._fitness import FITNESS_TERMS
from uvms_jax.evo._fitness import FitnessInputs
from uvms_jax.evo._fitness import Objective
from uvms_jax.evo._fitness import Problem
from uvms_jax.evo._fitness import make_objective
from uvms_jax.evo._fitness import register_fitness_term
from uvms_jax.evo._ga import BinaryGA
from uvms_jax.evo._ga import GAParams
from uvms_jax.evo._ga import GAResult
from uvms_jax.evo._ga import GAState
from uvms_jax.evo._ga import ga_batch_compiled
from uvms_jax.evo._ga import run_ga
from uvms_jax.evo._ga import run_ga_batch
from uvms_jax.evo._grid import GridResult
from uvms_jax.evo._grid import ZoomResult
from uvms_jax.evo._grid import distinct_best
from uvms_jax.evo._grid import grid_axes
from uvms_jax.evo._grid import grid_search
from uvms_jax.evo._grid import refine_grid_search
from uvms_jax.evo._grid import zoom_from
from uvms_jax.evo._problem import DockingEval
from uvms_jax.evo._problem import DockingProblem
from uvms_jax.evo._problem import base_transform
from uvms_jax.evo._problem import docking_point
from uvms_jax.evo._problem import evaluate
from uvms_jax.evo._problem import evaluate_traced
from uvms_jax.evo._problem import in_search_set
from uvms_jax.evo._problem import make_docking_problem
from uvms_jax.evo._scenes import ArmTask
from uvms_jax.evo._scenes import boxes
from uvms_jax.evo._scenes import scene_robot
from uvms_jax.evo._scenes import arm_docking_problem
from uvms_jax.evo._scenes import panel_targets
from uvms_jax.evo._scenes import panel_task
from uvms_jax.evo._scenes import fewer_alternatives
from uvms_jax.evo._settings import FIELDS
from uvms_jax.evo._settings import ArmSceneSettings
from uvms_jax.evo._settings import BoxSettings
from uvms_jax.evo._settings import CMAESSettings
from uvms_jax.evo._settings import DockingSettings
from uvms_jax.evo._settings import FieldBits
from uvms_jax.evo._settings import GASettings
from uvms_jax.evo._settings import GridSettings
from uvms_jax.evo._settings import PanelSettings
from uvms_jax.evo._settings import SceneSettings
from uvms_jax.evo._settings import TermSettings
from uvms_jax.evo._settings import WmaxSettings
from uvms_jax.evo._shard import ShardedProblem
from uvms_jax.evo._geometry import SLACK
from uvms_jax.evo._geometry import SphereWorld
from uvms_jax.evo._geometry import WorldRows
from uvms_jax.evo._world import capsule_world
from uvms_jax.evo._geometry import make_sphere_world
from uvms_jax.evo._world import world_collides
from uvms_jax.evo._shard import device_mesh
from uvms_jax.evo._shard import shard_over_devices
from uvms_jax.evo._wmax import WmaxMap
from uvms_jax.evo._wmax import wmax_map
from uvms_jax.evo._write import docking_summary
from uvms_jax.evo._write import write_docking
