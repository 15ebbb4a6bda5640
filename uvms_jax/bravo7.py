"""The Reach Bravo 7's published tables: the source and the oracle of its description file.

Kinematics from the public Blueprint Lab URDF (docs/theory.md §1.3), device ids of the BPL
protocol (docs/theory.md §6), and the manufacturer's kinematic and dynamic data (Blueprint Lab,
"Reach Bravo Kinematics and Dynamics", 2020): its standard-DH table and each link's mass,
centre of mass, inertia and buoyancy, given in its own link frames (:func:`uvms_jax.kin.bravo7_inertials` maps them into the URDF
link frames; docs/hardware.md says how, a test proves it).
The stages use the arm as a :class:`uvms_jax.robot.Robot` loaded from its shipped description
(``uvms_jax/robot/descriptions/bravo7.urdf`` and its card), which was written from these
tables; tests check the two against each other. ``kin.bravo7()`` (the papers' reproductions)
builds its chain from the joint table here.

Tables only, in plain Python: every computation on them lives in ``uvms_jax.kin``.

Units: metres and radians; the jaws A move in metres here (the wire speaks millimetres:
``uvms_jax.hw`` converts).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from uvms_jax.urdf import PRISMATIC, UrdfJoint

__all__ = [
    "ARM_JOINTS",
    "DH_BASE_XYZ",
    "DH_INERTIALS",
    "DH_JOINT_SIGNS",
    "DH_LINKS",
    "INERTIAL_BODIES",
    "DHLink",
    "Inertial",
    "JAWS",
    "JOINTS",
    "NAME",
    "TOOL_RPY",
    "TOOL_XYZ",
    "URDF_PI",
    "Joint",
]

NAME = "bravo7"

# The URDF writes π to five decimals; the project keeps its numbers as published.
URDF_PI = 3.14159


@dataclass(frozen=True)
class Joint(UrdfJoint):
    """One joint as the URDF writes it (:class:`uvms_jax.urdf.UrdfJoint`: name "A" (jaws) … "G"
    (base rotate), limits in rad, or m for the jaws), plus its BPL device id ``device_id``
    (one byte on the wire)."""

    device_id: int = field(kw_only=True)


# URDF velocity and effort limits of the revolute joints (docs/theory.md §1.3).
_V = 0.5
_EFFORT = 9.0

# The six revolute joints in chain order G, F, E, D, C, B (device ids 0x07 … 0x02).
ARM_JOINTS: tuple[Joint, ...] = (
    Joint("G", (0.0665, 0.0, 0.078), (0.0, 0.0, 0.0), (0.0, 0.0, -1.0), 0.0, 6.3, _V, _EFFORT, device_id=0x07),
    Joint("F", (-0.046, 0.0, 0.0674), (0.0, 0.0, 0.0), (0.0, 1.0, 0.0), 0.0, 3.5, _V, _EFFORT, device_id=0x06),
    Joint("E", (-0.0052, 0.0, -0.29055), (0.0, 0.0, 0.0), (0.0, 1.0, 0.0), 0.0, 3.5, _V, _EFFORT, device_id=0x05),
    Joint("D", (0.0408, 0.0, 0.09695), (0.0, 0.0, URDF_PI), (0.0, 0.0, -1.0), 0.0, 6.3, _V, _EFFORT, device_id=0x04),
    Joint("C", (-0.0408, 0.0, 0.063), (0.0, 0.0, 0.0), (0.0, 1.0, 0.0), 0.0, 3.5, _V, _EFFORT, device_id=0x03),
    Joint("B", (-0.0408, 0.0, -0.08863), (0.0, URDF_PI, 0.0), (0.0, 0.0, -1.0), 0.0, 6.3, _V, _EFFORT, device_id=0x02),
)

# Fixed joint from link B to the jaws base frame: the project's tool frame.
TOOL_XYZ: tuple[float, float, float] = (0.0, 0.0, 0.124)
TOOL_RPY: tuple[float, float, float] = (0.0, 0.0, 0.0)

# The jaws A: a prismatic joint hanging from the tool frame, 0 … 35 mm of travel.
JAWS = Joint("A", (0.0, 0.0, 0.009), (0.0, 0.0, 0.0), (0.0, 0.0, 1.0), 0.0, 0.035, 0.1, 10.0, kind=PRISMATIC, device_id=0x01)

# Every actuator in hardware order G, F, E, D, C, B, A.
JOINTS: tuple[Joint, ...] = ARM_JOINTS + (JAWS,)


# -- the manufacturer's kinematic and dynamic data ---------------------------------------------


@dataclass(frozen=True)
class DHLink:
    """One row of the manufacturer's standard-DH table: ``Rz(θ) Tz(d) Tx(a) Rx(α)``.

    Attributes:
      d: offset along the previous z [m].
      theta_offset: added to the joint angle, θ = sign·q + theta_offset [rad] (the whole θ for
        the fixed last row).
      a: length along the new x [m].
      alpha: twist about the new x [rad].
    """

    d: float
    theta_offset: float
    a: float
    alpha: float


# θa = atan(5.2/293.55): the elbow's 5.2 mm offset (a thesis table prints 395.55, a typo).
_THETA_A = math.atan2(5.2, 293.55)
# Rows 0…5 turn with the joints G, F, E, D, C, B; row 6 is the fixed step to the jaws.
DH_LINKS: tuple[DHLink, ...] = (
    DHLink(107.4e-3, math.pi, 46.0e-3, math.pi / 2),
    DHLink(0.0, -math.pi / 2 + _THETA_A, 293.6e-3, 0.0),
    DHLink(0.0, -math.pi / 2 - _THETA_A, 40.8e-3, -math.pi / 2),
    DHLink(-160.0e-3, 0.0, 40.8e-3, -math.pi / 2),
    DHLink(0.0, 0.0, 40.8e-3, -math.pi / 2),
    DHLink(-223.5e-3, 0.0, 0.0, math.pi / 2),
    DHLink(0.0, -math.pi / 2, 120.0e-3, 0.0),
)
# How the URDF joint angles q (G…B) turn the DH rows: θ_i = sign_i·q_i + theta_offset_i. The
# base rotate G turns about -z in the URDF and +z in the DH table.
DH_JOINT_SIGNS: tuple[int, ...] = (-1, 1, 1, 1, 1, 1)
# The DH base frame in the URDF base frame (same orientation) [m]: on the G axis, 107.4 mm
# below the F axis (URDF: G at x 66.5 mm; F axis at z 78 + 67.4 = 145.4 mm).
DH_BASE_XYZ: tuple[float, float, float] = (0.0665, 0.0, 0.078 + 0.0674 - 0.1074)


@dataclass(frozen=True)
class Inertial:
    """Mass properties of one link, in one link frame (SI units).

    Attributes:
      mass: [kg].
      com: centre of mass [m].
      inertia: (xx, yy, zz, xy, xz, yz) of the inertia tensor about the centre of mass, axes
        of the frame [kg·m²].
      volume: displaced water volume [m³].
      cob: centre of buoyancy [m].
    """

    mass: float
    com: tuple[float, float, float]
    inertia: tuple[float, float, float, float, float, float]
    volume: float
    cob: tuple[float, float, float]


def _published(mass, com_mm, inertia_kg_mm2, volume_l, cob_mm) -> Inertial:
    """An :class:`Inertial` from the units of the manufacturer's table (mm, kg·mm², L)."""
    return Inertial(mass, tuple(c * 1e-3 for c in com_mm), tuple(i * 1e-6 for i in inertia_kg_mm2),
                    volume_l * 1e-3, tuple(c * 1e-3 for c in cob_mm))


# Links 0 (base) … 7 (jaws, closed), each in the manufacturer's link frame (kin.bravo7_inertials).
DH_INERTIALS: tuple[Inertial, ...] = (
    _published(1.25, (-18, -4, -1), (2108, 2573, 3483, 182, -15, -21), 0.72, (-18, -3, -3)),
    _published(1.55, (17, -7, 57), (11442, 12980, 3202, -484, 3405, -1265), 0.60, (27, -11, 92)),
    _published(1.98, (117, 15, 6), (3960, 69099, 70450, 4200, 3204, -24), 1.94, (145, 35, -1)),
    _published(1.14, (22, -29, 1), (3213, 2327, 4340, -1548, -31, 6), 0.47, (33, -43, -7)),
    _published(1.14, (18, 6, -117), (21232, 22252, 2054, 330, -3738, -1278), 0.51, (20, 12, -140)),
    _published(1.03, (20, -24, 1), (2430, 2026, 3330, -1144, -40, 11), 0.43, (33, -38, -8)),
    _published(1.04, (0, 0, -128), (22359, 22363, 936, 1, -19, 15), 0.48, (0, 0, -152)),
    _published(0.47, (28, -1, 0), (244, 1130, 1178, -12, 0, 1), 0.16, (28, 1, 0)),
)
# The URDF body each manufacturer's link is fixed to: the base, the links turned by G…B, and
# the jaws (given in the tool frame, the jaws closed).
INERTIAL_BODIES: tuple[str, ...] = ("base", "G", "F", "E", "D", "C", "B", "tool")
