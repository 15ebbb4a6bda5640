"""A plan's hovering runs with a controller in the loop, many at once, in one MJX call.

:func:`batch_controlled` is the batch form of :func:`~uvms_jax.hover.run_plan_hovering`: every
scenario (a current, a controller, navigation noise on or off) at every docked pose runs the
plan in one ``jax.jit(jax.vmap(jax.vmap(rollout)))`` call, ``lax.scan`` over control periods,
with no host round trip. Each period of a scenario:

- the current and its rate at the period's start (a piecewise-linear profile per scenario,
  :func:`~uvms_jax.hover.current_at`; every physics step takes the current of its own time, as
  :class:`~uvms_jax.hover.HoverSim` does);
- the navigation estimate (:func:`nav_schedule`, :func:`_nav_update`): fixes at their rate,
  late and noisy, fused with exact dead reckoning, as :class:`~uvms_jax.hover.NavigationEstimate`
  computes it (its random draws are JAX's, so a noisy run is not the CPU's draw for draw);
- the commands: the whole-body controller's period (:meth:`WholeBody.step
  <uvms_jax.hover.WholeBody.step>`), or the plan replayed on the servos with the PID's thrusts
  (:meth:`WholeBody.thrust <uvms_jax.hover.WholeBody.thrust>`), with or without the
  feed-forward — the same methods and :mod:`~uvms_jax.hover._wbc` formulas the CPU runs, with
  ``xp=jax.numpy``; the docked pose, the ballast and the plan's tables enter them as traced
  arrays, so poses and plans vary across the batch;
- the physics steps (:meth:`HoverMJX.physics_step <uvms_jax.hover.HoverMJX.physics_step>`, each
  ending with the next one's position stage, so the kinematics at the period's end come free);
- the tool's world pose against its planned path, kept at the gates; the largest errors and the
  limit counts over the run.

A scenario's controller is a traced index, so one compiled program runs all three controllers
(a batch of one controller computes only its own).
"""

from __future__ import annotations

import copy
import dataclasses
import time as _time
import types
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from uvms_jax.robot import Robot

from ._batch import HoverMJX, hover_mjx, mjx
from ._control import LIMIT_SLACK
from ._hydro import current_at
from ._model import buoyancy_bodies, trimmed
from ._plan import follow_tool_path, plan_targets
from ._settings import ControllerSettings, NavigationSettings, VehicleSettings, WholeBodySettings
from ._wbc import pose_error
from ._wholebody import WholeBody

__all__ = ["CONTROLS", "ControlledResult", "CurrentRanking", "batch_controlled", "nav_schedule", "rank_by_current"]

CONTROLS = ("pid", "feed_forward", "whole_body")  # a scenario's controller: its index here
# The plan's per-period tables of WholeBody that vary with the plan (traced in the batch).
_PLAN_TABLES = ("T_tool", "tool_rate", "momentum_rate", "T_link", "body_com", "body_frame", "body_cvel", "root_com")


# -- navigation -----------------------------------------------------------------------------------
def nav_schedule(navigation: NavigationSettings, period: float, periods: int) -> tuple[np.ndarray, np.ndarray, int]:
    """When each navigation fix arrives and which instant it describes, for ``periods`` control
    periods of ``period`` [s], as :class:`~uvms_jax.hover.NavigationEstimate` times them (float64
    on the host, so the device's float32 time never shifts a fix by a period).

    Returns:
      ``(rows (periods, m), ids (periods, m), history)``: at period k the fixes ``ids[k]`` arrive,
      each describing the state recorded at period ``rows[k]`` (−1: no fix in that slot; m the
      most fixes one period receives); ``history`` the periods of state a scenario must keep.
    """
    s = navigation
    fixes: list[list[tuple[int, int]]] = [[] for _ in range(periods)]
    j, k = 0, 0
    while k < periods:
        if j / s.rate_hz + s.latency_s <= k * period + 1e-12:
            fixes[k].append((int(np.floor(j / s.rate_hz / period + 1e-9)), j))
            j += 1
        else:
            k += 1
    m = max(1, max(len(f) for f in fixes))
    rows, ids = np.full((periods, m), -1, dtype=np.int32), np.zeros((periods, m), dtype=np.int32)
    for k, f in enumerate(fixes):
        for i, (row, fix) in enumerate(f):
            rows[k, i], ids[k, i] = row, fix
    lag = max([k - r for k, f in enumerate(fixes) for r, _ in f], default=0)
    return rows, ids, lag + 1


class NavState(NamedTuple):
    """A scenario's navigation: the estimate ``p (3,)``, ``R (3, 3)``; the true pose at the last
    call (dead reckoning's reference); the last ``history`` periods' true poses and estimates
    (ring buffers indexed by period modulo ``history``)."""

    p: jax.Array
    R: jax.Array
    p_last: jax.Array
    R_last: jax.Array
    truth_p: jax.Array
    truth_R: jax.Array
    est_p: jax.Array
    est_R: jax.Array


def _rotation(rotvec):
    """``(3, 3)`` the rotation by ``rotvec`` (axis × angle [rad]), Rodrigues' formula, smooth at 0."""
    theta2 = rotvec @ rotvec
    theta = jnp.sqrt(jnp.maximum(theta2, 1e-30))
    small = theta2 < 1e-12
    a = jnp.where(small, 1.0 - theta2 / 6.0, jnp.sin(theta) / theta)
    b = jnp.where(small, 0.5 - theta2 / 24.0, (1.0 - jnp.cos(theta)) / jnp.maximum(theta2, 1e-30))
    x, y, z = rotvec
    K = jnp.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]], dtype=rotvec.dtype)
    return jnp.eye(3, dtype=rotvec.dtype) + a * K + b * (K @ K)


def _rotvec(R):
    """``(3,)`` the rotation vector of ``R (3, 3)`` (:func:`~uvms_jax.hover._wbc.pose_error`)."""
    T = jnp.eye(4, dtype=R.dtype).at[:3, :3].set(R)
    return pose_error(T, jnp.eye(4, dtype=R.dtype), xp=jnp)[3:]


def _nav_start(position, R, history: int) -> NavState:
    return NavState(position, R, position, R, jnp.broadcast_to(position, (history, 3)),
                    jnp.broadcast_to(R, (history, 3, 3)), jnp.broadcast_to(position, (history, 3)),
                    jnp.broadcast_to(R, (history, 3, 3)))


def _nav_update(nav: NavState, k, rows, ids, position, R_true, navigation: NavigationSettings, noise, key):
    """The estimate at period ``k`` given the true pose now: dead reckoning, then the fixes
    ``ids`` of the instants ``rows`` (:func:`nav_schedule`'s row k), each drawn with the
    navigation's noise times ``noise`` (0: exact fixes) and taken in with its ``fix_gain``."""
    s, L = navigation, nav.truth_p.shape[0]
    p = nav.p + (position - nav.p_last)
    R = nav.R @ (nav.R_last.T @ R_true)
    slot = k % L
    truth_p, truth_R = nav.truth_p.at[slot].set(position), nav.truth_R.at[slot].set(R_true)
    est_p, est_R = nav.est_p.at[slot].set(p), nav.est_R.at[slot].set(R)
    for i in range(rows.shape[0]):  # static: the most fixes one period receives
        row, valid = rows[i] % L, rows[i] >= 0
        draw = jax.random.normal(jax.random.fold_in(key, ids[i]), (6,), dtype=p.dtype) * noise
        p_fix = truth_p[row] + s.position_noise_m * draw[:3]
        R_fix = truth_R[row] @ _rotation(np.radians(s.angle_noise_deg) * draw[3:])
        gain = jnp.where(valid, s.fix_gain, 0.0)
        p = p + gain * (p_fix - est_p[row])
        R = R @ _rotation(gain * _rotvec(est_R[row].T @ R_fix))
    return NavState(p, R, position, R_true, truth_p, truth_R, est_p, est_R)


# -- the controllers, with traced pose, ballast and plan -------------------------------------------
def _traced(template: WholeBody, pose, tables, volume, cob, feed_forward: bool) -> WholeBody:
    """A copy of ``template`` whose docked pose ``(4,)``, hull ballast (volume [m³], cob (3,) [m])
    and plan tables (``_PLAN_TABLES``) are the traced arrays given."""
    wb = copy.copy(template)
    c, s = jnp.cos(pose[3]), jnp.sin(pose[3])
    zero, one = jnp.zeros_like(c), jnp.ones_like(c)
    R = jnp.stack([jnp.stack([c, -s, zero]), jnp.stack([s, c, zero]), jnp.stack([zero, zero, one])])
    wb.pose = pose
    wb.T_dock = jnp.eye(4, dtype=pose.dtype).at[:3, :3].set(R).at[:3, 3].set(pose[:3])
    for name, value in zip(_PLAN_TABLES, tables):
        if not hasattr(template, name):  # a renamed table would leave the template's in place
            raise AttributeError(f"WholeBody has no plan table {name!r} (_PLAN_TABLES)")
        setattr(wb, name, value)
    wb.vehicle = types.SimpleNamespace(**{**vars(template.vehicle), "volume": volume, "cob": cob})
    wb.settings = dataclasses.replace(template.settings, feed_forward=feed_forward)
    return wb


class _Command(NamedTuple):
    target: jax.Array
    reference: jax.Array
    thrust: jax.Array
    integral: jax.Array
    thrust_limited: jax.Array
    joint_limited: jax.Array


def _commands(controllers: dict, mode, k, p, R, velocity, omega, q_ref, integral, current, rate, q_now, q_next):
    """The commands of the scenario's controller ``mode`` (an index into :data:`CONTROLS`):
    every controller in ``controllers`` (name → :class:`WholeBody`) is evaluated and the
    scenario's is selected (under ``vmap`` a switch would evaluate them all as well)."""
    out = {}
    for name, wb in controllers.items():
        if name == "whole_body":
            c = wb.step(k, p, R, velocity, omega, q_ref, integral, current, rate, xp=jnp)
            out[name] = _Command(c.target, c.reference, c.thrust, c.integral, c.thrust_limited, c.joint_limited)
        else:  # the plan replayed on the servos; the PID's thrusts, with or without the feed-forward
            u, _, i, sat = wb.thrust(k, p, R, velocity, omega, integral, current, rate, xp=jnp)
            out[name] = _Command(q_now, q_next, u, i, sat, jnp.zeros((), bool))
    names = list(out)
    cmd = out[names[0]]
    for name in names[1:]:
        pick = mode == CONTROLS.index(name)
        cmd = jax.tree.map(lambda a, b, pick=pick: jnp.where(pick, a, b), out[name], cmd)
    return cmd


def _slack(limit):
    """The rounding allowed on a value computed onto ``limit`` before it counts as beyond it:
    :data:`LIMIT_SLACK` in float64; in float32 a few units of its last place (the scaled
    allocation puts a thruster at its limit ±1 ulp, 40 N ± 4e-6 N)."""
    return LIMIT_SLACK + 4 * jnp.finfo(limit.dtype).eps * jnp.abs(limit)


def _batched_like(tree, anchor):
    """``tree`` with every leaf's value unchanged but computed from ``anchor``, a traced bool
    scalar that is True (``lax.select``: ``jnp.where`` returns an empty leaf as it is).

    Under ``vmap``, every leaf of a scan's starting carry is then batched along each axis
    ``anchor`` is, and ``lax.scan``'s batching rule batches the scan's body once. From a carry
    only partly batched it batches the body again for every round of carry fields it finds
    batched after the last (twice or more per ``vmap``, the physics scan inside each time).
    """
    return jax.tree.map(lambda x: jax.lax.select(jax.lax.broadcast_in_dim(anchor, x.shape, ()), x, x), tree)


# -- one scenario ---------------------------------------------------------------------------------
class _Carry(NamedTuple):
    data: mjx.Data
    integral: jax.Array
    q_ref: jax.Array
    nav: NavState | None
    gate_error: jax.Array  # (g,) [m]
    gate_angle: jax.Array  # (g,) [rad]
    gate_joint: jax.Array  # (g,) [rad]
    worst: jax.Array  # (4,): tool error [m], tool angle [rad], drift [m], joint angle past a limit [rad]
    peak_thrust: jax.Array  # [N]
    counts: jax.Array  # (4,) int: thrust-limited, joint-limited periods, thrust and joint violations


@dataclasses.dataclass(frozen=True, eq=False)
class _Rollout:
    """One scenario's run (pure; ``vmap`` it): the constants shared by the batch."""

    sim: HoverMJX
    templates: dict  # controller name → WholeBody (its static parts)
    navigation: NavigationSettings | None
    fix_rows: np.ndarray  # (P, m) int
    fix_ids: np.ndarray  # (P, m) int
    history: int
    gate_rows: np.ndarray  # (g,) int: the record row of each gate

    def __call__(self, pose, tables, hull_volume, hull_cob, volume, cob, q_plan, gate_q, times, knots, mode, noise,
                 key, record: bool = False):
        sim, c = self.sim, jnp.asarray
        dtype = sim.dtype
        pose, q_plan = c(pose, dtype), c(q_plan, dtype)
        controllers = {name: _traced(t, pose, tables, hull_volume, hull_cob, name != "pid")
                       for name, t in self.templates.items()}
        wb = next(iter(controllers.values()))
        R_goal = wb.T_dock[:3, :3] @ wb.T_tool[:, :3, :3]  # (P + 1, 3, 3) the tool's planned world pose
        p_goal = wb.T_tool[:, :3, 3] @ wb.T_dock[:3, :3].T + wb.T_dock[:3, 3]
        # The carry's data holds the position stage (kinematics included) of its qpos: each
        # physics step ends with the next one's (HoverMJX.integrate), so a period ends with them.
        d = mjx.fwd_position(sim.mx, sim.placed(pose, q_plan[0]))
        nav = None if self.navigation is None else _nav_start(d.qpos[:3], d.xmat[sim.vehicle_id], self.history)
        g = self.gate_rows.size
        carry = _Carry(d, jnp.zeros(4, dtype), q_plan[0], nav, jnp.zeros(g, dtype), jnp.zeros(g, dtype), jnp.zeros(g, dtype),
                       jnp.zeros(4, dtype), jnp.zeros((), dtype), jnp.zeros(4, jnp.int32))
        # Batched over the poses and the scenarios alike (True: both are checked to be finite).
        carry = _batched_like(carry, jnp.isfinite(pose[0] + knots[0, 0]))
        period, steps, dt = sim.period, sim.physics_steps, sim.model.opt.timestep
        lower, upper, limits = c(sim.robot.lower, dtype), c(sim.robot.upper, dtype), c(sim.limits, dtype)

        def one(carry: _Carry, xs):
            k, rows, ids = xs
            d, t = carry.data, k * period
            current = current_at(times, knots, t, xp=jnp)
            rate = (current_at(times, knots, t + period, xp=jnp) - current) / period
            position, R = d.qpos[:3], d.xmat[sim.vehicle_id]
            nav = carry.nav
            if nav is not None:
                nav = _nav_update(nav, k, rows, ids, position, R, self.navigation, noise, key)
                position, R = nav.p, nav.R
            cmd = _commands(controllers, mode, k, position, R, d.qvel[:3], d.qvel[3:6], carry.q_ref, carry.integral,
                            current, rate, q_plan[k], q_plan[k + 1])
            d = d.replace(ctrl=d.ctrl.at[sim.thruster].set(cmd.thrust).at[sim.servo].set(cmd.target))

            def physics(d, j):
                wind = current_at(times, knots, (k * steps + j) * dt, xp=jnp)
                return mjx.fwd_position(sim.mx, sim.integrate(d, wind, volume, cob)), None

            d, _ = jax.lax.scan(physics, d, jnp.arange(steps))
            row = k + 1
            tool_R = d.site_xmat[sim.tool_site].reshape(3, 3)
            error = jnp.linalg.norm(d.site_xpos[sim.tool_site] - p_goal[row])
            angle = jnp.linalg.norm(_rotvec(R_goal[row].T @ tool_R))
            drift = jnp.linalg.norm(d.qpos[:3] - pose[:3])
            q = d.qpos[sim.qadr]
            excess = jnp.max(jnp.maximum(jnp.maximum(lower - q, q - upper), 0.0))
            at_gate = self.gate_rows == row
            joint = jnp.max(jnp.abs(q - gate_q), axis=-1)
            outside = lambda x: (x < lower - _slack(lower)) | (x > upper + _slack(upper))  # noqa: E731
            counts = carry.counts + jnp.stack([
                cmd.thrust_limited, cmd.joint_limited, jnp.any(jnp.abs(cmd.thrust) > limits + _slack(limits)),
                jnp.any(outside(q) | outside(cmd.target))]).astype(jnp.int32)
            carry = _Carry(d, cmd.integral, cmd.reference, nav, jnp.where(at_gate, error, carry.gate_error),
                           jnp.where(at_gate, angle, carry.gate_angle), jnp.where(at_gate, joint, carry.gate_joint),
                           jnp.maximum(carry.worst, jnp.stack([error, angle, drift, excess])),
                           jnp.maximum(carry.peak_thrust, jnp.max(jnp.abs(cmd.thrust))), counts)
            out = (d.qpos[:3], d.qpos[3:7], q, d.site_xpos[sim.tool_site], cmd.thrust, error, angle) if record else None
            return carry, out

        P = self.fix_rows.shape[0]
        carry, recs = jax.lax.scan(one, carry, (jnp.arange(P), c(self.fix_rows), c(self.fix_ids)))
        summary = (carry.gate_error, carry.gate_angle, carry.gate_joint, carry.worst, carry.peak_thrust, carry.counts)
        return summary, recs


# -- the batch ------------------------------------------------------------------------------------
@dataclasses.dataclass(frozen=True)
class ControlledResult:
    """K poses × N scenarios of a plan, a controller in the loop (:func:`batch_controlled`).

    Attributes:
      poses: ``(K, 4)``; current_times: ``(m,)`` [s]; currents: ``(N, m, 3)`` the scenarios'
        current profiles [m/s]; controls: ``(N,)`` names (:data:`CONTROLS`); noisy: ``(N,)``
        navigation noise on.
      gate_times: ``(g,)`` [s]; gate_tool_error ``(K, N, g)`` [m] and gate_tool_angle [rad]: the
        tool's world pose from its planned one at each gate; gate_joint_error: the joints from
        the plan's at each gate [rad].
      max_tool_error, max_tool_angle, max_drift: ``(K, N)`` over the run [m, rad, m];
        max_joint_excess: ``(K, N)`` the farthest a joint went past a limit [rad] (0: none;
        the MJX model has no joint stops, :mod:`~uvms_jax.hover._batch`).
      thrust_limited_periods, joint_limited_periods: ``(K, N)`` periods in which the allocation
        scaled the demand to the thrusters' limits / a joint rate bound was active;
        thrust_violations, joint_violations: periods with a thrust beyond its limit / a joint
        target or angle outside the joint limits (both by more than rounding).
      peak_thrust: ``(K, N)`` [N].
      records: with ``record``, per period's end ``(K, N, P, ...)``: position, quat, q, tool,
        thrust, tool_error, tool_angle; else None.
      env_steps: physics steps × scenarios in the call; compile_s, run_s [s].
    """

    poses: np.ndarray
    current_times: np.ndarray
    currents: np.ndarray
    controls: np.ndarray
    noisy: np.ndarray
    gate_times: np.ndarray
    gate_tool_error: np.ndarray
    gate_tool_angle: np.ndarray
    gate_joint_error: np.ndarray
    max_tool_error: np.ndarray
    max_tool_angle: np.ndarray
    max_drift: np.ndarray
    max_joint_excess: np.ndarray
    thrust_limited_periods: np.ndarray
    joint_limited_periods: np.ndarray
    thrust_violations: np.ndarray
    joint_violations: np.ndarray
    peak_thrust: np.ndarray
    tool_tolerance_m: float
    tool_tolerance_rad: float
    records: dict | None
    env_steps: int
    compile_s: float
    run_s: float

    @property
    def gate_reached(self) -> np.ndarray:
        """``(K, N, g)`` bool: the tool within both tolerances of its planned world pose."""
        return (self.gate_tool_error <= self.tool_tolerance_m) & (self.gate_tool_angle <= self.tool_tolerance_rad)

    @property
    def reasons(self) -> np.ndarray:
        """``(K, N)`` str: why each run would be held (its first gate missed, as
        :class:`~uvms_jax.hover.HoverRun` words it, with the periods the thrusters were at their
        limit: a current beyond what they hold), or ``""`` for a run that reached every gate."""
        out = np.full(self.gate_tool_error.shape[:2], "", dtype=object)
        for k, n in zip(*np.nonzero(~self.gate_reached.all(axis=-1))):
            i = int(np.argmin(self.gate_reached[k, n]))
            e, a = self.gate_tool_error[k, n, i], self.gate_tool_angle[k, n, i]
            miss = (f"the tool is {1e3 * e:.1f} mm from its planned pose (tolerance {1e3 * self.tool_tolerance_m:.0f} mm)"
                    if e > self.tool_tolerance_m else f"the tool is turned {np.degrees(a):.2f}° from its planned pose "
                    f"(tolerance {np.degrees(self.tool_tolerance_rad):.2f}°)")
            limited = self.thrust_limited_periods[k, n]
            out[k, n] = f"gate {i + 1} of {self.gate_times.size}: {miss}" + (
                f"; the thrusters were at their limit in {limited} control periods" if limited else "")
        return out

    @property
    def worst_gate_tool_error(self) -> np.ndarray:
        """``(K, N)`` the largest gate tool error [m] (0 without gates)."""
        return self.gate_tool_error.max(axis=-1, initial=0.0)


_RECORDS = ("position", "quat", "q", "tool", "thrust", "tool_error", "tool_angle")


def _scenarios(currents, current_times, controls, noisy, navigation):
    """Checked ``(times (m,), knots (N, m, 3), modes (N,), noise (N,))``."""
    currents = np.asarray(currents, dtype=float)
    if currents.ndim == 2:
        currents = currents[:, None, :]
    times = np.zeros(1) if current_times is None else np.asarray(current_times, dtype=float).reshape(-1)
    if currents.ndim != 3 or currents.shape[1:] != (times.size, 3) or not np.all(np.isfinite(currents)):
        raise ValueError(f"currents must be (N, 3) or (N, m = {times.size}, 3) finite velocities, got {currents.shape}")
    if times.size > 1 and np.any(np.diff(times) <= 0):
        raise ValueError(f"current_times must be strictly increasing, got {times}")
    N = len(currents)
    controls = np.broadcast_to(np.asarray(controls, dtype=object), (N,))
    if bad := sorted(set(controls) - set(CONTROLS)):
        raise ValueError(f"controls must be among {CONTROLS}, got {bad}")
    noisy = np.broadcast_to(np.asarray(noisy, dtype=bool), (N,))
    if navigation is None and noisy.any():
        raise ValueError("navigation noise asked for without navigation settings")
    return times, currents, controls, noisy


def batch_controlled(robot: Robot, plan, poses, currents, *, controls="whole_body", noisy=False,
                     current_times=None, vehicle: VehicleSettings = VehicleSettings(),
                     controller: ControllerSettings = ControllerSettings(),
                     whole_body: WholeBodySettings = WholeBodySettings(),
                     navigation: NavigationSettings | None = None, joint_plans=None, dwell_s: float = 0.5,
                     gripper_s: float = 1.0, tool_tolerance_m: float = 0.01, tool_tolerance_deg: float = 2.0,
                     seed: int = 0, record: bool = False, sim: HoverMJX | None = None) -> ControlledResult:
    """``plan`` at every docked pose in every scenario, a controller in the loop, in one call.

    Args:
      poses: ``(K, 4)`` docked poses ``[x, y, z, ψ]`` [m, rad].
      currents: ``(N, 3)`` constant currents, or ``(N, m, 3)`` profiles at ``current_times``
        ``(m,)`` [s] (linear between, held beyond) [m/s, world].
      controls: each scenario's controller (one name for all, or ``(N,)``): ``"pid"`` (the plan
        replayed on the servos, the PID's thrusts), ``"feed_forward"`` (the same with the
        feed-forward wrench) or ``"whole_body"`` (:meth:`~uvms_jax.hover.WholeBody.step`).
      noisy: each scenario's navigation noise on (bool or ``(N,)``): the pose comes through
        ``navigation``'s fixes with its noise, or with exact fixes (same rate and latency).
      navigation: None: every controller sees the true pose (``noisy`` must be False).
      joint_plans: ``(K, P + 1, n)`` the joint angles per pose and control period (e.g.
        :func:`~uvms_jax.hover.follow_tool_path` from other poses); None: the plan's at every
        pose. The tool's planned path is their forward kinematics at each docked pose.
      tool_tolerance_m, tool_tolerance_deg: a gate is reached within both [m, °].
      seed: the navigation noise's; record: keep each period's state (memory grows with P).
      sim: a :func:`~uvms_jax.hover.hover_mjx` for ``robot``, ``vehicle`` and ``controller``.

    Raises:
      ValueError: a plan for other joints, bad shapes, an unknown controller, joint plans
        outside the joint limits, noise without navigation.
    """
    if tuple(plan.joint_names) != tuple(robot.joint_names):
        raise ValueError(f"the plan moves {plan.joint_names}, the arm has {robot.joint_names}")
    poses = np.atleast_2d(np.asarray(poses, dtype=float))
    if poses.shape[1:] != (4,) or not np.all(np.isfinite(poses)):
        raise ValueError(f"poses must be (K, 4) finite [x, y, z, psi], got {poses.shape}")
    times, knots, controls, noisy = _scenarios(currents, current_times, controls, noisy, navigation)
    sim = hover_mjx(robot, vehicle, controller) if sim is None else sim
    period, K, n = controller.period, len(poses), robot.n_joints
    targets, gate_times, duration = plan_targets(plan, dwell_s, gripper_s)
    P = round(duration / period) + 1
    if joint_plans is None:
        q = np.broadcast_to(np.array([targets(t) for t in period * np.arange(P + 1)]), (K, P + 1, n))
    else:
        q = np.asarray(joint_plans, dtype=float)
        if q.shape != (K, P + 1, n):
            raise ValueError(f"joint_plans must be (K = {K}, P + 1 = {P + 1}, {n}), got {q.shape}")
    if np.any(q < robot.lower - LIMIT_SLACK) or np.any(q > robot.upper + LIMIT_SLACK):
        raise ValueError("joint plans outside the joint limits")
    gate_rows = np.searchsorted(period * np.arange(P + 1), gate_times - 1e-9).clip(max=P)
    gate_q = (np.broadcast_to(np.array([targets(t) for t in gate_times]).reshape(-1, n), (K, gate_times.size, n))
              if joint_plans is None else q[:, gate_rows])
    per_pose, templates = [], {}
    for k in range(K):
        v = trimmed(vehicle, robot, q[k, 0])
        if k == 0 or joint_plans is not None:
            wb = WholeBody(robot, v, controller, whole_body, poses[k], q[k], sim.model)
        templates = templates or {name: wb for name in CONTROLS if name in set(controls)}
        _, volume, cob = buoyancy_bodies(sim.model, robot, v)
        per_pose.append(([getattr(wb, name) for name in _PLAN_TABLES], v.volume, np.asarray(v.cob), volume, cob))
    tables = [np.stack([p[0][i] for p in per_pose]) for i in range(len(_PLAN_TABLES))]
    hull_volume, hull_cob, volume, cob = (np.stack([p[j] for p in per_pose]) for j in range(1, 5))
    if navigation is None:
        rows, ids, history = np.full((P, 1), -1, np.int32), np.zeros((P, 1), np.int32), 1
    else:
        rows, ids, history = nav_schedule(navigation, period, P)
    rollout = _Rollout(sim, templates, navigation, rows, ids, history, gate_rows)
    modes = np.array([CONTROLS.index(c) for c in controls], dtype=np.int32)
    keys = jax.vmap(lambda i: jax.random.fold_in(jax.random.key(seed), i))(jnp.arange(len(knots)))

    def run(pose, tables, hull_volume, hull_cob, volume, cob, q, gate_q, knots, modes, noise, keys):
        per_scenario = jax.vmap(lambda kn, mo, no, ke: rollout(pose, tables, hull_volume, hull_cob, volume, cob, q,
                                                                gate_q, jnp.asarray(times, sim.dtype), kn, mo, no, ke,
                                                                record=record))
        return per_scenario(knots, modes, noise, keys)

    f = sim.dtype
    args = (jnp.asarray(poses, f), [jnp.asarray(t, f) for t in tables], jnp.asarray(hull_volume, f),
            jnp.asarray(hull_cob, f), jnp.asarray(volume, f), jnp.asarray(cob, f), jnp.asarray(q, f),
            jnp.asarray(gate_q, f), jnp.asarray(knots, f), jnp.asarray(modes), jnp.asarray(noisy, f), keys)
    batch = jax.jit(jax.vmap(run, in_axes=(0,) * 8 + (None,) * 4))
    t0 = _time.perf_counter()
    compiled = batch.lower(*args).compile()
    t1 = _time.perf_counter()
    (gate_error, gate_angle, gate_joint, worst, peak, counts), recs = jax.block_until_ready(compiled(*args))
    t2 = _time.perf_counter()
    a = lambda x: np.asarray(x, dtype=float)  # noqa: E731
    counts = np.asarray(counts)
    return ControlledResult(
        poses=poses, current_times=times, currents=knots, controls=np.asarray(controls, dtype=str), noisy=noisy.copy(),
        gate_times=np.asarray(gate_times, dtype=float), gate_tool_error=a(gate_error), gate_tool_angle=a(gate_angle),
        gate_joint_error=a(gate_joint), max_tool_error=a(worst[..., 0]), max_tool_angle=a(worst[..., 1]),
        max_drift=a(worst[..., 2]), max_joint_excess=a(worst[..., 3]), thrust_limited_periods=counts[..., 0],
        joint_limited_periods=counts[..., 1], thrust_violations=counts[..., 2], joint_violations=counts[..., 3], peak_thrust=a(peak),
        tool_tolerance_m=float(tool_tolerance_m), tool_tolerance_rad=float(np.radians(tool_tolerance_deg)),
        records=dict(zip(_RECORDS, map(a, recs))) if record else None,
        env_steps=int(K * len(knots) * P * sim.physics_steps), compile_s=t1 - t0, run_s=t2 - t1)


# -- docking poses by the current they tolerate ---------------------------------------------------
@dataclasses.dataclass(frozen=True)
class CurrentRanking:
    """Docking poses ranked by the current they tolerate (:func:`rank_by_current`).

    Attributes:
      poses: ``(K, 4)`` the poses given (the docked one first); path_share: ``(K,)`` the share
        of the tool's path each follows (a pose is run when it is 1).
      speeds: ``(S,)`` [m/s]; worst_gate_tool_error: ``(K, S)`` the worst over the directions
        of a run's largest gate tool error [m] (NaN: not run).
      tolerated: ``(K,)`` the largest speed up to which every gate of every direction is
        reached, at that speed and every slower one [m/s] (NaN: not in still water, or not run).
      order: ``(K,)`` the poses, most tolerant first (ties: in the order given); chosen: the
        first of them.
      result: the batch over the poses that were run.
    """

    poses: np.ndarray
    path_share: np.ndarray
    speeds: np.ndarray
    worst_gate_tool_error: np.ndarray
    tolerated: np.ndarray
    order: np.ndarray
    result: ControlledResult

    @property
    def chosen(self) -> int:
        return int(self.order[0])


def rank_by_current(robot: Robot, plan, poses, speeds, directions: int = 8, *, control: str = "whole_body",
                    noisy: bool = True, navigation: NavigationSettings | None = NavigationSettings(),
                    vehicle: VehicleSettings = VehicleSettings(), controller: ControllerSettings = ControllerSettings(),
                    dwell_s: float = 0.5, gripper_s: float = 1.0, **kwargs) -> CurrentRanking:
    """Rank docking ``poses`` ``(K, 4)`` by the current they tolerate, in one
    :func:`batch_controlled` call: the plan at its docked pose ``poses[0]`` and the same tool
    motion from each other pose (:func:`~uvms_jax.hover.follow_tool_path`, as
    :func:`~uvms_jax.hover.batch_candidates`), with ``control``, in currents of every speed in
    ``speeds`` [m/s] from ``directions`` evenly spread horizontal directions. A pose from which
    the tool cannot follow the whole path is not run. ``kwargs`` go to :func:`batch_controlled`.

    Raises:
      ValueError: speeds not increasing from 0, fewer than one direction, and as
        :func:`batch_controlled`.
    """
    speeds = np.asarray(speeds, dtype=float).reshape(-1)
    if speeds.size == 0 or speeds[0] != 0.0 or np.any(np.diff(speeds) <= 0) or directions < 1:
        raise ValueError(f"speeds must increase from 0 and directions be >= 1, got {speeds} and {directions}")
    poses = np.atleast_2d(np.asarray(poses, dtype=float))
    targets, _, duration = plan_targets(plan, dwell_s, gripper_s)
    period = controller.period
    docked = np.array([targets(t) for t in period * np.arange(round(duration / period) + 2)])
    tables, share = [docked], [1.0]
    for p in poses[1:]:
        q, reached = follow_tool_path(robot, vehicle, docked, poses[0], p)
        share.append(float(np.mean(reached)))
        tables.append(q)
    share = np.array(share)
    run = share == 1.0
    angle = 2 * np.pi * np.arange(directions) / directions
    currents = (speeds[:, None, None] * np.stack([np.cos(angle), np.sin(angle), 0 * angle], axis=-1)).reshape(-1, 3)
    res = batch_controlled(robot, plan, poses[run], currents, controls=control, noisy=noisy, navigation=navigation,
                           vehicle=vehicle, controller=controller, joint_plans=np.stack(tables)[run], dwell_s=dwell_s,
                           gripper_s=gripper_s, **kwargs)
    reached = res.gate_reached.all(axis=-1).reshape(-1, speeds.size, directions).all(axis=-1)  # (kept, S)
    ok = np.cumprod(reached, axis=-1).astype(bool)
    tolerated, worst = np.full(len(poses), np.nan), np.full((len(poses), speeds.size), np.nan)
    tolerated[run] = np.where(ok.any(axis=-1), speeds[np.maximum(ok.sum(axis=-1) - 1, 0)], np.nan)
    worst[run] = res.worst_gate_tool_error.reshape(-1, speeds.size, directions).max(axis=-1)
    order = np.lexsort((np.arange(len(poses)), -np.nan_to_num(tolerated, nan=-1.0)))
    return CurrentRanking(poses=poses, path_share=share, speeds=speeds, worst_gate_tool_error=worst,
                          tolerated=tolerated, order=order, result=res)
