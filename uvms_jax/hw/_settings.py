"""Settings of the hardware runner, in one place.

:class:`ExecutorSettings` (executor and link) and :class:`SimSettings` (simulated arm and its
faults) are the single source of the defaults; :class:`HwSettings` holds both, shaped like
``configs/hw/default.yaml`` (a test keeps the two equal), so that
``uvms_jax.settings.from_mapping(HwSettings, d, "hw")`` builds them from a plain dict, as every
stage's settings are built.
"""

from __future__ import annotations

import dataclasses
import math
import numbers

from uvms_jax.settings import check_fields, setting

__all__ = ["ExecutorSettings", "HwSettings", "SimSettings"]


@dataclasses.dataclass(frozen=True)
class ExecutorSettings:
    """Executor, safety and link settings.

    Attributes:
      rate_hz: streaming rate of position demands and state requests [Hz].
      gate_threshold_rad: reached-gate threshold on every arm encoder [rad] (thesis 4.6).
      gate_threshold_mm: reached-gate threshold on the jaws [mm].
      gate_timeout_s: longest wait for the gate after a move's profile has ended [s].
      tracking_error_rad: abort if any encoder lags its demand by more than this while
        moving [rad].
      link_timeout_s: abort if no complete state has arrived for this long [s].
      request_timeout_s: wait for one request's responses before retrying [s].
      status_period_s: how often hardware status is read while running [s].
      speed_scale: fraction (0, 1] of the joints' velocity and acceleration limits the
        executor uses.
      continuity_tol_rad: largest allowed jump between a segment's first waypoint and the
        previous segment's last [rad].
      start_tolerance_rad: largest allowed distance of the measured start from the plan's
        first waypoint unless ``approach`` is set [rad].
      approach: move to the plan's first waypoint first (limit-checked like any move).
      connect_retries: state requests tried before the link is declared down at start.
      limit_margin_rad: abort if a measured arm angle leaves its limits by more than this [rad].
      limit_margin_mm: the same for the jaws [mm].
      grip_settle_s: a closing jaws step also passes its gate when the jaws stop short of the
        goal on an object: their position changed by less than ``gate_threshold_mm`` for this
        long after the profile ended [s]. Later gates then expect the jaws at that opening.
      stream_hz: 0: read the state by a request every tick; otherwise the joints stream
        POSITION and VELOCITY at this rate [Hz] (heartbeat, 1..255) and the executor reads
        the stream, sending no request per tick.
      max_state_age_s: when some answers to a state or status request are lost (each device
        answers in its own datagram), the newest answers up to this old complete it [s].
      plausible_speed_factor: a measured state is trusted only if no joint moved more than
        this factor × its speed limit × the time since the last trusted state (at least one
        tick), plus the gate threshold, and no measured speed exceeds this factor × its limit;
        anything else is a corrupted frame that passed the 8-bit CRC, and is skipped.
    """

    rate_hz: float = setting(50.0, gt=0)
    gate_threshold_rad: float = setting(0.01, gt=0)
    gate_threshold_mm: float = setting(0.5, gt=0)
    gate_timeout_s: float = setting(2.0, gt=0)
    tracking_error_rad: float = setting(0.3, gt=0)
    link_timeout_s: float = setting(0.5, gt=0)
    request_timeout_s: float = setting(0.02, gt=0)
    status_period_s: float = setting(0.25, gt=0)
    speed_scale: float = setting(1.0, gt=0, le=1)
    continuity_tol_rad: float = setting(1e-3, gt=0)
    start_tolerance_rad: float = setting(0.05, gt=0)
    approach: bool = False
    connect_retries: int = setting(10, ge=1)
    limit_margin_rad: float = setting(0.05, gt=0)
    limit_margin_mm: float = setting(1.0, gt=0)
    grip_settle_s: float = setting(0.3, gt=0)
    stream_hz: int = setting(0, ge=0, le=255)
    max_state_age_s: float = setting(0.1, gt=0)
    plausible_speed_factor: float = setting(2.0, ge=1)

    def __post_init__(self) -> None:
        check_fields(self)


@dataclasses.dataclass(frozen=True)
class SimSettings:
    """Simulated arm: servo, physics and fault injection.

    Attributes:
      physics_dt: MuJoCo time step [s].
      servo_gain: position-mode gain, commanded joint speed = gain × error [1/s] (saturated
        at the joint's velocity limit).
      drop: probability that an incoming or outgoing datagram is lost.
      corrupt: probability that an outgoing datagram has one byte changed.
      latency_s: delay added to every response [s].
      stuck_joint: name of a joint that does not move ("" = none; case ignored, checked
        against the arm by :class:`~uvms_jax.hw.SimArm`).
      fault_joint: name of a joint that reports ``fault_bits`` ("" = none; as ``stuck_joint``).
      fault_bits: hardware-status bits reported by ``fault_joint`` (bytes A–D little-endian,
        :class:`~uvms_jax.hw.HardwareStatus`).
      fault_after_s: simulated time after which the fault appears [s].
      object_width_mm: an object between the jaws: closing jaws stop at this opening, as a
        real gripper stalls on what it grasps [mm] (0 = nothing to grasp).
      dynamics: the links carry the robot's masses and inertias (its description's, e.g. the
        manufacturer's for the Bravo 7) under gravity and buoyancy (along the world's z, see
        ``base_rpy``), so the arm sags under load and its currents show it; False, or an arm
        whose description has none: weightless links.
      water_density: density of the water around the arm for buoyancy [kg/m³] (0: in air).
      base_rpy: orientation of the arm's base frame in the world (whose z is up) as URDF
        roll, pitch, yaw about the fixed x, y, z axes, R = Rz(yaw) Ry(pitch) Rx(roll) [rad];
        gravity acts along the world's −z and buoyancy along its +z. (0, 0, 0): base z up;
        (π, 0, 0): hanging under a vehicle, base z down. Yaw does not change the loads.
      coalesce: send all answers to one datagram in one datagram (a byte stream's view)
        instead of one packet per datagram, as the arm does over UDP.
      seed: seed of the fault-injection random generator.
    """

    physics_dt: float = setting(0.002, gt=0)
    servo_gain: float = setting(8.0, gt=0)
    drop: float = setting(0.0, ge=0, le=1)
    corrupt: float = setting(0.0, ge=0, le=1)
    latency_s: float = setting(0.0, ge=0)
    stuck_joint: str = ""
    fault_joint: str = ""
    fault_bits: int = setting(0, ge=0, le=0xFFFFFFFF)
    fault_after_s: float = setting(0.0, ge=0)
    object_width_mm: float = setting(0.0, ge=0)
    dynamics: bool = True
    water_density: float = setting(1000.0, ge=0)
    base_rpy: tuple[float, float, float] = (0.0, 0.0, 0.0)
    coalesce: bool = False
    seed: int = 0

    def __post_init__(self) -> None:
        check_fields(self)
        for name in ("stuck_joint", "fault_joint"):
            if not isinstance(getattr(self, name), str):
                raise ValueError(f"SimSettings.{name} must be a joint name or empty, got {getattr(self, name)!r}")
        try:
            rpy = tuple(float(v) if isinstance(v, numbers.Real) else math.nan for v in self.base_rpy)
        except TypeError:  # not a sequence
            rpy = ()
        if len(rpy) != 3 or not all(map(math.isfinite, rpy)):
            raise ValueError(f"SimSettings.base_rpy must be 3 finite angles (roll, pitch, yaw) [rad], "
                             f"got {self.base_rpy!r}")
        object.__setattr__(self, "base_rpy", rpy)  # a list or numpy array given: a tuple of floats


@dataclasses.dataclass(frozen=True)
class HwSettings:
    """Both settings of a hardware run, as the ``hw`` config group writes them.

    Attributes:
      executor: executor, safety and link settings.
      sim: simulated arm and its faults (used only on a simulated link).
    """

    executor: ExecutorSettings = ExecutorSettings()
    sim: SimSettings = SimSettings()

