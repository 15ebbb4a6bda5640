"""Loading a :class:`Robot` from a URDF or MJCF description, the format told by the content.

What comes from the file: the chain from the base to the tip (joint kinds, axes, frames,
position and velocity limits, efforts), the gripper joint's limits, and every link's mass,
centre of mass and inertia (URDF ``<inertial>``, MJCF body inertia), each folded into the
moving body it is fixed to. What comes from the caller (the arm's config): the capsule radius
of the collision model, the fingers' size, the displaced volumes (no description format has
them) and the hardware profile.
"""

from __future__ import annotations

import dataclasses
import hashlib
import logging
import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import mujoco
import numpy as np

from uvms_jax.frames import pose
from uvms_jax.robot._card import ArmKeys, check_arm, read_card
from uvms_jax.robot._geometry import description_shapes, fixed_to
from uvms_jax.robot._model import BASE, BodyInertial, Finger, Gripper, Hardware, Robot
from uvms_jax.robot._parse import (
    build_chain,
    description_bytes,
    mjcf_path_joints,
    read_urdf,
    strict_root,
    urdf_joint,
    urdf_path_joints,
)
from uvms_jax.settings import SettingsError

__all__ = ["DESCRIPTIONS", "load_arm", "load_robot", "robot_from_config", "shipped_arms"]

log = logging.getLogger(__name__)

#: The description files shipped with the package (the Reach Bravo 7, ...).
DESCRIPTIONS = Path(__file__).parent / "descriptions"


def _format(data: bytes, source: str) -> str:
    """``"urdf"`` or ``"mjcf"`` from the root element, parsed strictly; a clear error otherwise."""
    root = strict_root(data, f"robot description {source}")
    if root.tag in ("robot", "mujoco"):
        return "urdf" if root.tag == "robot" else "mjcf"
    raise ValueError(f"robot description {source} has root <{root.tag}>: expected <robot> (URDF) or <mujoco> (MJCF)")


def _inertia_matrix(xx, yy, zz, xy, xz, yz) -> np.ndarray:
    return np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])


def _fold(T_base_part: np.ndarray, mass: float, I_part: np.ndarray, T_base_body: np.ndarray,
          body: int, volume: float = 0.0, cob_part=None) -> BodyInertial:
    """Mass properties given in a part's centre-of-mass frame ``T_base_part`` (at q = 0),
    expressed in the frame of the body they are fixed to."""
    T = np.linalg.inv(T_base_body) @ T_base_part
    R, p = T[:3, :3], T[:3, 3]
    I = R @ I_part @ R.T
    cob = p if cob_part is None else p + R @ np.asarray(cob_part, float)
    return BodyInertial(body, float(mass), tuple(map(float, p)),
                        (float(I[0, 0]), float(I[1, 1]), float(I[2, 2]), float(I[0, 1]), float(I[0, 2]),
                         float(I[1, 2])), float(volume), tuple(map(float, cob)))


def _urdf_robot(urdf, folder: Path | None, base: str | None, tip: str | None, gripper: str | None):
    joints, T_base_tool, base_link = urdf_path_joints(urdf, base, tip)
    robot = urdf.robot
    joint_of = {j.child: j for j in robot.joints}
    # Every link's frame at q = 0 below the base (a breadth-first walk of the tree).
    frames, todo = {base_link: np.eye(4)}, [base_link]
    while todo:
        parent = todo.pop()
        for j in robot.joints:
            if j.parent == parent:
                frames[j.child] = frames[parent] @ (np.eye(4) if j.origin is None else np.asarray(j.origin, float))
                todo.append(j.child)
    bodies = {base_link: BASE, **{j.link: i for i, j in enumerate(joints)}}
    body_frames = {BASE: np.eye(4), **{i: j.frame for i, j in enumerate(joints)}}
    parent_of = {c: j.parent for c, j in joint_of.items()}
    inertials = []
    for link in robot.links:
        body = fixed_to(link.name, parent_of, bodies)  # joints off the path (a gripper's) at q = 0
        if link.inertial is None or body is None or link.name not in frames:
            continue
        origin = np.eye(4) if link.inertial.origin is None else np.asarray(link.inertial.origin, float)
        I = np.asarray(link.inertial.inertia, float) if link.inertial.inertia is not None else np.zeros((3, 3))
        inertials.append((link.name, frames[link.name] @ origin, float(link.inertial.mass or 0.0), I, body))
    grip = None
    if gripper is not None:
        found = [j for j in robot.joints if j.name == gripper]
        if not found:
            raise ValueError(f"gripper joint {gripper!r} not in the URDF (joints: {sorted(j.name for j in robot.joints)})")
        g = urdf_joint(found[0], np.eye(4), found[0].child)
        if g.kind != "prismatic":
            raise ValueError(f"gripper joint {gripper!r} must be prismatic (its opening in metres), it is {g.kind}")
        grip = (g.lower, g.upper, g.speed, g.effort)
    return joints, T_base_tool, base_link, robot.name, inertials, bodies, body_frames, frames, grip, (urdf, folder)


def _mjcf_robot(source, base: str | None, tip: str | None, gripper: str | None):
    spec = mujoco.MjSpec.from_file(str(source)) if isinstance(source, Path) else mujoco.MjSpec.from_string(source)
    tip_site, tip_body = (tip, None) if tip in {s.name for s in spec.sites} else (None, tip)
    joints, T_base_tool, name = mjcf_path_joints(source, base, tip_body, tip_site)
    model = spec.compile()
    data = mujoco.MjData(model)
    data.qpos[:] = 0.0
    mujoco.mj_kinematics(model, data)
    names = [model.body(b).name or f"body{b}" for b in range(model.nbody)]
    base_name = names[0] if base is None else base

    def world(p, xmat) -> np.ndarray:
        return pose(np.reshape(xmat, (3, 3)), p)

    T_base_world = np.linalg.inv(world(data.xpos[names.index(base_name)], data.xmat[names.index(base_name)]))
    bodies = {base_name: BASE, **{j.link: i for i, j in enumerate(joints)}}
    body_frames = {BASE: np.eye(4), **{i: j.frame for i, j in enumerate(joints)}}
    parent_of = {names[b]: names[int(model.body_parentid[b])] for b in range(1, model.nbody)}
    inertials = []
    for b in range(1, model.nbody):
        body = fixed_to(names[b], parent_of, bodies)
        if body is None or model.body_mass[b] <= 0:
            continue
        T_com = T_base_world @ world(data.xipos[b], data.ximat[b])  # principal axes of inertia
        inertials.append((names[b], T_com, float(model.body_mass[b]), np.diag(model.body_inertia[b]), body))
    grip = None
    if gripper is not None:
        jid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, gripper)
        if jid < 0:
            raise ValueError(f"gripper joint {gripper!r} not in the MJCF model")
        if int(model.jnt_type[jid]) != int(mujoco.mjtJoint.mjJNT_SLIDE) or not model.jnt_limited[jid]:
            raise ValueError(f"gripper joint {gripper!r} must be a slide joint with a range (its opening in metres)")
        effort = float(model.jnt_actfrcrange[jid, 1]) if model.jnt_actfrclimited[jid] else 0.0
        grip = (float(model.jnt_range[jid, 0]), float(model.jnt_range[jid, 1]), None, effort)
    frames = {n: T_base_world @ world(data.xpos[b], data.xmat[b]) for b, n in enumerate(names)}
    folder = source.parent if isinstance(source, Path) else None
    return joints, T_base_tool, base_name, name, inertials, bodies, body_frames, frames, grip, (spec, model, folder)


def load_robot(
    description,
    *,
    tip: str | None = None,
    base: str | None = None,
    gripper: str | Mapping[str, Any] | None = None,
    gripper_velocity: float | None = None,
    link_radius: float,
    finger_size=(0.016, 0.03, 0.08),
    buoyancy: Mapping[str, Mapping[str, Any]] | None = None,
    hardware: Mapping[str, Any] | None = None,
    name: str | None = None,
    collision: str = "description",
) -> Robot:
    """A :class:`Robot` from a URDF or MJCF file (or its text); the format is read from the
    root element, not the file name.

    Args:
      description: path to the file, or the XML text.
      tip: the tool frame: a URDF link, an MJCF body or site (default: the only leaf).
      base: the base: a URDF link or an MJCF body (default: the root link / the world body).
      gripper: name of the prismatic (URDF) or slide (MJCF) joint that opens the jaws, below
        the tip, its limits [m] read from the file; or, for a description without one, the
        gripper itself: ``{"joint": NAME, "lower": m, "upper": m, "velocity": m/s}`` (the
        fingers then hang from the tip). None: no gripper.
      gripper_velocity: the gripper's speed limit [m/s]; default: the file's (an MJCF has none).
      finger_size: full edges of one finger box [m] (the fingers' collision shape where the
        description has no hand: see :attr:`Robot.fingers`).
      link_radius: capsule radius of the links' collision model [m] (required: the capsules
        along the links are the collision model where the description's is not used).
      buoyancy: link/body name → ``{"volume": m³, "cob": [x, y, z] m in that link's frame}``.
      hardware: ``{"protocol": "bpl", "device_ids": {joint: id, ...}}``, or None.
      name: the robot's name (default: the file's).
      collision: ``"description"``: the file's collision primitives and meshes
        (:attr:`Robot.shapes`), capsules where it has none or a mesh cannot be read (logged);
        ``"capsules"``: capsules along the links whatever the file has.

    Raises:
      ValueError: a missing file, text that is not URDF or MJCF, unknown names, and every
        error of :func:`chain_from_urdf` / :func:`chain_from_mjcf`.
    """
    data, source = description_bytes(description, "robot description")
    path = None if source == "<text>" else Path(source)
    fmt = _format(data, source)
    in_file = gripper if isinstance(gripper, str) else None
    if fmt == "urdf":
        urdf = read_urdf(path if path is not None else data.decode())
        parts = _urdf_robot(urdf, None if path is None else path.parent, base, tip, in_file)
    else:
        parts = _mjcf_robot(path if path is not None else data.decode(), base, tip, in_file)
    joints, T_base_tool, base_link, file_name, raw_inertials, bodies, body_frames, frames, grip, parsed = parts
    chain = build_chain(joints, T_base_tool, file_name if name is None else name)
    buoyancy = dict(buoyancy or {})
    unknown = sorted(set(buoyancy) - set(frames))
    if unknown:
        raise ValueError(f"buoyancy names links not in the description: {unknown}")
    inertials = []
    for link, T_com, mass, I, body in raw_inertials:
        b = buoyancy.pop(link, None)
        volume, cob = (0.0, None) if b is None else (float(b["volume"]), np.asarray(b["cob"], float))
        cob_com = None if cob is None else np.linalg.inv(T_com) @ frames[link] @ np.r_[cob, 1.0]
        inertials.append(_fold(T_com, mass, I, body_frames[body], body, volume, None if cob is None else cob_com[:3]))
    if buoyancy:  # links named that carry no mass properties in the file
        raise ValueError(f"buoyancy of links {sorted(buoyancy)}: the description gives them no mass properties")
    if collision not in ("description", "capsules"):
        raise ValueError(f"collision must be 'description' or 'capsules', got {collision!r}")
    shapes, fingers = (), ()
    if collision == "description":
        shapes, fingers = description_shapes(chain.name, fmt, parsed, bodies, frames, body_frames, float(link_radius),
                                             in_file)
    else:
        log.info("arm %s: collision model of capsules along the links (radius %g m), as asked", chain.name,
                 float(link_radius))
    gripper_model = None
    if isinstance(gripper, Mapping):
        unknown = sorted(set(gripper) - {"joint", "lower", "upper", "velocity", "effort"})
        if unknown or "joint" not in gripper:
            raise ValueError(f"a gripper given in settings needs joint, lower, upper, velocity (effort optional); "
                             f"got keys {sorted(gripper)}")
        gripper_model = Gripper(str(gripper["joint"]), float(gripper["lower"]), float(gripper["upper"]),
                                float(gripper["velocity"]), float(gripper.get("effort", 0.0)),
                                tuple(float(v) for v in finger_size))
    elif grip is not None:
        lower, upper, speed, effort = grip
        speed = speed if gripper_velocity is None else gripper_velocity
        if speed is None:
            raise ValueError(f"gripper {gripper!r}: the file gives no speed limit; set gripper_velocity [m/s]")
        gripper_model = Gripper(gripper, lower, upper, float(speed), effort, tuple(float(v) for v in finger_size))
    hw = None
    if hardware is not None:
        hw = Hardware(str(hardware["protocol"]), tuple((str(k), int(v)) for k, v in dict(hardware["device_ids"]).items()))
    return Robot(
        name=chain.name,
        chain=chain,
        base_link=base_link,
        link_names=tuple(j.link for j in joints),
        effort_limits=tuple(j.effort for j in joints),
        link_radius=float(link_radius),
        inertials=tuple(inertials),
        shapes=shapes,
        gripper=gripper_model,
        hardware=hw,
        source=source,
        digest=hashlib.sha256(data).hexdigest(),
        fingers=tuple(Finger(**f) for f in fingers),
    )


def shipped_arms() -> list[str]:
    """Names of the arm cards shipped with the package (``uvms_jax/robot/descriptions/*.yaml``)."""
    return sorted(p.stem for p in DESCRIPTIONS.glob("*.yaml"))


def _card(card: str) -> tuple[ArmKeys, Path]:
    """An arm card's checked settings and its folder: a shipped name or a path to a YAML file."""
    path = DESCRIPTIONS / f"{card}.yaml" if card in shipped_arms() else Path(card)
    if not path.is_file():
        raise SettingsError(f"arm card {card!r}: neither a shipped arm ({', '.join(shipped_arms())}) nor a YAML file")
    return read_card(path), path.parent


def robot_from_config(cfg: Mapping[str, Any], where: str = "arm") -> Robot:
    """A :class:`Robot` from an arm's settings: ``card`` (a shipped arm's name, e.g.
    ``bravo7``, or a YAML file of these settings) and/or ``description`` (a URDF or MJCF file;
    in a card, relative to the card) with the keyword arguments of :func:`load_robot` by
    name; keys given beside a card override the card's.

    Raises:
      SettingsError: (a ValueError) a card that does not read, or a key of the settings or the
        card that the schema refuses (:mod:`uvms_jax.robot._card`: unknown, of the wrong type,
        not finite, out of range), named by its key path under ``where`` (a card's key after
        the card's file); ValueError: every error of :func:`load_robot`.
    """
    cfg = {k: os.fspath(v) if isinstance(v, os.PathLike) else v for k, v in cfg.items()}  # a card's, a file's path
    given = check_arm(cfg, where).given()
    folder = Path.cwd()
    if "card" in given:
        card, folder = _card(str(given.pop("card")))
        given = {**card.given(), **given}
    if not given.get("description"):
        raise SettingsError(f"{where}: the settings need `card` (a shipped arm or a YAML card) or `description` (a "
                            "URDF/MJCF file)")
    if given.get("link_radius") is None:
        raise SettingsError(f"{where}: the settings need link_radius [m] for {given['description']}: the radius of "
                            "the capsules along its links (the collision model)")
    description = given.pop("description")
    robot = load_robot(folder / str(description), **given)
    if folder == DESCRIPTIONS:  # a shipped description: named the same on every machine
        robot = dataclasses.replace(robot, source=f"uvms_jax/robot/descriptions/{description}")
    return robot


def load_arm(card: str) -> Robot:
    """A :class:`Robot` from an arm card: a shipped arm's name (:func:`shipped_arms`) or a path."""
    return robot_from_config({"card": card})
