"""Arm docking scenes from settings: the arm, the vehicle, the obstacles and the task poses."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from uvms_jax import bravo7, kin
from uvms_jax.evo._arm import ArmDockingProblem, make_arm_docking_problem
from uvms_jax.evo._settings import ArmSceneSettings, BoxSettings, PanelSettings

#: Arm models by name: chain builder and link capsule radius [m].
ARMS = {"bravo7": (kin.bravo7, bravo7.LINK_RADIUS)}


def pose_matrix(xyz, rpy) -> np.ndarray:
    """``(4, 4)`` pose from a position [m] and roll-pitch-yaw [rad]."""
    T = np.eye(4)
    T[:3, :3] = Rotation.from_euler("xyz", rpy).as_matrix()  # fixed x-y-z axes: R_z R_y R_x, as URDF
    T[:3, 3] = xyz
    return T


def boxes(items: tuple[BoxSettings, ...]) -> tuple[np.ndarray, np.ndarray]:
    """``(T (m, 4, 4), half (m, 3))`` of box settings."""
    if not items:
        return np.zeros((0, 4, 4)), np.zeros((0, 3))
    return np.stack([pose_matrix(b.pos, b.rpy) for b in items]), np.stack([np.asarray(b.size) / 2 for b in items])


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


def scenario_targets(scenario: dict) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, list[str]]:
    """Targets and obstacles of a pick-and-place scenario (``configs/scenario/*.yaml``).

    Returns:
      ``T_world_tool (k, 4, 4)``: the grasp pose of every object and the place pose of every
      base, one per symmetric yaw of the object; ``group (k,)``: the node of each pose as a
      target index; the scenario's tables as boxes ``(T (m, 4, 4), half (m, 3))``; the node
      names, one per target.
    """
    from uvms_jax import plan  # only this preset needs the planning scene (MuJoCo, OMPL)

    scene = plan.build_scene(scenario)
    nodes = sorted(scene.objects) + sorted(scene.bases)
    poses, group, names = [], [], []
    for i, node in enumerate(nodes):
        _, at, _ = plan.tool_poses(scene, node)
        poses.append(at)
        group += [i] * len(at)
        names.append((scene.objects.get(node) or scene.bases[node]).name)
    tables = tuple(BoxSettings(b.name, b.pos, b.size, b.rpy) for b in scene.spec.tables)
    T_box, half = boxes(tables)
    return np.concatenate(poses), np.asarray(group), T_box, half, names


def load_arm(arm: str, tip: str | None = None) -> tuple[kin.Chain, float | None]:
    """An arm by name (:data:`ARMS`) or from a robot description file.

    Args:
      arm: a name in :data:`ARMS`, or a path to a URDF (``.urdf``) or MJCF (``.xml``) file.
      tip: the tool frame in the file: a link of a URDF, a body of an MJCF model (default: the
        file's only leaf); must be None for a named arm.

    Returns:
      ``(chain, link radius [m])``; the radius is None for a file (it holds no capsule size).

    Raises:
      ValueError: unknown name or file type (and the importers' errors for a bad file).
    """
    if arm in ARMS:
        if tip is not None:
            raise ValueError(f"arm_tip is for arms from files; {arm!r} has its own tool frame")
        make_chain, radius = ARMS[arm]
        return make_chain(), radius
    path = Path(arm)
    if path.suffix == ".urdf":
        return kin.from_urdf(path, tip_link=tip), None
    if path.suffix == ".xml":
        return kin.from_mjcf(path, tip_body=tip), None
    raise ValueError(f"unknown arm {arm!r}: a name in {sorted(ARMS)} or a .urdf / .xml (MJCF) file")


def arm_docking_problem(scene: ArmSceneSettings, dtype=None) -> ArmDockingProblem:
    """The :class:`ArmDockingProblem` of an arm scene's settings.

    Raises:
      ValueError: unknown arm, or bad geometry (see :func:`make_arm_docking_problem`).
    """
    chain, radius = load_arm(scene.arm, scene.arm_tip)
    if scene.link_radius is None and radius is None:
        raise ValueError(f"arm {scene.arm!r} comes from a file: set link_radius (its links' capsule radius [m])")
    T_box, half = boxes(scene.scene_boxes)
    group = None
    if scene.panel is not None:
        T_tool = panel_targets(scene.panel)
    else:
        T_tool, group, T_tables, half_tables, _ = scenario_targets(scene.scenario)
        T_box, half = np.concatenate([T_box, T_tables]), np.concatenate([half, half_tables])
    return make_arm_docking_problem(
        chain=chain,
        T_vehicle_base=pose_matrix(scene.mount_xyz, scene.mount_rpy),
        T_world_tool=T_tool,
        group=group,
        low=scene.pose_low,
        high=scene.pose_high,
        p_dock=scene.p_dock,
        p_i=scene.p_init,
        a=scene.a,
        b=scene.b,
        link_radius=radius if scene.link_radius is None else scene.link_radius,
        vehicle_boxes=boxes(scene.vehicle_boxes),
        scene_boxes=(T_box, half),
        n_seeds=scene.ik_seeds,
        iterations=scene.ik_iterations,
        damping=scene.ik_damping,
        seed=scene.ik_seed,
        dtype=dtype,
    )
