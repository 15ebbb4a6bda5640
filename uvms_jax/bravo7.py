"""The Reach Bravo 7: every number the project knows about the arm, in one place.

Kinematics from the public Blueprint Lab URDF (docs/theory.md §1.3), device ids of the BPL
protocol (docs/theory.md §6) and the size of the project's primitive collision model.
``uvms_jax.kin`` (the POE chain, URDF/MJCF export), ``uvms_jax.plan`` (the collision scene)
and ``uvms_jax.hw`` (joint limits, the simulator) all build on these tables.

Plain Python on purpose: importing this module imports neither JAX nor NumPy, so the
hardware path stays light.

Units: metres and radians; the jaws A move in metres here (the wire speaks millimetres:
``uvms_jax.hw`` converts).
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = [
    "ARM_JOINTS",
    "JAWS",
    "JOINTS",
    "LINK_RADIUS",
    "NAME",
    "TOOL_RPY",
    "TOOL_XYZ",
    "URDF_PI",
    "Joint",
]

NAME = "bravo7"

# The URDF writes π to five decimals; the project keeps its numbers as published.
URDF_PI = 3.14159

REVOLUTE = "revolute"
PRISMATIC = "prismatic"


@dataclass(frozen=True)
class Joint:
    """One joint as the URDF writes it, plus its BPL device id.

    Attributes:
      name: Bravo 7 letter, "A" (jaws) … "G" (base rotate).
      device_id: BPL device id (one byte on the wire).
      xyz: joint origin in the parent link frame [m].
      rpy: joint origin orientation, URDF roll-pitch-yaw [rad].
      axis: joint axis in the joint frame (unit vector).
      lower, upper: position limits [rad, or m for the jaws].
      velocity: URDF speed limit [rad/s, or m/s for the jaws].
      effort: URDF effort limit [N·m, or N for the jaws].
      kind: "revolute" or "prismatic".
    """

    name: str
    device_id: int
    xyz: tuple[float, float, float]
    rpy: tuple[float, float, float]
    axis: tuple[float, float, float]
    lower: float
    upper: float
    velocity: float
    effort: float
    kind: str = REVOLUTE


# URDF velocity and effort limits of the revolute joints (docs/theory.md §1.3).
_V = 0.5
_EFFORT = 9.0

# The six revolute joints in chain order G, F, E, D, C, B (device ids 0x07 … 0x02).
ARM_JOINTS: tuple[Joint, ...] = (
    Joint("G", 0x07, (0.0665, 0.0, 0.078), (0.0, 0.0, 0.0), (0.0, 0.0, -1.0), 0.0, 6.3, _V, _EFFORT),
    Joint("F", 0x06, (-0.046, 0.0, 0.0674), (0.0, 0.0, 0.0), (0.0, 1.0, 0.0), 0.0, 3.5, _V, _EFFORT),
    Joint("E", 0x05, (-0.0052, 0.0, -0.29055), (0.0, 0.0, 0.0), (0.0, 1.0, 0.0), 0.0, 3.5, _V, _EFFORT),
    Joint("D", 0x04, (0.0408, 0.0, 0.09695), (0.0, 0.0, URDF_PI), (0.0, 0.0, -1.0), 0.0, 6.3, _V, _EFFORT),
    Joint("C", 0x03, (-0.0408, 0.0, 0.063), (0.0, 0.0, 0.0), (0.0, 1.0, 0.0), 0.0, 3.5, _V, _EFFORT),
    Joint("B", 0x02, (-0.0408, 0.0, -0.08863), (0.0, URDF_PI, 0.0), (0.0, 0.0, -1.0), 0.0, 6.3, _V, _EFFORT),
)

# Fixed joint from link B to the jaws base frame: the project's tool frame.
TOOL_XYZ: tuple[float, float, float] = (0.0, 0.0, 0.124)
TOOL_RPY: tuple[float, float, float] = (0.0, 0.0, 0.0)

# The jaws A: a prismatic joint hanging from the tool frame, 0 … 35 mm of travel.
JAWS = Joint("A", 0x01, (0.0, 0.0, 0.009), (0.0, 0.0, 0.0), (0.0, 0.0, 1.0), 0.0, 0.035, 0.1, 10.0, PRISMATIC)

# Every actuator in hardware order G, F, E, D, C, B, A.
JOINTS: tuple[Joint, ...] = ARM_JOINTS + (JAWS,)

# Capsule radius of the primitive link shapes [m], in the planning scene and the simulator.
# The links are roughly 0.09 m across at the joint housings (docs/theory.md §1.3) and slimmer
# along the tubes; capsules of 0.045 m make the wrist capsules (D, E) touch link B in poses the
# real arm reaches (the thesis's grasps among them), so the model uses 0.04 m.
LINK_RADIUS = 0.04
