"""Worlds and queries from MoveIt's messages as YAML: a ``PlanningScene`` (collision objects of
primitives, the allowed collision matrix) and a ``MotionPlanRequest`` (start state, joint goal),
as the MotionBenchMaker problem sets and ``moveit_msgs`` dumps hold them; and the self-collision
pairs an SRDF disables (MoveIt folds them into the scene's allowed collision matrix, and so does
:func:`load_srdf`'s caller: ``World(obstacles, allowed=world.allowed | load_srdf(path))``).

MoveIt writes quaternions as ``x, y, z, w``; cylinders as ``[height, radius]``, cones likewise;
boxes as full edges. Poses are in the planning frame, which is taken as the robot's base frame.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
from lxml import etree

from uvms_jax import frames
from uvms_jax.plan._spec import Obstacle
from uvms_jax.plan._worlds import World
from uvms_jax.robot import Robot
from uvms_jax.settings import read_yaml

__all__ = ["MotionRequest", "load_moveit_request", "load_moveit_scene", "load_srdf"]


@dataclasses.dataclass(frozen=True)
class MotionRequest:
    """A joint-space query: start and goal of the arm's joints, and the finger opening.

    Attributes:
      start, goal: ``(n,)`` joint values in the robot's joint order [rad or m].
      opening: the gripper joint's value in the start state [m], None where the state has none.
      source: the file it came from.
    """

    start: np.ndarray
    goal: np.ndarray
    opening: float | None
    source: str = "<mapping>"


def _read(path) -> tuple[Mapping[str, Any], str]:
    path = Path(path)
    data = read_yaml(path)  # bounded; SettingsError (a ValueError) naming the file and line
    if not isinstance(data, Mapping):
        raise ValueError(f"{path} must hold a mapping (a MoveIt message), got {type(data).__name__}")
    return data, str(path)


def _pose(p: Mapping[str, Any], where: str) -> np.ndarray:
    try:
        xyz = [float(v) for v in p["position"]]
        x, y, z, w = (float(v) for v in p["orientation"])
    except (KeyError, TypeError, ValueError):
        raise ValueError(f"{where}: a pose needs position [x, y, z] and orientation [x, y, z, w]") from None
    if not np.all(np.isfinite([*xyz, x, y, z, w])) or len(xyz) != 3:
        raise ValueError(f"{where}: pose must be 3 + 4 finite numbers, got {p}")
    norm = np.linalg.norm([w, x, y, z])
    if norm == 0:
        raise ValueError(f"{where}: orientation is the zero quaternion")
    return frames.pose(frames.quat_matrix(np.array([w, x, y, z]) / norm), xyz)


def _primitive(name: str, kind: str, dims, T: np.ndarray, where: str) -> Obstacle:
    dims = [float(d) for d in dims]
    quat = tuple(float(v) for v in frames.matrix_quat(T[:3, :3]))
    pos = tuple(float(v) for v in T[:3, 3])
    if kind == "box" and len(dims) == 3:
        return Obstacle(name, "box", pos, dims=tuple(dims), quat=quat)
    if kind == "sphere" and len(dims) == 1:
        return Obstacle(name, "sphere", pos, dims=(dims[0],), quat=quat)
    if kind == "cylinder" and len(dims) == 2:
        return Obstacle(name, "cylinder", pos, dims=(dims[1], dims[0]), quat=quat)
    raise ValueError(f"{where}: a {kind!r} with dimensions {dims} is not supported "
                     "(box [x, y, z], sphere [r], cylinder [height, r])")


def load_moveit_scene(path) -> World:
    """The :class:`World` of a MoveIt ``PlanningScene`` YAML file: its ``world.collision_objects``
    (each primitive an :class:`Obstacle` named ``<id>`` or ``<id>/<k>``, at the object's ``pose``
    times the primitive's pose where the message has an object pose) and its
    ``allowed_collision_matrix`` (the link pairs marked true)."""
    data, source = _read(path)
    obstacles = []
    for i, obj in enumerate((data.get("world") or {}).get("collision_objects") or []):
        where = f"{source}: world.collision_objects[{i}]"
        if obj.get("meshes") or obj.get("planes"):
            raise ValueError(f"{where}: mesh and plane collision objects are not supported (primitives only)")
        prims, poses = obj.get("primitives") or [], obj.get("primitive_poses") or []
        if len(prims) != len(poses):
            raise ValueError(f"{where}: {len(prims)} primitives but {len(poses)} primitive_poses")
        T_obj = _pose(obj["pose"], where) if obj.get("pose") else np.eye(4)
        for k, (prim, pose) in enumerate(zip(prims, poses)):
            name = str(obj.get("id", i)) + (f"/{k}" if len(prims) > 1 else "")
            obstacles.append(_primitive(name, str(prim.get("type")), prim.get("dimensions") or [],
                                        T_obj @ _pose(pose, where), where))
    allowed = set()
    acm = data.get("allowed_collision_matrix") or {}
    names, values = acm.get("entry_names") or [], acm.get("entry_values") or []
    if len(values) != len(names) or any(len(row) != len(names) for row in values):
        raise ValueError(f"{source}: allowed_collision_matrix must be {len(names)} × {len(names)} for its entry_names")
    for a, row in zip(names, values):
        for b, ok in zip(names, row):
            if ok is True and a != b:
                allowed.add(frozenset((str(a), str(b))))
    return World(tuple(obstacles), frozenset(allowed), name=Path(source).stem)


def load_moveit_request(path, robot: Robot) -> MotionRequest:
    """The start and joint goal of a MoveIt ``MotionPlanRequest`` YAML file for ``robot``:
    ``start_state.joint_state`` (names and positions; the gripper joint's value, if given, is
    the opening) and ``goal_constraints[0].joint_constraints``. Every arm joint must be given."""
    data, source = _read(path)
    state = (data.get("start_state") or {}).get("joint_state") or {}
    given = dict(zip(state.get("name") or [], state.get("position") or []))
    goals = (data.get("goal_constraints") or [{}])[0].get("joint_constraints") or []
    goal = {c.get("joint_name"): c.get("position") for c in goals}

    def vector(values: Mapping[str, Any], label: str) -> np.ndarray:
        missing = [j for j in robot.joint_names if j not in values]
        if missing:
            raise ValueError(f"{source}: {label} has no value for joints {missing}")
        try:
            return np.array([float(values[j]) for j in robot.joint_names])
        except (TypeError, ValueError):
            raise ValueError(f"{source}: {label} values must be numbers") from None

    g = robot.gripper
    opening = None if g is None or g.joint not in given else float(given[g.joint])
    return MotionRequest(vector(given, "start_state.joint_state"), vector(goal, "goal_constraints[0]"), opening,
                         source)


def load_srdf(path) -> frozenset[frozenset[str]]:
    """The link pairs an SRDF file's ``<disable_collisions link1= link2=>`` elements exempt from
    self-collision checks (whatever their ``reason``), as a :class:`World`'s ``allowed`` takes
    them. External entities are never resolved; a file that is not well-formed XML, or has no
    ``<robot>`` root, is refused with a ValueError naming it."""
    source = str(path)
    try:
        root = etree.parse(source, parser=etree.XMLParser(recover=False, resolve_entities=False, no_network=True)).getroot()
    except (OSError, etree.XMLSyntaxError) as err:
        raise ValueError(f"{source}: not a readable SRDF file ({err})") from None
    if root.tag != "robot":
        raise ValueError(f"{source}: an SRDF's root element is <robot>, got <{root.tag}>")
    pairs = set()
    for k, e in enumerate(root.iter("disable_collisions")):
        a, b = e.get("link1"), e.get("link2")
        if not a or not b:
            raise ValueError(f"{source}: disable_collisions #{k} needs link1 and link2")
        pairs.add(frozenset((a, b)))
    return frozenset(pairs)
