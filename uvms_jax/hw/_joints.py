"""Bravo 7 joint table for the hardware path and the send-side limit guard.

The limits are those of :mod:`uvms_jax.bravo7` (docs/theory.md §1.3), in wire units: joint
order everywhere in ``uvms_jax.hw`` (plans, executor, logs) is G, F, E, D, C, B — device ids
0x07 … 0x02 — then the jaws A (0x01). Revolute joints in rad and rad/s, the jaws in mm and
mm/s, exactly as they travel on the wire.
"""

from __future__ import annotations

import dataclasses
import math
import struct

import numpy as np

from uvms_jax import bravo7

from ._ids import DeviceID

__all__ = [
    "ARM_JOINTS",
    "BRAVO7",
    "JAWS",
    "JointSpec",
    "LimitError",
    "MM_PER_M",
    "check_position",
    "check_velocity",
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
      name: Bravo 7 letter ("A" … "G").
      device_id: BPL device id.
      lower, upper: position limits [rad, or mm for the jaws].
      max_velocity: speed limit [rad/s, or mm/s for the jaws].
      max_acceleration: acceleration limit used by the executor [rad/s², or mm/s²]
        (**default**: the URDF gives none).
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


MM_PER_M = 1e3  # the jaws travel in metres in the URDF, in millimetres on the wire

# The executor's acceleration limit of the revolute joints [rad/s²]: the URDF gives none (default).
_ACCELERATION = 1.0
# The jaws' speed and acceleration on the wire [mm/s, mm/s²]: defaults of the runner, slower
# than the URDF's speed limit.
_JAWS_VELOCITY_MM = 20.0
_JAWS_ACCELERATION_MM = 40.0

# In plan order G, F, E, D, C, B.
ARM_JOINTS: tuple[JointSpec, ...] = tuple(
    JointSpec(j.name, DeviceID(j.device_id), j.lower, j.upper, j.velocity, _ACCELERATION)
    for j in bravo7.ARM_JOINTS)
JAWS = JointSpec(bravo7.JAWS.name, DeviceID(bravo7.JAWS.device_id), bravo7.JAWS.lower * MM_PER_M,
                 bravo7.JAWS.upper * MM_PER_M, _JAWS_VELOCITY_MM, _JAWS_ACCELERATION_MM, unit="mm")
BRAVO7: tuple[JointSpec, ...] = ARM_JOINTS + (JAWS,)


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


def spec_for_device(device_id: int, joints: tuple[JointSpec, ...] = BRAVO7) -> JointSpec:
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
