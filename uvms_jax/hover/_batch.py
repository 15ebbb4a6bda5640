"""Many hovering scenarios in one jitted batch, with MJX: currents × candidate docking poses.

The model is :func:`~uvms_jax.hover.hover_model`'s MJCF, put on the device once
(:func:`hover_mjx`). One scenario is a vehicle hovering at a docked pose ``[x, y, z, ψ]`` in a
constant current while its arm follows a table of servo targets (one row per control period);
:meth:`HoverMJX.rollout` runs it with ``lax.scan`` over control periods, and
:func:`batch_scenarios` runs K poses × N currents in one ``jax.jit(jax.vmap(jax.vmap(...)))``
call, recording the state once per control period (never per physics step).

What MJX lacks is computed in JAX and applied as body wrenches (``xfrc_applied``), on every
physics step, for the pose and velocity being integrated:

- **buoyancy**, :func:`~uvms_jax.hover.buoyancy_xfrc` with ``xp=jnp``, as on the CPU;
- **the fluid drag and the current.** MJX 3.17 implements MuJoCo's inertia-box fluid model,
  but refuses it with the ``implicitfast`` integrator (``put_model`` raises
  ``NotImplementedError('implicitfast not implemented for fluid drag.')``), and this model
  needs ``implicitfast``: the arm's servos (kv 150 N·m·s/rad on joints of about 0.05 kg·m²)
  make explicit Euler or RK4 unstable at a 2 ms step. So the MJX model gets ``density``,
  ``viscosity`` and ``wind`` 0, and :func:`fluid_xfrc` (the same formula as MuJoCo's
  ``mj_inertiaBoxFluidModel``, with ``xp``) adds the drag with each scenario's current as a
  traced input. The current therefore varies per batch element without touching the model. It
  enters the step explicitly, where the CPU's ``implicitfast`` also differentiates the fluid
  force: that is the one difference from :class:`HoverSim` (tens of µm in 1.2 s, the same in
  float32 and float64); with the same explicit wrench on the CPU, MJX in float64 agrees with
  MuJoCo's C engine to rounding (tests/hover/test_hover_batch.py).

The physics step is :func:`mujoco.mjx.step` opened up (``fwd_position``, ``fwd_velocity``, the
wrenches, ``fwd_actuation``, ``fwd_acceleration``, ``implicit``), so the wrenches are computed
from the step's own kinematics, as ``HoverSim`` does between ``mj_step1`` and ``mj_step2``
(lift taken from the previous step's pose fails the roll-period test, docs/hover.md).
Joint-limit constraints are switched off in the MJX model (``mjDSBL_LIMIT``): MJX would give
every limited joint a constraint row and run the solver on every step, while the servos keep the
joints inside their limits (the targets are checked to be within them); a joint driven onto a
limit is the one case where MJX and the CPU would differ.

On the CPU, compile with ``XLA_FLAGS=--xla_cpu_use_fusion_emitters=false`` (tests/conftest.py
and benchmarks/hover_mjx.py set it): with XLA's CPU fusion emitters this program ran about 450
times slower here (jax 0.10.2). The flag does not concern GPUs.
"""

from __future__ import annotations

import contextlib
import copy
import dataclasses
import functools
import io
import math
import time as _time
from collections.abc import Callable, Sequence
from typing import NamedTuple

import jax
import jax.numpy as jnp
import mujoco
import numpy as np

from uvms_jax.robot import TOOL_SITE, Robot

from ._control import LIMIT_SLACK, control_steps, hold_pose, thrust_layout
from ._hydro import buoyancy_xfrc, fluid_bodies, fluid_xfrc
from ._model import VEHICLE_BODY, buoyancy_bodies, hover_model, servo_name, thruster_name, trimmed
from ._plan import docked_tool, follow_tool_path, plan_targets
from ._settings import ControllerSettings, VehicleSettings

with contextlib.redirect_stdout(io.StringIO()):  # mujoco.mjx prints "Failed to import warp" on CPU
    from mujoco import mjx

__all__ = ["BatchResult", "HoverMJX", "HoverState", "PeriodRecord", "batch_candidates", "batch_plan", "batch_scenarios", "currents_grid",
           "fluid_bodies", "fluid_xfrc", "hover_mjx", "plot_robustness"]



# -- one scenario ---------------------------------------------------------------------------------
class HoverState(NamedTuple):
    """One scenario's state between control periods: the MJX data (its kinematics current for
    its ``qpos``) and the station keeping's ``(4,)`` integral."""

    data: mjx.Data
    integral: jax.Array


class PeriodRecord(NamedTuple):
    """What is kept of a control period, at its end (world frame, SI).

    Attributes:
      position: ``(3,)`` V's origin [m]; quat: ``(4,)`` V's orientation ``(w, x, y, z)``;
      q: ``(n,)`` the arm's joint angles [rad]; tool: ``(3,)`` the tool site [m];
      thrust: ``(n_thrusters,)`` the thrusts held over the period [N].
    """

    position: jax.Array
    quat: jax.Array
    q: jax.Array
    tool: jax.Array
    thrust: jax.Array


@dataclasses.dataclass(frozen=True, eq=False)
class HoverMJX:
    """The hovering vehicle's model on the device and its pure, jittable step (:func:`hover_mjx`).

    Attributes:
      model: the CPU model (:func:`~uvms_jax.hover.hover_model`, with its fluid options).
      mx: the MJX model: the same, less MuJoCo's fluid (density, viscosity, wind 0: this class
        applies it) and joint-limit constraints.
      robot, vehicle, controller: what it was built for (``vehicle``'s volume and centre of
        buoyancy are the default buoyancy; a rollout can take others, e.g. a trim per pose).
      physics_steps: MuJoCo steps per control period.
    """

    model: mujoco.MjModel
    mx: mjx.Model
    robot: Robot
    vehicle: VehicleSettings
    controller: ControllerSettings
    physics_steps: int
    vehicle_id: int
    qadr: np.ndarray
    servo: np.ndarray
    thruster: np.ndarray
    tool_site: int
    buoyant: np.ndarray
    volume: np.ndarray
    cob: np.ndarray
    fluid_ids: np.ndarray
    fluid_box: np.ndarray
    fluid_root: np.ndarray
    B_pinv: np.ndarray
    limits: np.ndarray

    @property
    def period(self) -> float:
        """Control period [s]."""
        return self.controller.period

    @property
    def dtype(self):
        """The float type the device computes in (float32 unless ``jax_enable_x64``)."""
        return jnp.zeros(()).dtype

    def _c(self, x):
        return jnp.asarray(x, dtype=self.dtype)

    # state ---------------------------------------------------------------------------------
    def init(self, pose, q0) -> HoverState:
        """The vehicle at rest at ``pose = [x, y, z, ψ]`` [m, rad] (level), the arm at ``q0``
        ``(n,)`` [rad] with its servos holding it; kinematics computed."""
        return HoverState(mjx.kinematics(self.mx, self.placed(pose, q0)), jnp.zeros(4, dtype=self.dtype))

    def placed(self, pose, q0) -> mjx.Data:
        """:meth:`init`'s data with nothing computed: ``qpos`` and the servos' ``ctrl`` set."""
        pose, q0 = self._c(pose), self._c(q0)
        d = mjx.make_data(self.mx)
        quat = jnp.stack([jnp.cos(pose[3] / 2), jnp.zeros_like(pose[3]), jnp.zeros_like(pose[3]),
                          jnp.sin(pose[3] / 2)])
        qpos = d.qpos.at[:3].set(pose[:3]).at[3:7].set(quat).at[self.qadr].set(q0)
        return d.replace(qpos=qpos, ctrl=d.ctrl.at[self.servo].set(q0))

    def record(self, d: mjx.Data) -> PeriodRecord:
        """The :class:`PeriodRecord` of ``d`` (whose kinematics must be current)."""
        return PeriodRecord(d.qpos[:3], d.qpos[3:7], d.qpos[self.qadr], d.site_xpos[self.tool_site],
                            d.ctrl[self.thruster])

    # physics -------------------------------------------------------------------------------
    def wrenches(self, d: mjx.Data, wind, volume, cob) -> jax.Array:
        """``(nbody, 6)`` ``xfrc_applied``: buoyancy plus the fluid's drag in ``wind`` (3,)
        [m/s], for the kinematics and velocities in ``d`` (after ``fwd_velocity``)."""
        b, f = self.buoyant, self.fluid_ids
        v = self.vehicle
        lift = buoyancy_xfrc(d.xpos[b], d.xmat[b], d.xipos[b], volume, cob, v.water_density,
                             self._c(self.model.opt.gravity), xp=jnp)
        drag = fluid_xfrc(d.xipos[f], d.ximat[f], d.cvel[f], d.subtree_com[self.fluid_root], self._c(self.fluid_box),
                          v.water_density, v.viscosity, wind, xp=jnp)
        return jnp.zeros((self.model.nbody, 6), self.dtype).at[b].add(lift).at[f].add(drag)

    def physics_step(self, d: mjx.Data, wind, volume, cob) -> mjx.Data:
        """One MuJoCo step (``implicitfast``) with buoyancy and drag set for the pose and
        velocity being integrated: :func:`mujoco.mjx.step` with the wrenches inserted between
        the velocity and the acceleration stages."""
        return self.integrate(mjx.fwd_position(self.mx, d), wind, volume, cob)

    def integrate(self, d: mjx.Data, wind, volume, cob) -> mjx.Data:
        """:meth:`physics_step` after its position stage (``mjx.fwd_position``), which ``d`` must
        hold for its ``qpos``: a loop that ends each step with the next one's position stage
        has the kinematics of every step's end without computing them twice."""
        m = self.mx
        d = mjx.fwd_velocity(m, d)
        d = d.replace(xfrc_applied=self.wrenches(d, wind, volume, cob))
        d = mjx.fwd_actuation(m, d)
        d = mjx.fwd_acceleration(m, d)
        if d._impl.efc_J.size == 0:  # static: no constraint rows in this model (limits off, nothing collides)
            d = d.replace(qacc=d.qacc_smooth)
        else:  # pragma: no cover - a model with constraints
            d = mjx.solve(m, d)
        return mjx.implicit(m, d)

    # control -------------------------------------------------------------------------------
    def thrust(self, state: HoverState, reference) -> tuple[jax.Array, jax.Array]:
        """``(thrust (n_thrusters,) [N], integral (4,))``: station keeping on ``reference``
        ``[x, y, z, ψ]`` plus levelling, allocated (zeros when the controller is off)."""
        d = state.data
        if not self.controller.enabled:
            return jnp.zeros(self.limits.size, self.dtype), state.integral
        u, _, integral = hold_pose(reference, d.qpos[:3], d.qpos[3:7], d.xmat[self.vehicle_id], d.qvel[:3], d.qvel[3:6],
                                   state.integral, self.controller, self._c(self.B_pinv), self._c(self.limits), xp=jnp)
        return u, integral

    def control_step(self, state: HoverState, targets, wind, reference, volume=None,
                     cob=None) -> tuple[HoverState, PeriodRecord]:
        """One control period of one scenario (pure; ``jit``/``vmap`` it): the thrusts for the
        present state, the servo targets ``(n,)`` [rad] set, then :attr:`physics_steps`
        physics steps in the current ``wind`` (3,) [m/s], then the kinematics of the new pose.

        Args:
          reference: ``(4,)`` the pose to hold ``[x, y, z, ψ]``.
          volume, cob: ``(k,)``, ``(k, 3)`` buoyancy of :attr:`buoyant` (default: the vehicle's).

        Returns:
          the next state and the record of the period's end.
        """
        volume = self._c(self.volume if volume is None else volume)
        cob = self._c(self.cob if cob is None else cob)
        wind = self._c(wind)
        u, integral = self.thrust(state, self._c(reference))
        d = state.data
        d = d.replace(ctrl=d.ctrl.at[self.thruster].set(u).at[self.servo].set(self._c(targets)))

        def physics(d, _):
            return self.physics_step(d, wind, volume, cob), None

        d, _ = jax.lax.scan(physics, d, None, length=self.physics_steps)
        d = mjx.kinematics(self.mx, d)  # the step leaves the kinematics of its start
        return HoverState(d, integral), self.record(d)

    def rollout(self, pose, wind, targets, volume=None, cob=None, record: bool = True):
        """One scenario from rest at ``pose`` ``[x, y, z, ψ]``, holding it, in a constant
        current ``wind`` (3,) [m/s], the servos following ``targets`` ``(P, n)`` [rad] (row k
        from time ``k · period``), for P control periods (pure; ``vmap`` it).

        Returns:
          ``record``: the :class:`PeriodRecord` fields stacked over the start and every
          period's end, ``(P + 1, ...)``; else ``(last record, max drift [m])`` (nothing per
          period: for throughput runs).
        """
        pose, targets = self._c(pose), self._c(targets)
        state = self.init(pose, targets[0])
        first = self.record(state.data)

        def period(carry, row):
            state, worst = carry
            state, rec = self.control_step(state, row, wind, pose, volume, cob)
            worst = jnp.maximum(worst, jnp.linalg.norm(rec.position - pose[:3]))
            return (state, worst), (rec if record else None)

        (state, worst), recs = jax.lax.scan(period, (state, jnp.zeros((), self.dtype)), targets)
        if not record:
            return self.record(state.data), worst
        return jax.tree.map(lambda a, b: jnp.concatenate([a[None], b]), first, recs)


def hover_mjx(robot: Robot, vehicle: VehicleSettings = VehicleSettings(),
              controller: ControllerSettings = ControllerSettings(), *, physics_dt: float = 0.002) -> HoverMJX:
    """Build the MJX model of the vehicle carrying ``robot`` once (:func:`hover_model`'s MJCF,
    ``mjx.put_model``) and the constants of its step.

    Raises:
      ValueError: ``controller.period`` not a whole number of ``physics_dt``.
    """
    steps = control_steps(controller.period, physics_dt)
    model = hover_model(robot, vehicle, physics_dt=physics_dt)
    device_model = copy.copy(model)
    device_model.opt.density = 0.0  # the fluid is fluid_xfrc's (MJX: no fluid with implicitfast)
    device_model.opt.viscosity = 0.0
    device_model.opt.wind[:] = 0.0
    device_model.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_LIMIT)
    mx = mjx.put_model(device_model)
    ids, volume, cob = buoyancy_bodies(model, robot, vehicle)
    fluid_ids, box = fluid_bodies(model)
    _, B_pinv, limits = thrust_layout(vehicle)
    return HoverMJX(model=model, mx=mx, robot=robot, vehicle=vehicle, controller=controller, physics_steps=steps,
                    vehicle_id=model.body(VEHICLE_BODY).id,
                    qadr=np.array([model.jnt_qposadr[model.joint(j).id] for j in robot.joint_names], dtype=int),
                    servo=np.array([model.actuator(servo_name(j)).id for j in robot.joint_names], dtype=int),
                    thruster=np.array([model.actuator(thruster_name(k)).id for k in range(len(vehicle.thrusters))],
                                      dtype=int),
                    tool_site=model.site(TOOL_SITE).id, buoyant=ids, volume=volume, cob=cob, fluid_ids=fluid_ids,
                    fluid_box=box, fluid_root=np.asarray(model.body_rootid[fluid_ids], dtype=int),
                    B_pinv=B_pinv, limits=limits)


# -- the batch ------------------------------------------------------------------------------------
@dataclasses.dataclass(frozen=True)
class BatchResult:
    """K poses × N currents hovering (:func:`batch_scenarios`); world frame, SI.

    Attributes:
      poses: ``(K, 4)`` docked poses ``[x, y, z, ψ]``; currents: ``(N, 3)`` [m/s].
      time: ``(T,)`` the record times: the start and every control period's end [s].
      position, quat, q, tool, thrust: ``(K, N, T, ...)`` the records (:class:`PeriodRecord`).
      docked_tool: ``(K, N, T, 3)`` where the docked arm holds the tool on the plan: FK of the
        targets at the docked base, as :func:`~uvms_jax.hover.run_plan_hovering` measures it.
      drift: ``(K, N, T)`` the vehicle's distance from its docked pose; tool_error:
        ``(K, N, T)`` the tool's from its docked position [m].
      gate_times: ``(g,)``; gate_tool_error, gate_joint_error: ``(K, N, g)`` at the gates [m,
        rad]; a gate is reached within ``tool_tolerance_m`` and ``joint_tolerance_rad``.
      compile_s, run_s: the jitted batch's compile time and its run time [s].
    """

    poses: np.ndarray
    currents: np.ndarray
    time: np.ndarray
    position: np.ndarray
    quat: np.ndarray
    q: np.ndarray
    tool: np.ndarray
    thrust: np.ndarray
    docked_tool: np.ndarray
    drift: np.ndarray
    tool_error: np.ndarray
    gate_times: np.ndarray
    gate_tool_error: np.ndarray
    gate_joint_error: np.ndarray
    tool_tolerance_m: float
    joint_tolerance_rad: float
    compile_s: float
    run_s: float

    @property
    def max_drift(self) -> np.ndarray:
        """``(K, N)`` the largest drift [m]."""
        return self.drift.max(axis=-1)

    @property
    def max_tool_error(self) -> np.ndarray:
        """``(K, N)`` the worst tool error [m]."""
        return self.tool_error.max(axis=-1)

    @property
    def gate_reached(self) -> np.ndarray:
        """``(K, N, g)`` bool: each gate reached."""
        return (self.gate_tool_error <= self.tool_tolerance_m) & (self.gate_joint_error <= self.joint_tolerance_rad)

    @property
    def gate_share(self) -> np.ndarray:
        """``(K, N)`` the share of gates reached (1 without gates)."""
        g = self.gate_reached
        return g.mean(axis=-1) if g.shape[-1] else np.ones(g.shape[:2])

    @property
    def current_speed(self) -> np.ndarray:
        """``(N,)`` [m/s]."""
        return np.linalg.norm(self.currents, axis=-1)

    def summary(self) -> dict:
        """Per pose and current: drift, worst tool error, gates (lists, SI units)."""
        return {"poses": self.poses.tolist(), "currents_m_s": self.currents.tolist(),
                "max_drift_m": self.max_drift.tolist(), "max_tool_error_m": self.max_tool_error.tolist(),
                "gate_share": self.gate_share.tolist(), "gates": int(self.gate_times.size),
                "peak_thrust_N": np.abs(self.thrust).max(axis=(-1, -2)).tolist(),
                "simulated_s": float(self.time[-1]), "compile_s": self.compile_s, "run_s": self.run_s}


def currents_grid(speeds: Sequence[float], directions_deg: Sequence[float]) -> np.ndarray:
    """``(len(speeds) · len(directions), 3)`` horizontal currents [m/s]: every speed [m/s]
    towards every heading [deg from the world's x, counter-clockwise], speed-major."""
    s = np.asarray(speeds, dtype=float)[:, None]
    a = np.radians(np.asarray(directions_deg, dtype=float))[None, :]
    return np.stack([s * np.cos(a), s * np.sin(a), np.zeros_like(s * a)], axis=-1).reshape(-1, 3)


def _target_table(targets, periods: int, period: float, n: int, K: int) -> np.ndarray:
    """``(K, P, n)`` servo targets per pose and control period."""
    if callable(targets):
        table = np.array([targets(k * period) for k in range(periods)], dtype=float)
    else:
        table = np.asarray(targets, dtype=float)
    if table.ndim == 2:
        table = np.broadcast_to(table, (K,) + table.shape)
    if table.shape[0] != K or table.shape[-1] != n or table.shape[1] < periods:
        raise ValueError(f"targets must give (P ≥ {periods}, {n}) or (K = {K}, P, {n}) joint angles, "
                         f"got shape {table.shape}")
    return np.ascontiguousarray(table[:, :periods])


@functools.lru_cache(maxsize=8)
def _batch_program(sim: HoverMJX):
    """The jitted K poses × N currents rollout of ``sim``, one per sim: every input is an
    argument, so a second batch of the same shapes on the same sim reuses its trace and its
    compiled program rather than tracing MJX again."""
    per_current = jax.vmap(sim.rollout, in_axes=(None, 0, None, None, None))
    return jax.jit(jax.vmap(per_current, in_axes=(0, None, 0, 0, 0)))


def batch_scenarios(robot: Robot, vehicle: VehicleSettings, controller: ControllerSettings, poses, currents,
                    targets: Callable[[float], Sequence[float]] | np.ndarray, duration: float, *,
                    gate_times: Sequence[float] = (), trim: bool = True, tool_tolerance_m: float = 0.01,
                    joint_tolerance_rad: float = 0.01, physics_dt: float = 0.002,
                    sim: HoverMJX | None = None) -> BatchResult:
    """Every docked pose in every current, hovering, in one ``jax.jit(jax.vmap(...))`` call.

    Each scenario starts at rest at its pose (level, arm at the first target), holds it by
    station keeping and levelling, and its servos follow ``targets``; the state is recorded at
    the start and after every control period.

    Args:
      poses: ``(K, 4)`` docked poses ``[x, y, z, ψ]`` [m, rad].
      currents: ``(N, 3)`` constant water velocities [m/s] (e.g. :func:`currents_grid`).
      targets: time [s] → ``(n,)`` servo targets [rad] (read at each control tick), or a table
        ``(P, n)`` or per pose ``(K, P, n)`` with one row per control period.
      duration: [s], rounded to whole control periods.
      gate_times: times [s] at which the tool must be within ``tool_tolerance_m`` of its docked
        position and the joints within ``joint_tolerance_rad`` of their targets.
      trim: ballast the hull neutral and level for the arm at each pose's first target
        (:func:`~uvms_jax.hover.trimmed`, as :func:`~uvms_jax.hover.run_plan_hovering`);
        False: ``vehicle`` as given.
      sim: a :func:`hover_mjx` built for the same robot, vehicle layout and controller (built
        here when None).

    Raises:
      ValueError: bad shapes, or a target outside the joint limits.
    """
    poses = np.atleast_2d(np.asarray(poses, dtype=float))
    currents = np.atleast_2d(np.asarray(currents, dtype=float))
    if poses.shape[1:] != (4,) or currents.shape[1:] != (3,):
        raise ValueError(f"poses must be (K, 4) and currents (N, 3), got {poses.shape} and {currents.shape}")
    sim = hover_mjx(robot, vehicle, controller, physics_dt=physics_dt) if sim is None else sim
    period = controller.period
    periods = round(duration / period)
    if periods < 1 or not math.isfinite(duration):
        raise ValueError(f"duration must be at least one control period ({period} s), got {duration}")
    K, N, n = len(poses), len(currents), robot.n_joints
    table = _target_table(targets, periods, period, n, K)
    if np.any(table < robot.lower - LIMIT_SLACK) or np.any(table > robot.upper + LIMIT_SLACK):
        raise ValueError("arm targets outside the joint limits")
    volumes, cobs = [], []
    for k in range(K):
        v = trimmed(vehicle, robot, table[k, 0]) if trim else vehicle
        _, vol, cob = buoyancy_bodies(sim.model, robot, v)
        volumes.append(vol)
        cobs.append(cob)
    volumes, cobs = np.array(volumes), np.array(cobs)

    batch = _batch_program(sim)
    args = tuple(jnp.asarray(a, dtype=sim.dtype) for a in (poses, currents, table, volumes, cobs))
    t0 = _time.perf_counter()
    compiled = batch.lower(*args).compile()
    t1 = _time.perf_counter()
    recs = jax.block_until_ready(compiled(*args))
    t2 = _time.perf_counter()
    recs = PeriodRecord(*(np.asarray(a, dtype=float) for a in recs))

    times = period * np.arange(periods + 1)
    # Where the docked arm holds the tool on the plan: its targets at the record times.
    q_plan = table[:, np.minimum(np.arange(periods + 1), periods - 1)]  # (K, T, n)
    docked = np.stack([docked_tool(robot, vehicle, p, q) for p, q in zip(poses, q_plan)])  # (K, T, 3)
    docked = np.broadcast_to(docked[:, None], recs.tool.shape)
    tool_error = np.linalg.norm(recs.tool - docked, axis=-1)
    drift = np.linalg.norm(recs.position - poses[:, None, None, :3], axis=-1)
    gate_times = np.asarray(gate_times, dtype=float).reshape(-1)
    rows = np.searchsorted(times, gate_times - 1e-9).clip(max=len(times) - 1)
    if callable(targets):
        gate_q = np.broadcast_to(np.array([targets(t) for t in gate_times], dtype=float).reshape(-1, n),
                                 (K, gate_times.size, n))
    else:
        gate_q = table[:, np.clip(np.round(gate_times / period).astype(int), 0, periods - 1)]
    joint_error = (np.abs(recs.q[:, :, rows] - gate_q[:, None]).max(axis=-1) if gate_times.size
                   else np.zeros((K, N, 0)))
    return BatchResult(poses=poses, currents=currents, time=times, position=recs.position, quat=recs.quat, q=recs.q,
                       tool=recs.tool, thrust=recs.thrust, docked_tool=docked, drift=drift, tool_error=tool_error,
                       gate_times=gate_times, gate_tool_error=tool_error[:, :, rows], gate_joint_error=joint_error,
                       tool_tolerance_m=float(tool_tolerance_m), joint_tolerance_rad=float(joint_tolerance_rad),
                       compile_s=t1 - t0, run_s=t2 - t1)


def batch_plan(robot: Robot, plan, poses, currents, vehicle: VehicleSettings = VehicleSettings(),
               controller: ControllerSettings = ControllerSettings(), *, dwell_s: float = 0.5,
               gripper_s: float = 1.0, **kwargs) -> BatchResult:
    """:func:`batch_scenarios` for a ``plan.json``'s motion (:func:`~uvms_jax.hover.plan_targets`),
    its gates and its duration plus one control period, as
    :func:`~uvms_jax.hover.run_plan_hovering` replays it at one pose in one current."""
    if tuple(plan.joint_names) != tuple(robot.joint_names):
        raise ValueError(f"the plan moves {plan.joint_names}, the arm has {robot.joint_names}")
    targets, gate_times, duration = plan_targets(plan, dwell_s, gripper_s)
    return batch_scenarios(robot, vehicle, controller, poses, currents, targets, duration + controller.period,
                           gate_times=gate_times, **kwargs)


def batch_candidates(robot: Robot, plan, poses, currents, vehicle: VehicleSettings = VehicleSettings(),
                     controller: ControllerSettings = ControllerSettings(), *, dwell_s: float = 0.5,
                     gripper_s: float = 1.0, **kwargs) -> tuple[BatchResult, np.ndarray]:
    """Docking candidates in every current in one batch: the plan's motion at its own docked
    pose ``poses[0]``, and the same tool motion from each other pose ``poses[1:]``
    (:func:`~uvms_jax.hover.follow_tool_path`), timed and gated as :func:`batch_plan`.

    A candidate from which the tool cannot follow the whole path (a row out of reach within
    the joint limits) is left out of the batch.

    Returns:
      ``(result, reached)``: the batch over the kept poses, and ``reached (K,)`` the share of the
      path's rows each pose's tool follows (1 for the first; a pose is kept when it is 1).
    """
    if tuple(plan.joint_names) != tuple(robot.joint_names):
        raise ValueError(f"the plan moves {plan.joint_names}, the arm has {robot.joint_names}")
    poses = np.atleast_2d(np.asarray(poses, dtype=float))
    targets, gate_times, duration = plan_targets(plan, dwell_s, gripper_s)
    duration += controller.period
    periods = round(duration / controller.period)
    docked = np.array([targets(k * controller.period) for k in range(periods)])
    tables, share = [docked], [1.0]
    for p in poses[1:]:
        q, reached = follow_tool_path(robot, vehicle, docked, poses[0], p)
        share.append(float(np.mean(reached)))
        if share[-1] == 1.0:
            tables.append(q)
    share = np.array(share)
    return batch_scenarios(robot, vehicle, controller, poses[share == 1.0], currents, np.stack(tables), duration,
                           gate_times=gate_times, **kwargs), share


def plot_robustness(result: BatchResult, path, labels: Sequence[str] | None = None) -> None:
    """Per pose, the share of gates reached and the worst tool error against the current's
    speed (the worst over the currents' directions at each speed), to ``path`` (PNG)."""
    from uvms_jax.plotting import pyplot

    plt = pyplot()
    speed = np.round(result.current_speed, 9)
    levels = np.unique(speed)
    share = np.array([[result.gate_share[k, speed == s].min() for s in levels] for k in range(len(result.poses))])
    error = np.array([[result.max_tool_error[k, speed == s].max() for s in levels] for k in range(len(result.poses))])
    labels = labels or [f"pose {k}: ({p[0]:.2f}, {p[1]:.2f}, {p[2]:.2f}) m, {np.degrees(p[3]):.0f}°"
                        for k, p in enumerate(result.poses)]
    fig, (a, b) = plt.subplots(1, 2, figsize=(10, 4), constrained_layout=True)
    for k, label in enumerate(labels):
        a.plot(levels, share[k], marker="o", label=label)
        b.plot(levels, 1e3 * error[k], marker="o", label=label)
    a.set(xlabel="current speed [m/s]", ylabel="share of gates reached", ylim=(-0.05, 1.05),
          title="gates reached (worst direction)")
    b.axhline(1e3 * result.tool_tolerance_m, color="k", lw=0.8, ls="--", label="gate tolerance")
    b.set(xlabel="current speed [m/s]", ylabel="worst tool error [mm]", title="tool error (worst direction)")
    b.legend(fontsize=7)
    fig.savefig(path, dpi=120)
    plt.close(fig)
