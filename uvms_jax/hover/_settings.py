"""Settings of the hovering vehicle: its hull and thrusters, the station keeping, the water current.

Frames: the world W has z up (gravity along -z); the vehicle frame V has its origin at the
hull's centre of mass (the centre of the hull box), x forward, y to port, z up — the frame in
which ``configs/docking/scene/*.yaml`` place the arm (``mount_xyz``, ``mount_rpy``). Metres,
kilograms, newtons, seconds, radians.

Every default is explained in docs/hover.md; the numbers that make the vehicle with the Bravo 7
neutrally buoyant and level are checked by ``tests/hover`` against :func:`~uvms_jax.hover.trimmed`.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from uvms_jax.settings import setting

__all__ = ["ControllerSettings", "CurrentSettings", "DEFAULT_THRUSTERS", "GRAVITY", "Thruster", "VehicleSettings",
           "NavigationSettings", "WholeBodySettings"]

GRAVITY = 9.81  # [m/s²] the value the arm simulator (uvms_jax.hw) uses too
_UNIT_TOL = 1e-3  # a thruster direction this far from unit length is a typo, not rounding


def _vector(value, n: int, what: str) -> np.ndarray:
    a = np.asarray(value, dtype=float)
    if a.shape != (n,) or not np.all(np.isfinite(a)):
        raise ValueError(f"{what} must be {n} finite numbers, got {value!r}")
    return a


@dataclasses.dataclass(frozen=True)
class Thruster:
    """One fixed thruster on the hull.

    Attributes:
      pos: ``(3,)`` where its thrust acts, in the vehicle frame V [m].
      direction: ``(3,)`` unit vector in V along which a positive command pushes the vehicle
        (used normalised; a norm further than 1e-3 from 1 raises).
      max_thrust: thrust limit [N], the same both ways: commands lie in ``[-max, max]``.
    """

    pos: tuple[float, float, float]
    direction: tuple[float, float, float]
    max_thrust: float = setting(40.0, gt=0)

    def __post_init__(self) -> None:
        _vector(self.pos, 3, "thruster pos")
        d = _vector(self.direction, 3, "thruster direction")
        if abs(float(np.linalg.norm(d)) - 1.0) > _UNIT_TOL:
            raise ValueError(f"thruster direction must be a unit vector, got {self.direction!r} "
                             f"(norm {np.linalg.norm(d):.6g})")
        if not (math.isfinite(self.max_thrust) and self.max_thrust > 0):
            raise ValueError(f"thruster max_thrust must be > 0 [N], got {self.max_thrust}")


def _vectored_layout(half_x: float, half_y: float, vert_x: float, vert_y: float,
                     max_thrust: float) -> tuple[Thruster, ...]:
    """Eight thrusters as on a BlueROV2 Heavy: four horizontal ones at the corners, their thrust
    lines at ±45° to the surge axis (front left, front right, rear left, rear right), then four
    vertical ones (the same order), all in the plane of the centre of mass (z = 0), so that no
    horizontal thrust pitches or rolls the hull."""
    c = math.sqrt(0.5)
    horizontal = [((half_x, half_y, 0.0), (c, -c, 0.0)), ((half_x, -half_y, 0.0), (c, c, 0.0)),
                  ((-half_x, half_y, 0.0), (c, c, 0.0)), ((-half_x, -half_y, 0.0), (c, -c, 0.0))]
    vertical = [((sx * vert_x, sy * vert_y, 0.0), (0.0, 0.0, 1.0)) for sx, sy in ((1, 1), (1, -1), (-1, 1), (-1, -1))]
    return tuple(Thruster(p, d, max_thrust) for p, d in horizontal + vertical)


# The default layout for the 0.9 × 0.7 × 0.4 m hull: horizontal thrusters 0.1 m in from the
# corners, vertical ones on the sides; 40 N each way (docs/hover.md: a T200 at 16 V).
DEFAULT_THRUSTERS = _vectored_layout(0.35, 0.25, 0.25, 0.30, 40.0)


@dataclasses.dataclass(frozen=True)
class VehicleSettings:
    """The hovering vehicle: hull, hydrostatics, the water, thrusters and the arm's mount.

    The hull is a uniform box of ``size`` and ``mass`` centred on V's origin (so MuJoCo's
    equivalent inertia box, from which its fluid model takes the drag areas, is the hull box
    itself). Its buoyancy ``water_density · volume · g`` acts upward at ``cob``.

    The defaults (docs/hover.md) make the vehicle carrying a Reach Bravo 7 at the middle of its
    joint ranges neutrally buoyant and level: ``volume`` = (75 kg + the arm's 9.60 kg) / ρ less
    the arm's own 5.31 L, and ``cob`` forward of the centre of mass by the lever that balances
    the arm's moment (:func:`~uvms_jax.hover.trimmed` computes both for any arm and pose).

    Attributes:
      size: ``(3,)`` the hull box's edges along V's x, y, z [m].
      mass: dry mass of the hull, arm not included [kg].
      volume: water displaced by the hull, arm not included [m³].
      cob: ``(3,)`` the hull's centre of buoyancy in V, i.e. relative to its centre of mass [m];
        its z must be > 0: roll and pitch are left to the hydrostatics, which restore them only
        with the centre of buoyancy above the centre of mass.
      water_density: [kg/m³] (0: no water — no buoyancy, no drag).
      viscosity: dynamic viscosity of the water [Pa·s] (MuJoCo's linear, Stokes-like term).
      gravity: [m/s²] along the world's -z (0: weightless, and no buoyancy).
      thrusters: the thruster layout (default :data:`DEFAULT_THRUSTERS`).
      mount_xyz: ``(3,)`` the arm's base in V [m].
      mount_rpy: ``(3,)`` its orientation in V, URDF roll, pitch, yaw [rad] (default: hanging).
    """

    size: tuple[float, float, float] = setting((0.9, 0.7, 0.4), gt=0)
    mass: float = setting(75.0, gt=0)
    volume: float = setting(0.07929, ge=0)
    cob: tuple[float, float, float] = (0.0341, 0.0005, 0.05)
    water_density: float = setting(1000.0, ge=0)
    viscosity: float = setting(0.0009, ge=0)
    gravity: float = setting(GRAVITY, ge=0)
    thrusters: tuple[Thruster, ...] = DEFAULT_THRUSTERS
    mount_xyz: tuple[float, float, float] = (0.35, 0.0, -0.2)
    mount_rpy: tuple[float, float, float] = (math.pi, 0.0, 0.0)

    def __post_init__(self) -> None:
        if _vector(self.size, 3, "size").min() <= 0:
            raise ValueError(f"size must be 3 positive edges [m], got {self.size!r}")
        if not _vector(self.cob, 3, "cob")[2] > 0:
            raise ValueError(f"cob must lie above the centre of mass (cob z > 0 [m]) for roll and pitch to "
                             f"restore, got {self.cob!r}")
        _vector(self.mount_xyz, 3, "mount_xyz")
        _vector(self.mount_rpy, 3, "mount_rpy")
        for name in ("mass", "volume", "water_density", "viscosity", "gravity"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0):
                raise ValueError(f"{name} must be finite and >= 0, got {value}")
        if not self.mass > 0:
            raise ValueError(f"mass must be > 0 [kg], got {self.mass}")
        if not self.thrusters:
            raise ValueError("thrusters: the vehicle needs at least one")


@dataclasses.dataclass(frozen=True)
class ControllerSettings:
    """Station keeping on (x, y, z, ψ): a PID per axis in the world frame, every ``period``.

    Each gain tuple is ``(x, y, z, ψ)``; the position gains are per metre of error, the yaw
    gains per radian. With the defaults the 84.6 kg vehicle (no added mass in the model; the
    Bravo 7 held still, 12.2 kg·m² about z) has closed-loop poles at −5.0 and −0.45 ± 0.19j
    rad/s in each translation and at −5.0, −1.3 and −0.25 rad/s in yaw, before drag adds its
    damping (docs/hover.md); a 0.3 m step saturates the thrusters, which the allocation handles.

    Attributes:
      enabled: off: the thrusters stay at zero unless a thrust is commanded.
      period: control period [s], a whole number of physics steps.
      kp: proportional gains [N/m, N/m, N/m, N·m/rad].
      kd: derivative gains on the world-frame velocity and the yaw rate [N·s/m …, N·m·s/rad].
      ki: integral gains [N/(m·s) …, N·m/(rad·s)].
      integral_limit: largest force (torque for ψ) the integral term may give [N …, N·m]:
        the integral stops growing there (no wind-up).
      integral_band: the integral grows on an axis only while its error is within this
        [m …, rad]: it trims the steady loads (a current's drag, a residual buoyancy) near the
        reference and stays out of large moves, which it would overshoot.
      level_kp, level_kd: PD gains that hold roll and pitch level [N·m/rad, N·m·s/rad]
        (:func:`~uvms_jax.hover.level_attitude`); 0, 0: the hydrostatics alone.
    """

    enabled: bool = True
    period: float = setting(0.02, gt=0)
    kp: tuple[float, float, float, float] = setting((400.0, 400.0, 400.0, 100.0), ge=0)
    kd: tuple[float, float, float, float] = setting((500.0, 500.0, 500.0, 80.0), ge=0)
    ki: tuple[float, float, float, float] = setting((100.0, 100.0, 100.0, 20.0), ge=0)
    integral_limit: tuple[float, float, float, float] = setting((60.0, 60.0, 60.0, 15.0), ge=0)
    integral_band: tuple[float, float, float, float] = setting((0.25, 0.25, 0.25, 0.25), ge=0)
    level_kp: float = setting(600.0, ge=0)
    level_kd: float = setting(110.0, ge=0)

    def __post_init__(self) -> None:
        for name in ("kp", "kd", "ki", "integral_limit", "integral_band"):
            a = np.asarray(getattr(self, name), dtype=float)
            if a.shape != (4,) or not np.all(np.isfinite(a)) or np.any(a < 0):
                raise ValueError(f"{name} must be 4 finite numbers >= 0 (x, y, z, yaw), got {getattr(self, name)!r}")
        if not (math.isfinite(self.period) and self.period > 0):
            raise ValueError(f"period must be > 0 [s], got {self.period}")


@dataclasses.dataclass(frozen=True)
class WholeBodySettings:
    """The whole-body controller (:mod:`uvms_jax.hover._wbc`, docs/hover.md): the tool's pose
    first, station keeping in its null space, model-based feed-forward on the thrusters.

    Attributes:
      tool_gain: share of the tool's pose error the arm's reference removes per control
        period (``K₁ = tool_gain / period``), in (0, 1].
      station_gain: ``K₂`` [1/s], the rate at which the second task asks the vehicle back to
        the docked pose (``v₂ = −K₂ η``); the thrusters' PID (:class:`ControllerSettings`)
        tracks that velocity.
      vehicle_weight: weight of the vehicle's coordinates against the arm's (1) in the first
        task's weighted pseudo-inverse; small: the arm moves the tool, the vehicle barely.
      damping: damped least squares of the first task near singularities [m].
      orientation_length: the length [m] a radian of the tool's orientation weighs against a
        metre of its position in the first task: where the arm's free joints cannot do the
        whole 6-D task (joints at their bounds), the least squares keeps the position first.
        Where they can, the weighting changes nothing (and nothing of the null space).
      servo_lead_s: the arm's targets lead its reference by this much of its rate [s]: a
        position servo ``kp (q* − q) − kv q̇`` lags a ramp by ``kv/kp`` (0.03 s for the hover
        model's servos).
      prediction_s: the vehicle's pose is predicted this far ahead from its velocity [s].
      feed_forward: add the feed-forward wrench (the arm's inverse dynamics along the plan,
        hydrostatics, the current's drag and added mass) to the thrusters' demand.
      added_mass: ``(3,)`` the hull's added mass along V's x, y, z [kg] for the feed-forward
        (0: the hover model has none, docs/hover.md).
      smoothing_s: the plan's joint angles are averaged over this window [s] (a box, twice:
        triangular weights) before their rates and accelerations go into the feed-forward: the
        plan's waypoints are joined by straight lines, whose corners would ask for one period of
        an acceleration the servos spread over several; 0: none.
    """

    tool_gain: float = setting(1.0, gt=0, le=1)
    station_gain: float = setting(0.5, ge=0)
    vehicle_weight: float = setting(0.01, gt=0)
    damping: float = setting(1e-3, ge=0)
    orientation_length: float = setting(0.1, gt=0)
    servo_lead_s: float = setting(0.03, ge=0)
    prediction_s: float = setting(0.02, ge=0)
    feed_forward: bool = True
    added_mass: tuple[float, float, float] = setting((0.0, 0.0, 0.0), ge=0)
    smoothing_s: float = setting(0.06, ge=0)

    def __post_init__(self) -> None:
        if not 0 < self.tool_gain <= 1:
            raise ValueError(f"tool_gain must lie in (0, 1], got {self.tool_gain}")
        for name in ("station_gain", "damping", "servo_lead_s", "prediction_s", "smoothing_s"):
            if not (math.isfinite(getattr(self, name)) and getattr(self, name) >= 0):
                raise ValueError(f"{name} must be finite and >= 0, got {getattr(self, name)}")
        for name in ("vehicle_weight", "orientation_length"):
            if not (math.isfinite(getattr(self, name)) and getattr(self, name) > 0):
                raise ValueError(f"{name} must be > 0, got {getattr(self, name)}")
        if np.any(_vector(self.added_mass, 3, "added_mass") < 0):
            raise ValueError(f"added_mass must be >= 0 [kg], got {self.added_mass!r}")


@dataclasses.dataclass(frozen=True)
class NavigationSettings:
    """The vehicle's pose as its navigation gives it: fixes at a rate, late and noisy, like a
    vision-based relative fix, fused with dead reckoning on the vehicle's velocity (as a DVL and
    a gyro give it, taken as exact here).

    Attributes:
      rate_hz: fixes per second [Hz].
      latency_s: a fix arrives this long after the instant it describes [s].
      position_noise_m: standard deviation of a fix's position on each axis [m].
      angle_noise_deg: standard deviation of a fix's orientation about each axis [°].
      fix_gain: the share of a fix's innovation the estimate takes, in (0, 1]
        (:class:`~uvms_jax.hover.NavigationEstimate`; 1: the newest fix carried forward). It sets
        the filter's time constant, ``1 / (rate_hz · fix_gain)`` (1.7 s by default), and is the
        steady-state Kalman gain ``g²/(1 − g) = σ_w²/σ_fix²`` for dead reckoning that wanders by
        ``σ_w`` between fixes: the default 0.02 stands for 0.1 mm per fix (0.55 mm/√s), a DVL
        and gyro at hovering speeds (docs/hover.md, "Navigation").
      seed: the noise's random seed.
    """

    rate_hz: float = setting(30.0, gt=0)
    latency_s: float = setting(0.05, ge=0)
    position_noise_m: float = setting(0.005, ge=0)
    angle_noise_deg: float = setting(0.2, ge=0)
    fix_gain: float = setting(0.02, gt=0, le=1)
    seed: int = 0

    def __post_init__(self) -> None:
        for name in ("rate_hz", "latency_s", "position_noise_m", "angle_noise_deg"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0) or (name == "rate_hz" and not value > 0):
                raise ValueError(f"{name} must be finite and {'> 0' if name == 'rate_hz' else '>= 0'}, got {value}")
        if not 0 < self.fix_gain <= 1:
            raise ValueError(f"fix_gain must lie in (0, 1], got {self.fix_gain}")


@dataclasses.dataclass(frozen=True)
class CurrentSettings:
    """The water's velocity in the world frame: constant, or piecewise linear in time.

    Attributes:
      velocity: ``(3,)`` a constant current [m/s].
      times: ``(k,)`` strictly increasing times [s] of a profile (empty: the constant).
      velocities: ``(k, 3)`` the current at those times [m/s]; linear in between, held before
        the first and after the last. A profile replaces ``velocity``, which must then stay 0.
    """

    velocity: tuple[float, float, float] = (0.0, 0.0, 0.0)
    times: tuple[float, ...] = ()
    velocities: tuple[tuple[float, float, float], ...] = ()

    def __post_init__(self) -> None:
        v = _vector(self.velocity, 3, "current velocity")
        t = np.asarray(self.times, dtype=float)
        if len(self.velocities) != t.size:
            raise ValueError(f"current: {t.size} times but {len(self.velocities)} velocities")
        if t.size:
            if np.any(v != 0):
                raise ValueError("current: give either a constant velocity or a profile (times, velocities), not both")
            if not np.all(np.isfinite(t)) or np.any(np.diff(t) <= 0):
                raise ValueError(f"current times must be finite and strictly increasing, got {self.times!r}")
            for k, row in enumerate(self.velocities):
                _vector(row, 3, f"current velocities[{k}]")

    @classmethod
    def gusty(cls, mean, gust_m_s: float, gust_s: float, duration_s: float, seed: int = 0) -> "CurrentSettings":
        """A steady ``mean`` ``(3,)`` current [m/s] with gusts: a profile whose knots, every
        ``gust_s`` [s] from 0 to past ``duration_s`` [s], add to the mean a horizontal velocity of
        Gaussian components with standard deviation ``gust_m_s`` [m/s] (seeded: repeatable); linear
        in between. ``gust_m_s = 0`` gives the steady current as a profile."""
        if not (math.isfinite(gust_m_s) and gust_m_s >= 0 and gust_s > 0 and duration_s >= 0):
            raise ValueError(f"gusty current: gust_m_s >= 0, gust_s > 0 and duration_s >= 0 needed, got "
                             f"{gust_m_s}, {gust_s}, {duration_s}")
        times = gust_s * np.arange(int(np.ceil(duration_s / gust_s)) + 2)
        rng = np.random.default_rng(seed)
        gusts = np.concatenate([rng.normal(0.0, gust_m_s, (len(times), 2)), np.zeros((len(times), 1))], axis=1)
        velocities = _vector(mean, 3, "current mean") + gusts
        return cls(times=tuple(map(float, times)), velocities=tuple(tuple(map(float, v)) for v in velocities))

    def profile(self) -> tuple[np.ndarray, np.ndarray]:
        """``(times (k,) [s], velocities (k, 3) [m/s])``: the current as a piecewise-linear
        profile (a constant is one knot)."""
        if not self.times:
            return np.zeros(1), np.asarray(self.velocity, dtype=float)[None, :]
        return np.asarray(self.times, dtype=float), np.asarray(self.velocities, dtype=float)
