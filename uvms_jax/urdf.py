"""A moving joint as a URDF writes it: the record :mod:`uvms_jax.kin` builds chains from and
exports (``kin.chain_from_urdf_joints``, ``kin.to_urdf``), and the row type of the Bravo 7's
joint table (:mod:`uvms_jax.bravo7`, which adds the BPL device id). Plain Python, no JAX.
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["PRISMATIC", "REVOLUTE", "UrdfJoint"]

REVOLUTE = "revolute"
PRISMATIC = "prismatic"


@dataclass(frozen=True)
class UrdfJoint:
    """One moving joint as a URDF writes it.

    Attributes:
      name: the joint's name.
      xyz: joint origin in the parent link frame [m].
      rpy: joint origin orientation, URDF roll-pitch-yaw [rad].
      axis: joint axis in the joint frame (unit vector).
      lower, upper: position limits [rad, or m for a prismatic joint].
      velocity: URDF speed limit [rad/s, or m/s].
      effort: URDF effort limit [N·m, or N].
      kind: :data:`REVOLUTE` or :data:`PRISMATIC`.
    """

    name: str
    xyz: tuple[float, float, float]
    rpy: tuple[float, float, float]
    axis: tuple[float, float, float]
    lower: float
    upper: float
    velocity: float = 1.0
    effort: float = 1.0
    kind: str = REVOLUTE
