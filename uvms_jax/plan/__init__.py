"""Motion planning for any arm (a :class:`uvms_jax.robot.Robot`) in a pick-and-place scene such
as the thesis's test cage (thesis ch. 4–5).

* stage: :class:`PlanSettings` (with :class:`IkSettings`, :class:`PlanJsonSettings`),
  :func:`plan_task_graph` → :class:`TaskGraphPlan` (targets, every edge by every planner,
  metric tensors, cost matrices, :class:`PlannerSummary`), :func:`plan_for_schedule` → a
  :class:`uvms_jax.planfile.Plan`; files: :func:`write_task_graph`, :func:`write_plan`;
  figures: :func:`plot_ee_paths`, :func:`plot_plan_joints`, :func:`render_frame`, :func:`render_frames`;
  video of an executed run: :func:`render_run_video` → :class:`VideoInfo` (MP4, offscreen
  MuJoCo, camera :func:`scene_camera`);
* scene: :class:`SceneSpec` (from ``configs/scenario/*.yaml``, checked by :func:`check_scenario`
  against the scenario schema, docs/scenarios.md; extra :class:`Obstacle` s —
  box, cylinder, sphere, capsule, mesh file), :func:`scenario_robot` (the arm a scenario names; :func:`check_start_q`), :func:`build_scene` (robot, spec) →
  :class:`Scene` (MuJoCo model, object and base poses, grasp; the arm's base pose a parameter), :class:`Context`;
* collision: :class:`CollisionChecker` (MuJoCo, the reference) — ``is_valid``, ``clearance``,
  their batched versions, ``path_is_valid``, ``min_clearance`` (exact, MuJoCo only where the sphere bounds leave it open); :func:`densify`; :class:`SphereChecker` (the arm
  as spheres, compiled; whole motions per call, conservative, MuJoCo confirms rejections);
  every query (and :func:`plan_motion`) takes its :class:`Context` as an argument, the checkers
  hold no context a caller must set or reset;
* targets: :func:`pick_place_targets` (batched numerical IK of the eight pick-and-place steps),
  :class:`NodeTarget`, :data:`STEPS`; :func:`docking_task` (the grasp and place poses as a
  docking optimiser's task, ``uvms_jax.evo.ArmTask``, with the planner's collision world of the
  arm on its vehicle, :func:`docking_world`: the sphere checker's model as a
  ``uvms_jax.evo.SphereWorld``; :func:`vehicle_obstacles`: the vehicle's boxes in a scene;
  :func:`docked_scene`: the scenario with the arm's base on the docked vehicle and its hull);
* batches on a GPU: :func:`plan_batch` (many problems in one jitted call, :class:`BatchSettings`
  → :class:`BatchPlan`) on the sphere checker in JAX (:func:`sphere_arm`, :func:`sphere_worlds`:
  the robot's spheres and a padded batch of worlds);
* planning: :func:`plan_motion` (any OMPL geometric planner by name, :func:`ompl_planners`,
  with its parameters, :func:`planner_parameters`; simplification; MuJoCo re-check),
  :func:`time_parameterize`, :class:`Trajectory`, :func:`check_trajectory`, :func:`seed_ompl`;
* metrics: :func:`trajectory_metrics`, :class:`EdgeMetrics` (fields: ``uvms_jax.sched.METRICS``),
  :func:`static_torques` (the arm's weight and buoyancy and the held object's load);
* task graph: :func:`task_edges`, :func:`plan_edge`, :func:`metric_tensor` (the input of
  ``uvms_jax.sched.normalise_metrics``), :func:`plan_from_edges` (:func:`gripper_steps`: how an arm
  without a gripper takes its gripper steps);
* query path: :func:`plan_query` → :class:`QueryResult` (a robot in a :class:`World`, compiled
  :class:`VectorChecker` with MuJoCo's :class:`ExactChecker` and its pair tables'
  :data:`TABLE_BOUND`, its kernels compiled ahead by :func:`warm_kernels`; MoveIt scenes and requests:
  :func:`load_moveit_scene`, :func:`load_moveit_request`, an SRDF's disabled pairs :func:`load_srdf`); a scene in a context as a world:
  :func:`scene_world`, :func:`held_shapes`, :func:`scene_checker`, an edge on it:
  :func:`plan_scene_query` (``PlanSettings.checker = "query"``); many problems in one jitted
  call on a GPU: :func:`plan_batch` (:class:`BatchSettings`, :class:`BatchPlan`).

The package never imports ``uvms_jax.hw``: plans meet the hardware only through
:mod:`uvms_jax.planfile`.
"""

from uvms_jax.plan._collision import CollisionChecker
from uvms_jax.plan._collision import densify
from uvms_jax.plan._metrics import EdgeMetrics
from uvms_jax.plan._metrics import static_torques
from uvms_jax.plan._metrics import trajectory_metrics
from uvms_jax.plan._planners import ompl_planners
from uvms_jax.plan._planners import planner_parameters
from uvms_jax.plan._planning import PARTIAL_MOTIONS
from uvms_jax.plan._planning import PLANNERS
from uvms_jax.plan._planning import PlanResult
from uvms_jax.plan._planning import Trajectory
from uvms_jax.plan._planning import check_trajectory
from uvms_jax.plan._planning import plan_motion
from uvms_jax.plan._planning import seed_ompl
from uvms_jax.plan._planning import time_parameterize
from uvms_jax.plan._plots import plot_ee_paths
from uvms_jax.plan._plots import plot_plan_joints
from uvms_jax.plan._plots import render_frame
from uvms_jax.plan._plots import render_frames
from uvms_jax.plan._spec import Box
from uvms_jax.plan._scene import Context
from uvms_jax.plan._spec import Item
from uvms_jax.plan._spec import Obstacle
from uvms_jax.plan._scene import Scene
from uvms_jax.plan._spec import SceneSpec
from uvms_jax.plan._spec import MOUNT_KEYS
from uvms_jax.plan._scene import build_scene
from uvms_jax.plan._spec import scenario_robot
from uvms_jax.plan._spec import check_start_q
from uvms_jax.plan._schema import check_scenario
from uvms_jax.plan._settings import CHECKERS
from uvms_jax.plan._settings import IkSettings
from uvms_jax.plan._settings import PlanJsonSettings
from uvms_jax.plan._settings import PlanSettings
from uvms_jax.plan._spheres import SphereChecker
from uvms_jax.plan._targets import STEPS
from uvms_jax.plan._targets import NodeTarget
from uvms_jax.plan._targets import node_contexts
from uvms_jax.plan._targets import pick_place_targets
from uvms_jax.plan._targets import tool_poses
from uvms_jax.plan._taskgraph import PlannerSummary
from uvms_jax.plan._taskgraph import TaskGraphPlan
from uvms_jax.plan._taskgraph import plan_for_schedule
from uvms_jax.plan._taskgraph import plan_task_graph
from uvms_jax.plan._tasks import EdgeResult
from uvms_jax.plan._tasks import compatibility
from uvms_jax.plan._tasks import edge_endpoints
from uvms_jax.plan._tasks import goal_node
from uvms_jax.plan._tasks import gripper_steps
from uvms_jax.plan._tasks import metric_tensor
from uvms_jax.plan._tasks import plan_edge
from uvms_jax.plan._tasks import plan_from_edges
from uvms_jax.plan._tasks import task_edges
from uvms_jax.plan._video import VideoInfo
from uvms_jax.plan._video import render_run_video
from uvms_jax.plan._video import scene_camera
from uvms_jax.plan._world import VEHICLE_PREFIX
from uvms_jax.plan._world import docked_scene
from uvms_jax.plan._world import docking_task
from uvms_jax.plan._world import docking_world
from uvms_jax.plan._world import sphere_world
from uvms_jax.plan._world import vehicle_obstacles
from uvms_jax.plan._write import write_plan
from uvms_jax.plan._write import write_task_graph
from uvms_jax.plan._moveit import MotionRequest
from uvms_jax.plan._moveit import load_moveit_request
from uvms_jax.plan._moveit import load_moveit_scene
from uvms_jax.plan._moveit import load_srdf
from uvms_jax.plan._vector import ExactChecker
from uvms_jax.plan._query import QueryResult
from uvms_jax.plan._query import plan_query
from uvms_jax.plan._pair_tables import TABLE_BOUND
from uvms_jax.plan._vector import LIMIT_TOL
from uvms_jax.plan._vector import VectorChecker
from uvms_jax.plan._worlds import World
from uvms_jax.plan._vector import check_in_limits
from uvms_jax.plan._vector import warm_kernels
from uvms_jax.plan._vector_jax import SphereArm
from uvms_jax.plan._vector_jax import SphereWorlds
from uvms_jax.plan._vector_jax import sphere_arm
from uvms_jax.plan._vector_jax import sphere_worlds
from uvms_jax.plan._batch_jax import BatchPlan
from uvms_jax.plan._batch_jax import BatchSettings
from uvms_jax.plan._batch_jax import plan_batch
from uvms_jax.plan._scenequery import held_shapes
from uvms_jax.plan._scenequery import plan_scene_query
from uvms_jax.plan._scenequery import scene_checker
from uvms_jax.plan._scenequery import scene_world
