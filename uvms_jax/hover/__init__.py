"""A hovering vehicle carrying an arm, in MuJoCo: the physics core of the hover feature.

The vehicle is a hull on a free joint with the arm fixed under it at its mount
(:func:`hover_spec`, :func:`hover_model`). MuJoCo gives the coupled rigid-body dynamics,
gravity, and the drag of its inertia-box fluid model, with the water current as its ``wind``.
This package adds the buoyancy of every body at its centre of buoyancy (:func:`buoyancy_xfrc`
on :func:`buoyancy_bodies`, set into ``MjData`` by :func:`apply_buoyancy`), thrusters
(:class:`Thruster`; the default eight-thruster vectored layout :data:`DEFAULT_THRUSTERS`),
station keeping on (x, y, z, ψ) (:func:`station_keeping`) and thrust allocation by the scaled
pseudo-inverse of the thrust configuration matrix (:func:`thrust_matrix`,
:func:`allocate_thrust`); a whole-body controller (:class:`WholeBody`, :class:`WholeBodySettings`)
that keeps the tool on its planned path with the vehicle's station keeping in its null space.
:class:`HoverSim` steps it all on the CPU and records a
:class:`HoverLog`; :func:`write_hover_video` films a run in its planning scene. Over BPL,
:func:`execute_plan_hovering` runs a plan with the hw executor on the simulated arm mounted on
the vehicle, the whole-body controller between the plan and the arm
(:class:`ExecutorWholeBody`); :func:`run_hover` and :func:`write_hover` are the hover stage
(:func:`film_hover` films its main run while the others go on).
Settings: :class:`VehicleSettings` (trimmed to neutral and level for an arm
and pose by :func:`trimmed`), :class:`ControllerSettings`, :class:`CurrentSettings`.

The formulas are pure functions of arrays that take ``xp`` (``numpy`` or ``jax.numpy``), so a
batched MJX simulator can reuse them. Frames, units and the tests' oracles: docs/hover.md.
"""

from uvms_jax.hover._batch import BatchResult
from uvms_jax.hover._batch import HoverMJX
from uvms_jax.hover._batch import HoverState
from uvms_jax.hover._batch import PeriodRecord
from uvms_jax.hover._batch import batch_candidates
from uvms_jax.hover._batch import batch_plan
from uvms_jax.hover._batch import batch_scenarios
from uvms_jax.hover._batch import currents_grid
from uvms_jax.hover._batch import fluid_bodies
from uvms_jax.hover._batch import fluid_xfrc
from uvms_jax.hover._batch import hover_mjx
from uvms_jax.hover._batch import plot_robustness
from uvms_jax.hover._batch_control import CONTROLS
from uvms_jax.hover._batch_control import ControlledResult
from uvms_jax.hover._batch_control import CurrentRanking
from uvms_jax.hover._batch_control import batch_controlled
from uvms_jax.hover._batch_control import nav_schedule
from uvms_jax.hover._batch_control import rank_by_current
from uvms_jax.hover._executed import ExecutorWholeBody
from uvms_jax.hover._executed import executor_settings
from uvms_jax.hover._control import allocate_thrust
from uvms_jax.hover._control import control_steps
from uvms_jax.hover._control import hold_pose
from uvms_jax.hover._control import level_attitude
from uvms_jax.hover._control import station_keeping
from uvms_jax.hover._control import thrust_layout
from uvms_jax.hover._control import thrust_matrix
from uvms_jax.hover._control import wrap_angle
from uvms_jax.hover._control import yaw_of_quat
from uvms_jax.hover._hydro import buoyancy_xfrc
from uvms_jax.hover._hydro import current_at
from uvms_jax.hover._model import HULL_GEOM
from uvms_jax.hover._model import SERVO_KP
from uvms_jax.hover._model import SERVO_KV
from uvms_jax.hover._model import VEHICLE_BODY
from uvms_jax.hover._model import apply_buoyancy
from uvms_jax.hover._model import buoyancy_bodies
from uvms_jax.hover._model import hover_mjcf
from uvms_jax.hover._model import hover_model
from uvms_jax.hover._model import hover_spec
from uvms_jax.hover._model import servo_name
from uvms_jax.hover._model import thruster_name
from uvms_jax.hover._model import trimmed
from uvms_jax.hover._plan import HoverRun
from uvms_jax.hover._plan import docked_tool
from uvms_jax.hover._plan import execute_plan_hovering
from uvms_jax.hover._plan import follow_tool_path
from uvms_jax.hover._plan import plan_targets
from uvms_jax.hover._plan import run_plan_hovering
from uvms_jax.hover._plan import vehicle_arm_chain
from uvms_jax.hover._plan import vehicle_displacement
from uvms_jax.hover._settings import DEFAULT_THRUSTERS
from uvms_jax.hover._stage import HoverFilmed
from uvms_jax.hover._stage import HoverStage
from uvms_jax.hover._stage import film_hover
from uvms_jax.hover._stage import plot_hover
from uvms_jax.hover._stage import run_hover
from uvms_jax.hover._stage import write_hover
from uvms_jax.hover._settings import GRAVITY
from uvms_jax.hover._settings import ControllerSettings
from uvms_jax.hover._settings import CurrentSettings
from uvms_jax.hover._settings import Thruster
from uvms_jax.hover._settings import NavigationSettings
from uvms_jax.hover._settings import VehicleSettings
from uvms_jax.hover._settings import WholeBodySettings
from uvms_jax.hover._sim import HoverLog
from uvms_jax.hover._sim import HoverSim
from uvms_jax.hover._sim import HoverWorld
from uvms_jax.hover._sim import arm_motion
from uvms_jax.hover._video import HoverFilm
from uvms_jax.hover._video import hover_frame
from uvms_jax.hover._video import write_hover_video
from uvms_jax.hover._wholebody import NavigationEstimate
from uvms_jax.hover._wholebody import WholeBody
from uvms_jax.hover._wholebody import WholeBodyCommand

__all__ = ["allocate_thrust", "apply_buoyancy", "arm_motion", "batch_candidates", "batch_controlled", "batch_plan",
           "batch_scenarios", "BatchResult", "buoyancy_bodies", "buoyancy_xfrc", "control_steps",
           "ControlledResult", "CONTROLS", "ControllerSettings", "CurrentRanking", "current_at", "currents_grid", "CurrentSettings", "DEFAULT_THRUSTERS",
           "docked_tool", "execute_plan_hovering", "film_hover", "executor_settings", "ExecutorWholeBody", "fluid_bodies", "fluid_xfrc", "follow_tool_path",
           "GRAVITY", "hold_pose", "hover_mjcf", "hover_mjx", "hover_model", "hover_spec", "HoverFilm", "HoverFilmed", "hover_frame", "HoverLog", "HoverMJX",
           "HoverRun", "HoverSim", "HoverStage", "HoverState", "HoverWorld", "HULL_GEOM", "level_attitude", "nav_schedule", "NavigationEstimate",
           "NavigationSettings", "PeriodRecord",
           "plan_targets", "plot_hover", "plot_robustness", "rank_by_current", "run_hover", "run_plan_hovering", "SERVO_KP", "SERVO_KV", "servo_name",
           "station_keeping", "thrust_layout", "thrust_matrix", "Thruster", "thruster_name", "trimmed",
           "vehicle_arm_chain", "VEHICLE_BODY", "vehicle_displacement", "VehicleSettings", "WholeBody",
           "WholeBodyCommand", "WholeBodySettings", "wrap_angle", "write_hover", "write_hover_video",
           "yaw_of_quat"]
