"""Bravo 7 joint table for the hardware path (SPEC §1.3) and the send-side limit guard.

Joint order everywhere in ``uvms_jax.hw`` (plans, executor, logs): G, F, E, D, C, B — device
ids 0x07 … 0x02 — then the jaws A (0x01). Revolute joints in rad and rad/s, the jaws in mm and
mm/s, exactly as they travel on the wire.
"""

from __future__ import annotations

import dataclasses
import math
import struct

from ._ids import DeviceID

__all__ = [
    "ARM_JOINTS",
    "BRAVO7",
    "JAWS",
    "JointSpec",
    "LimitError",
    "check_position",
    "check_velocity",
    "spec_for_device",
    "to_f32",
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
        (**default**: SPEC gives none).
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
        """Whether ``value`` as sent on the wire (float32) lies within the float32 limits.

        Rounding to float32 is monotonic, so any float64 value in [lower, upper] passes and
        the device, which sees float32, agrees with this check. NaN never passes.
        """
        return to_f32(self.lower) <= to_f32(value) <= to_f32(self.upper)


_V = 0.5  # URDF velocity limit [rad/s] (SPEC §1.3)
_A = 1.0  # acceleration limit [rad/s²] (default)

# SPEC §1.3 table, in plan order G, F, E, D, C, B.
ARM_JOINTS: tuple[JointSpec, ...] = (
    JointSpec("G", DeviceID.G, 0.0, 6.3, _V, _A),
    JointSpec("F", DeviceID.F, 0.0, 3.5, _V, _A),
    JointSpec("E", DeviceID.E, 0.0, 3.5, _V, _A),
    JointSpec("D", DeviceID.D, 0.0, 6.3, _V, _A),
    JointSpec("C", DeviceID.C, 0.0, 3.5, _V, _A),
    JointSpec("B", DeviceID.B, 0.0, 6.3, _V, _A),
)
# URDF jaws travel 0 … 0.035 m = 0 … 35 mm on the wire; speed and acceleration are defaults.
JAWS = JointSpec("A", DeviceID.A, 0.0, 35.0, 20.0, 40.0, unit="mm")
BRAVO7: tuple[JointSpec, ...] = ARM_JOINTS + (JAWS,)

def to_f32(value: float) -> float:
    """``value`` rounded to float32, as it travels on the wire (inf past float32 range)."""
    try:
        return struct.unpack("<f", struct.pack("<f", value))[0]
    except OverflowError:
        return math.copysign(math.inf, value)


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
