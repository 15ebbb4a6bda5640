"""Motion planning for the Reach Bravo 7 in the thesis's test cage (issue 6; thesis ch. 4–5).

* scene: :class:`SceneSpec` (from ``configs/scenario/*.yaml``), :func:`build_scene` →
  :class:`Scene` (MuJoCo model, object and base poses, grasp), :class:`Context`;
* collision: :class:`CollisionChecker` — ``is_valid``, ``clearance``, their batched versions,
  ``path_is_valid``; :func:`densify`;
* targets: :func:`pick_place_targets` (batched numerical IK of the eight pick-and-place steps),
  :class:`NodeTarget`, :data:`STEPS`;
* planning: :func:`plan_motion` (OMPL RRTConnect / BKPIECE1 / PRM + simplification + re-check),
  :func:`time_parameterize`, :class:`Trajectory`, :func:`check_trajectory`, :func:`seed_ompl`;
* metrics: :func:`trajectory_metrics`, :class:`EdgeMetrics`;
* task graph: :func:`task_edges`, :func:`plan_edge`, :func:`metric_matrices`,
  :func:`cost_matrix`, :func:`plan_json` (the :mod:`uvms_jax.planfile` format).
"""

from uvms_jax.plan._collision import CollisionChecker
from uvms_jax.plan._collision import densify
from uvms_jax.plan._metrics import METRIC_NAMES
from uvms_jax.plan._metrics import EdgeMetrics
from uvms_jax.plan._metrics import trajectory_metrics
from uvms_jax.plan._planning import PLANNERS
from uvms_jax.plan._planning import PlanResult
from uvms_jax.plan._planning import Trajectory
from uvms_jax.plan._planning import check_trajectory
from uvms_jax.plan._planning import plan_motion
from uvms_jax.plan._planning import seed_ompl
from uvms_jax.plan._planning import time_parameterize
from uvms_jax.plan._scene import Box
from uvms_jax.plan._scene import Context
from uvms_jax.plan._scene import Item
from uvms_jax.plan._scene import Scene
from uvms_jax.plan._scene import SceneSpec
from uvms_jax.plan._scene import build_scene
from uvms_jax.plan._targets import STEPS
from uvms_jax.plan._targets import NodeTarget
from uvms_jax.plan._targets import node_contexts
from uvms_jax.plan._targets import pick_place_targets
from uvms_jax.plan._tasks import EdgeResult
from uvms_jax.plan._tasks import cost_matrix
from uvms_jax.plan._tasks import edge_endpoints
from uvms_jax.plan._tasks import goal_node
from uvms_jax.plan._tasks import metric_matrices
from uvms_jax.plan._tasks import plan_edge
from uvms_jax.plan._tasks import plan_json
from uvms_jax.plan._tasks import task_edges
