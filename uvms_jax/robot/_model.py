"""The robot model: one arm as data, from its description file plus what the file cannot say.

Split as pinocchio splits a robot (kinematic Model, GeometryModel): the chain is the
kinematics (``uvms_jax.kin.Chain``), the bodies carry the geometry and the mass properties,
the gripper and the hardware profile say how the arm is driven. Every stage receives a
:class:`Robot`; none imports a particular arm.

Bodies are numbered along the chain: ``-1`` the base link (fixed), ``i`` the link moved by
joint ``i`` (its frame is ``chain.T_base_joint0[i]`` at ``q = 0``). The tool frame is fixed to
body ``n - 1``.
A gripper's fingers read from the description (:class:`Finger`) hang from an arm body and slide
with the gripper's opening.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from uvms_jax import kin
from uvms_jax.robot._geometry import Shape

__all__ = ["BodyInertial", "Finger", "Gripper", "Hardware", "Robot", "Shape", "BASE"]

BASE = -1  # body number of the base link


@dataclasses.dataclass(frozen=True)
class BodyInertial:
    """Mass properties fixed to one body, in that body's frame (SI units).

    Attributes:
      body: body number (:data:`BASE` or a joint index).
      mass: [kg].
      com: ``(3,)`` centre of mass [m].
      inertia: ``(xx, yy, zz, xy, xz, yz)`` about the centre of mass [kg·m²].
      volume: displaced water volume [m³] (0: not known; buoyancy ignored).
      cob: ``(3,)`` centre of buoyancy [m] (the centre of mass where not known).
    """

    body: int
    mass: float
    com: tuple[float, float, float]
    inertia: tuple[float, float, float, float, float, float]
    volume: float = 0.0
    cob: tuple[float, float, float] = (0.0, 0.0, 0.0)


@dataclasses.dataclass(frozen=True)
class Gripper:
    """A parallel gripper at the tool frame: one joint sets the gap between two fingers.

    Attributes:
      joint: the gripper joint's name (on the wire and in plans).
      lower, upper: opening limits [m] (0 = closed).
      velocity: opening speed limit [m/s].
      effort: force limit [N].
      finger_size: ``(3,)`` full edges of one finger box [m] in the tool frame: across the
        opening (x), along y, along the approach (z, from the tool frame forward).
    """

    joint: str
    lower: float
    upper: float
    velocity: float
    effort: float = 0.0
    finger_size: tuple[float, float, float] = (0.016, 0.03, 0.08)

    def __post_init__(self) -> None:
        if not (np.isfinite(self.lower) and np.isfinite(self.upper) and self.lower < self.upper):
            raise ValueError(f"gripper {self.joint!r}: limits [{self.lower}, {self.upper}] must be finite, lower < upper")
        if not self.velocity > 0:
            raise ValueError(f"gripper {self.joint!r}: velocity must be > 0 [m/s], got {self.velocity}")
        if len(self.finger_size) != 3 or not min(self.finger_size) > 0:
            raise ValueError(f"gripper {self.joint!r}: finger_size needs 3 positive edges [m], got {self.finger_size}")


_UNIT = 1e-6  # tolerance on a finger axis's length (a unit vector written with 10 digits)


@dataclasses.dataclass(frozen=True)
class Finger:
    """A link moved by the gripper's opening: its prismatic joint (or a mimic of the gripper joint).

    Attributes:
      link: the description's link (URDF) or body (MJCF) name.
      joint: its prismatic (URDF) or slide (MJCF) joint: the gripper joint itself, or one that
        mimics it.
      body: the arm body it hangs from (robot body number, usually ``n - 1``).
      axis: ``(3,)`` unit slide axis in that body's frame.
      multiplier, offset: the finger joint's value is ``multiplier * opening + offset`` [m], the
        opening being the gripper joint's value (1 and 0 for the gripper joint's own finger).
      shapes: its collision shapes (and those of links fixed to it), ``Shape.body == body``,
        poses in the body's frame at finger joint value 0.
    """

    link: str
    joint: str
    body: int
    axis: tuple[float, float, float]
    multiplier: float = 1.0
    offset: float = 0.0
    shapes: tuple[Shape, ...] = ()

    def __post_init__(self) -> None:
        if len(self.axis) != 3 or abs(float(np.linalg.norm(self.axis)) - 1.0) > _UNIT:
            raise ValueError(f"finger {self.link!r}: axis must be a unit 3-vector, got {self.axis}")
        if not (np.isfinite(self.multiplier) and np.isfinite(self.offset)):
            raise ValueError(f"finger {self.link!r}: multiplier and offset must be finite")
        bad = sorted({s.body for s in self.shapes} - {self.body})
        if bad:
            raise ValueError(f"finger {self.link!r}: shapes on bodies {bad}, not its body {self.body}")

    def value(self, opening: float) -> float:
        """The finger joint's value [m] at the gripper's ``opening`` [m]."""
        return self.multiplier * float(opening) + self.offset

    def T(self, opening: float) -> np.ndarray:
        """``(4, 4)`` the finger's displacement in its body's frame at ``opening`` [m]: its
        shapes' poses are ``T(opening) @ shape.T``."""
        T = np.eye(4)
        T[:3, 3] = self.value(opening) * np.asarray(self.axis, dtype=float)
        return T


@dataclasses.dataclass(frozen=True)
class Hardware:
    """How the real arm is addressed: its wire protocol and one device id per actuator.

    Attributes:
      protocol: ``"bpl"`` (Blueprint Lab's Reach protocol) — the one the hardware runner speaks.
      device_ids: joint name → device id, for every arm joint and the gripper.
    """

    protocol: str
    device_ids: tuple[tuple[str, int], ...]

    def __post_init__(self) -> None:
        if self.protocol != "bpl":
            raise ValueError(f"hardware protocol {self.protocol!r} is not supported (supported: 'bpl')")
        ids = [i for _, i in self.device_ids]
        if len(set(ids)) != len(ids) or not all(0 < i < 0xFF for i in ids):
            raise ValueError(f"hardware device ids must be distinct, in 1 … 254, got {dict(self.device_ids)}")

    def device_id(self, joint: str) -> int:
        ids = dict(self.device_ids)
        if joint not in ids:
            raise ValueError(f"hardware profile has no device id for joint {joint!r} (has {sorted(ids)})")
        return ids[joint]


@dataclasses.dataclass(frozen=True, eq=False)  # identity: the chain holds arrays
class Robot:
    """One arm: kinematics, geometry, mass properties, gripper and hardware profile.

    Attributes:
      name: the arm's name.
      chain: base → tool kinematics with position and velocity limits.
      base_link: the base link's (URDF) or body's (MJCF) name in the description.
      link_names: ``(n,)`` the description's link/body moved by each joint.
      effort_limits: ``(n,)`` joint torque/force limits [N·m or N] (0: not given).
      link_radius: radius of the capsules along the links [m]: the collision model where
        ``shapes`` is empty.
      inertials: mass properties per body (empty: the description has none).
      shapes: the collision model read from the description (its primitives and meshes, each
        fixed to a body, see :class:`~uvms_jax.robot.Shape`); empty: capsules of
        ``link_radius`` along the links (the description has no collision geometry, or a mesh
        of it cannot be read, or the caller asked for capsules).
      gripper: the gripper at the tool frame, or None.
      fingers: the gripper's fingers read from the description (with the collision model read
        from it); empty: the gripper's ``finger_size`` boxes stand for them.
      hardware: the real arm's wire profile, or None (simulation only).
      source: where the description came from (a path, or ``"<text>"``).
      digest: SHA-256 of the description's bytes (a plan records it).
    """

    name: str
    chain: kin.Chain
    base_link: str
    link_names: tuple[str, ...]
    effort_limits: tuple[float, ...]
    link_radius: float
    inertials: tuple[BodyInertial, ...] = ()
    shapes: tuple[Shape, ...] = ()
    gripper: Gripper | None = None
    hardware: Hardware | None = None
    source: str = "<text>"
    digest: str = ""
    fingers: tuple[Finger, ...] = ()

    def __post_init__(self) -> None:
        n = self.chain.n_joints
        if len(self.link_names) != n or len(self.effort_limits) != n:
            raise ValueError(f"robot {self.name!r}: {n} joints but {len(self.link_names)} link names and "
                             f"{len(self.effort_limits)} effort limits")
        if not self.link_radius > 0:
            raise ValueError(f"robot {self.name!r}: link_radius must be > 0 [m], got {self.link_radius}")
        bad = sorted({s.body for s in self.shapes} - set(range(BASE, n)))
        if bad:
            raise ValueError(f"robot {self.name!r}: shapes on bodies {bad}, not -1 … {n - 1}")
        if self.fingers and self.gripper is None:
            raise ValueError(f"robot {self.name!r}: fingers without a gripper")
        bad = sorted({f.body for f in self.fingers} - set(range(BASE, n)))
        if bad:
            raise ValueError(f"robot {self.name!r}: fingers on bodies {bad}, not -1 … {n - 1}")
        if self.gripper is not None and self.gripper.joint in self.joint_names:
            raise ValueError(f"robot {self.name!r}: gripper joint {self.gripper.joint!r} is also an arm joint")
        if self.hardware is not None:
            for j in self.actuators:
                self.hardware.device_id(j)

    @property
    def n_joints(self) -> int:
        return self.chain.n_joints

    @property
    def joint_names(self) -> tuple[str, ...]:
        return tuple(self.chain.joint_names)

    @property
    def actuators(self) -> tuple[str, ...]:
        """Every driven joint: the arm's, then the gripper's."""
        return self.joint_names + ((self.gripper.joint,) if self.gripper is not None else ())

    @property
    def max_reach(self) -> float:
        """An upper bound of the tool's distance from the base origin [m]: the lengths between
        consecutive joint origins and to the tool, plus every prismatic joint's travel."""
        frames = np.asarray(self.chain.T_base_joint0, dtype=float)
        points = np.concatenate([np.zeros((1, 3)), frames[:, :3, 3], np.asarray(self.chain.T_base_tool0)[None, :3, 3]])
        travel = sum(float(u - lo) for u, lo, k in zip(self.upper, self.lower, self.chain.kinds) if k == "prismatic")
        return float(np.sum(np.linalg.norm(np.diff(points, axis=0), axis=1))) + travel

    @property
    def lower(self) -> np.ndarray:
        return np.asarray(self.chain.lower, dtype=float)

    @property
    def upper(self) -> np.ndarray:
        return np.asarray(self.chain.upper, dtype=float)

    @property
    def velocity_limits(self) -> np.ndarray:
        return np.asarray(self.chain.velocity_limits, dtype=float)

    def record(self) -> dict:
        """What a plan or a results file records of the arm: name, joints, gripper, source, digest."""
        g = self.gripper
        return {"name": self.name, "dof": self.n_joints, "joint_names": list(self.joint_names),
                "gripper": None if g is None else {"joint": g.joint, "lower_m": g.lower, "upper_m": g.upper,
                                                   "velocity_mps": g.velocity},
                "source": self.source, "sha256": self.digest}
