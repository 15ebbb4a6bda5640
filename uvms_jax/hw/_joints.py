"""An arm's joint table for the hardware path (:func:`joint_specs`) and the send-side limit guard.

The limits are the robot's (:class:`uvms_jax.robot.Robot`), in wire units: joint order
everywhere in ``uvms_jax.hw`` (plans, executor, logs) is the arm's chain order, then the
gripper; device ids come from the robot's hardware profile (the Bravo 7: G … B = 0x07 …
0x02, jaws A = 0x01). Revolute joints in rad and rad/s, the jaws in mm and mm/s, exactly as
they travel on the wire. An arm without a gripper (a tool changer, a suction cup, no tool) has
no jaws in its table: its plans hold still where a gripper would move (dwells).
"""

from __future__ import annotations

import dataclasses
import math
import struct

import numpy as np

from uvms_jax.urdf import REVOLUTE

__all__ = [
    "JointSpec",
    "LimitError",
    "MM_PER_M",
    "check_position",
    "check_velocity",
    "device_ids",
    "joint_specs",
    "spec_for_device",
    "to_f32",
    "wire_position",
    "wire_velocity",
]


class LimitError(ValueError):
    """A demand outside a joint's position or velocity limits; never clipped, always raised."""


@dataclasses.dataclass(frozen=True)
class JointSpec:
    """Limits of one actuator.

    Attributes:
      name: the joint's name in the robot model (and in plans).
      device_id: BPL device id.
      lower, upper: position limits [rad, or mm for the jaws].
      max_velocity: speed limit [rad/s, or mm/s for the jaws].
      max_acceleration: acceleration limit used by the executor [rad/s², or mm/s²]
        (**default**: descriptions give none).
      unit: "rad" or "mm".
    """

    name: str
    device_id: int
    lower: float
    upper: float
    max_velocity: float
    max_acceleration: float
    unit: str = "rad"

    def __post_init__(self) -> None:
        if not (math.isfinite(self.lower) and math.isfinite(self.upper) and self.lower < self.upper):
            raise ValueError(f"joint {self.name}: limits [{self.lower}, {self.upper}] are not an interval")
        if not (self.max_velocity > 0 and self.max_acceleration > 0):
            raise ValueError(f"joint {self.name}: velocity/acceleration limits must be positive")

    def contains(self, value: float) -> bool:
        """Whether ``value`` lies in [lower, upper], compared exactly (NaN never does).

        For a value read off the wire this is the float32 value itself: a limit such as 6.3
        rad, which float32 cannot represent, is not passed by the float32 just above it.
        """
        return self.lower <= value <= self.upper


MM_PER_M = 1e3  # the jaws travel in metres in the robot model, in millimetres on the wire

# The executor's acceleration limit of the revolute joints [rad/s²]: descriptions give none (default).
_ACCELERATION = 1.0
# The jaws' speed and acceleration on the wire [mm/s, mm/s²]: defaults of the runner, at most
# the gripper's speed limit (the Bravo 7's 100 mm/s, the Alpha 5's 50 mm/s: both run at 20).
_JAWS_VELOCITY_MM = 20.0
_JAWS_ACCELERATION_MM = 40.0


def _as_written(value) -> float:
    """A limit as the description writes it: the shortest decimal that the chain's float32
    holds (6.3, not 6.300000190734863), so that the guard compares with the arm's own number."""
    return float(str(np.float32(value)))


def device_ids(robot) -> dict[str, int]:
    """BPL device id of every actuator of ``robot`` (arm joints, then the gripper), by name.

    From ``robot.hardware``; an arm without a hardware profile gets the Reach convention's
    consecutive ids, the first joint highest and the gripper 1 (``n + 1 … 1``), good for the
    simulated links only (:func:`uvms_jax.hw.run_plan` refuses it a real link).
    """
    names = robot.actuators
    if robot.hardware is None:
        return {name: len(names) - k for k, name in enumerate(names)}
    return {name: robot.hardware.device_id(name) for name in names}


def joint_specs(robot) -> tuple[JointSpec, ...]:
    """The hardware path's joint table of ``robot`` (a :class:`uvms_jax.robot.Robot`), in wire units.

    Returns:
      ``(n + 1,)`` specs: the arm joints in chain order (rad, rad/s; acceleration 1 rad/s²,
      a default: descriptions give none), then the gripper (mm, mm/s: its limits × 1000, speed
      ``min(20 mm/s, its limit)``, acceleration 40 mm/s²), device ids from :func:`device_ids`;
      ``(n,)``, the arm joints alone, for an arm without a gripper.

    Raises:
      ValueError: an arm with a prismatic arm joint (the runner drives revolute joints and
        at most one gripper).
    """
    linear = [n for n, k in zip(robot.joint_names, robot.chain.kinds) if k != REVOLUTE]
    if linear:
        raise ValueError(f"robot {robot.name!r}: the hardware runner drives revolute arm joints, {linear} are not")
    ids = device_ids(robot)
    arm = tuple(JointSpec(name, ids[name], _as_written(lo), _as_written(hi), _as_written(v), _ACCELERATION)
                for name, lo, hi, v in zip(robot.joint_names, robot.lower, robot.upper, robot.velocity_limits))
    g = robot.gripper
    if g is None:
        return arm
    jaws = JointSpec(g.joint, ids[g.joint], g.lower * MM_PER_M, g.upper * MM_PER_M,
                     min(_JAWS_VELOCITY_MM, g.velocity * MM_PER_M), _JAWS_ACCELERATION_MM, unit="mm")
    return arm + (jaws,)


def to_f32(value: float) -> float:
    """``value`` rounded to float32, as it travels on the wire (inf past float32 range)."""
    try:
        return struct.unpack("<f", struct.pack("<f", value))[0]
    except OverflowError:
        return math.copysign(math.inf, value)


def _f32_inside(value: float, low: float, high: float) -> float:
    """``value`` (inside [low, high]) rounded to the nearest float32 that is also inside.

    Round-to-nearest can land up to half a float32 step outside a limit that float32 cannot
    represent (6.3 → 6.300000190734863); then the neighbouring float32 towards the inside is
    taken instead, at most one step (~5e-7 at 6.3) from ``value``.
    """
    f = to_f32(value)
    if f > high:  # compared in float64, exactly
        return float(np.nextafter(np.float32(f), np.float32(-np.inf)))
    if f < low:
        return float(np.nextafter(np.float32(f), np.float32(np.inf)))
    return f


def wire_position(spec: JointSpec, value: float) -> float:
    """The float32 POSITION demand that goes on the wire for ``value`` [rad or mm]: the nearest
    float32 inside the limits (:func:`_f32_inside`).

    Raises:
      LimitError: ``value`` outside the limits or NaN (never clipped).
    """
    return _f32_inside(check_position(spec, value), spec.lower, spec.upper)


def wire_velocity(spec: JointSpec, value: float) -> float:
    """The float32 VELOCITY demand that goes on the wire for ``value``, inside ±max_velocity.

    Raises:
      LimitError: ``|value|`` above the speed limit or NaN (never clipped).
    """
    return _f32_inside(check_velocity(spec, value), -spec.max_velocity, spec.max_velocity)


def spec_for_device(device_id: int, joints: tuple[JointSpec, ...]) -> JointSpec:
    """The spec of ``device_id``; raises LimitError for a device with no known limits."""
    for j in joints:
        if j.device_id == device_id:
            return j
    raise LimitError(f"no joint limits known for device 0x{int(device_id):02X}")


def check_position(spec: JointSpec, value: float) -> float:
    """Return ``value`` if it is inside ``spec``'s position limits, else raise LimitError."""
    if not spec.contains(value):
        raise LimitError(
            f"position demand {value!r} {spec.unit} for joint {spec.name} (device 0x{spec.device_id:02X}) "
            f"outside limits [{spec.lower}, {spec.upper}]"
        )
    return value


def check_velocity(spec: JointSpec, value: float) -> float:
    """Return ``value`` if ``|value| ≤ max_velocity``, else raise LimitError."""
    if not abs(value) <= spec.max_velocity:
        raise LimitError(
            f"velocity demand {value!r} {spec.unit}/s for joint {spec.name} (device 0x{spec.device_id:02X}) "
            f"exceeds ±{spec.max_velocity}"
        )
    return value
