"""Arm docking scenes from settings: the arm, the vehicle, the obstacles and the task poses."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from uvms_jax import frames
from uvms_jax import robot as robots
from uvms_jax.evo._arm import ArmDockingProblem, make_arm_docking_problem
from uvms_jax.evo._settings import ArmSceneSettings, BoxSettings, PanelSettings, term_weights
from uvms_jax.evo._geometry import SphereWorld


def boxes(items: tuple[BoxSettings, ...]) -> tuple[np.ndarray, np.ndarray]:
    """``(T (m, 4, 4), half (m, 3))`` of box settings."""
    if not items:
        return np.zeros((0, 4, 4)), np.zeros((0, 3))
    return np.stack([frames.rpy_pose(b.pos, b.rpy) for b in items]), np.stack([np.asarray(b.size) / 2 for b in items])


def panel_targets(panel: PanelSettings) -> np.ndarray:
    """Tool poses ``T_world_tool (n², 4, 4)`` on a vertical panel: an ``n × n`` grid over the
    task area (corners included), the tool ``standoff`` in front of the face, its z axis (the
    approach) horizontal at heading ``approach_yaw`` into the panel, its x axis up for
    ``roll = 0``."""
    n = panel.points_per_side
    if n < 2 or min(panel.size) <= 0 or panel.standoff < 0:
        raise ValueError(f"panel needs points_per_side >= 2, positive size and standoff >= 0, got {panel}")
    c, s = np.cos(panel.approach_yaw), np.sin(panel.approach_yaw)
    z = np.array([c, s, 0.0])  # approach, into the panel
    side = np.array([-s, c, 0.0])  # horizontal along the face
    up = np.array([0.0, 0.0, 1.0])
    cr, sr = np.cos(panel.roll), np.sin(panel.roll)
    x = cr * up + sr * side
    R = np.stack([x, np.cross(z, x), z], axis=-1)
    u = np.linspace(-panel.size[0] / 2, panel.size[0] / 2, n)
    v = np.linspace(-panel.size[1] / 2, panel.size[1] / 2, n)
    T = np.tile(np.eye(4), (n * n, 1, 1))
    T[:, :3, :3] = R
    uu, vv = np.meshgrid(u, v, indexing="ij")
    T[:, :3, 3] = np.asarray(panel.center) - panel.standoff * z + uu.reshape(-1, 1) * side + vv.reshape(-1, 1) * up
    return T


class ArmTask(NamedTuple):
    """What the arm must reach, as data: tool poses grouped into targets, and the obstacles
    around them (e.g. a pick-and-place scenario's grasp and place poses and its tables,
    :func:`uvms_jax.plan.docking_task`).

    Attributes:
      T_world_tool: ``(k, 4, 4)`` demanded tool poses in the world [m].
      group: ``(k,)`` target of each pose, ``0 … g − 1``; the poses of a target are
        alternatives (e.g. the symmetric grasps of an object).
      names: ``(g,)`` a label per target.
      T_world_box, half: ``(m, 4, 4), (m, 3)`` obstacle boxes in the world [m] (the vehicle
        must not meet them).
      world: the planner's collision world of the arm on its vehicle in this scene, one row per
        target (:func:`uvms_jax.plan.docking_world`); None: the arm's link capsules against
        the boxes (:func:`~uvms_jax.evo.capsule_world`).
    """

    T_world_tool: np.ndarray
    group: np.ndarray
    names: tuple[str, ...]
    T_world_box: np.ndarray
    half: np.ndarray
    world: SphereWorld | None = None


def panel_task(panel: PanelSettings) -> ArmTask:
    """The panel's control points, each its own target, with no obstacles (the scene's boxes
    hold the panel)."""
    T = panel_targets(panel)
    return ArmTask(T, np.arange(len(T)), tuple(f"point {i}" for i in range(len(T))), *boxes(()), None)


def fewer_alternatives(task: ArmTask, alternatives: int | None) -> ArmTask:
    """At most ``alternatives`` poses per target, evenly spaced in the given order (e.g. 2 of
    a cube's 4 grasp yaws: 0 and π); None keeps all."""
    if alternatives is None:
        return task
    if alternatives < 1:
        raise ValueError(f"alternatives must be >= 1 or None, got {alternatives}")
    keep = []
    for g in range(len(task.names)):
        idx = np.flatnonzero(task.group == g)
        keep += list(idx[np.linspace(0, len(idx), min(alternatives, len(idx)), endpoint=False).astype(int)])
    keep = np.sort(np.asarray(keep))
    return task._replace(T_world_tool=task.T_world_tool[keep], group=task.group[keep])


def scene_robot(scene: ArmSceneSettings) -> robots.Robot:
    """The arm an arm scene names: a shipped arm card (:func:`uvms_jax.robot.shipped_arms`,
    e.g. ``bravo7``) or a URDF/MJCF file with its tool frame ``arm_tip``; ``link_radius``, when
    set, replaces the arm's capsule radius.

    Raises:
      ValueError: an unknown arm, or a tip given for a shipped arm (it has its own tool frame).
    """
    settings: dict = {"card": scene.arm} if scene.arm in robots.shipped_arms() else {
        "description": scene.arm, "tip": scene.arm_tip}
    if "card" in settings and scene.arm_tip is not None:
        raise ValueError(f"arm_tip is for arms from files; {scene.arm!r} has its own tool frame")
    if scene.link_radius is not None:
        settings["link_radius"] = scene.link_radius
    return robots.robot_from_config(settings)


def arm_docking_problem(scene: ArmSceneSettings, task: ArmTask | None = None, dtype=None,
                        robot: robots.Robot | None = None) -> ArmDockingProblem:
    """The :class:`ArmDockingProblem` of an arm scene's settings and its task.

    Args:
      scene: the arm, the vehicle, the pose box, the objective's weights and the IK settings.
      task: what the arm must reach; None takes the scene's panel (``scene.panel``).
      dtype: float dtype of the problem's arrays.
      robot: the arm; None: the one the scene names (:func:`scene_robot`).

    Raises:
      ValueError: no task or two (a panel and a task), unknown arm, or bad geometry (see
        :func:`make_arm_docking_problem`).
    """
    if (scene.panel is None) == (task is None):
        raise ValueError("an arm scene needs exactly one task: scene.panel, or a task passed in (e.g. a "
                         "pick-and-place scenario's tool poses, uvms_jax.plan.docking_task)")
    robot = scene_robot(scene) if robot is None else robot
    task = fewer_alternatives(panel_task(scene.panel) if task is None else task, scene.alternatives)
    T_box, half = boxes(scene.scene_boxes)
    T_box, half = np.concatenate([T_box, task.T_world_box]), np.concatenate([half, task.half])
    return make_arm_docking_problem(
        chain=robot.chain,
        T_vehicle_base=frames.rpy_pose(scene.mount_xyz, scene.mount_rpy),
        T_world_tool=task.T_world_tool,
        group=task.group,
        low=scene.pose_low,
        high=scene.pose_high,
        p_dock=scene.p_dock,
        p_i=scene.p_init,
        a=scene.a,
        b=scene.b,
        terms=term_weights(scene.terms),
        link_radius=robot.link_radius,
        world=task.world,
        vehicle_boxes=boxes(scene.vehicle_boxes),
        scene_boxes=(T_box, half),
        n_seeds=scene.ik_seeds,
        iterations=scene.ik_iterations,
        damping=scene.ik_damping,
        seed=scene.ik_seed,
        dtype=dtype,
    )
