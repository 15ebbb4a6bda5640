"""Simulated Reach arm speaking BPL, backed by MuJoCo joint-space physics, with device faults.

The physics model is the robot's own (:func:`~uvms_jax.hw.sim_spec`, built on
:func:`uvms_jax.robot.add_robot`): its joints, links and mass properties under gravity and
buoyancy (docs/hardware.md §3), the jaws as one slide joint. The physics runs in the arm's base
frame; the base's orientation in the world (``SimSettings.base_rpy``: upright, or hanging under a
vehicle) turns gravity and buoyancy. An arm whose description has no mass properties is
simulated weightless (gravity compensated, no buoyancy): servoed kinematically.
The device firmware is modelled as a servo that turns the demand into a joint speed every
physics step — POSITION mode ``v = clip(gain·(q* - q), ±v_max)``, VELOCITY mode
``v = clip(v*, ±v_max)``, other modes ``v = 0`` — tracked by a MuJoCo velocity actuator plus an
integral of the speed error (a second, torque actuator) that carries the load. As the real
controller, it keeps the position limits: a demand towards a limit is cut to
``gain·(limit - q)`` (the joint slows and stops there), and a joint the drive's lag carries past
a limit is stopped on it (MuJoCo's own limits are soft).

The devices answer every request of the protocol listing (docs/hardware.md §1), each answer
in its own datagram. :class:`SimArm` is the device: physics, modes, demands, BPL request
answers, heartbeats. Demands outside the limits are ignored and counted
(``limit_violations``), never obeyed. The links it is reached by are in
:mod:`uvms_jax.hw._sim_link`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING, Protocol

import numpy as np

from ._codec import Packet, decode_float, encode_floats, encode_packet
from ._settings import SimSettings
from ._ids import BASE_COMPUTER, BASE_ROUTER, BROADCAST, HardwareStatus, Mode, PacketID
from ._joints import MM_PER_M, joint_specs
from ._sim_model import GRAVITY, add_drives, massive_bodies, sim_spec, world_up

if TYPE_CHECKING:
    import mujoco

__all__ = ["ArmWorld", "SimArm"]

_MM = 1.0 / MM_PER_M  # jaws: mm on the wire, m in MuJoCo

# The integral gain of the velocity loop [N·m/rad; N/m], which holds a load (gravity less
# buoyancy) with no steady speed error: the arm sags while the integral builds, then recovers.
_KI = 300.0

# What the simulated devices report about themselves (the simulator's values, not a real
# arm's): serial number = base + device id, model number, software version (major, sub-major,
# minor), and a steady environment inside the housings.
_SERIAL_BASE = 7000.0
_MODEL_NUMBER = 7.0
_SOFTWARE_VERSION = (0, 1, 0)
_TEMPERATURE_C, _HUMIDITY_PCT, _PRESSURE_BAR, _VOLTAGE_V = 20.0, 15.0, 1.0, 24.0
# Motor current model: a joint's effort limit (the description's; 10 N·m or N where it gives
# none) takes this current, and the drive stops at the current limit (torque saturates there).
_EFFORT_CURRENT_MA = 2000.0
_CURRENT_LIMIT_MA = 4000.0
_DEFAULT_EFFORT = 10.0
_HEARTBEAT_SLOTS = 10  # HEARTBEAT_SET carries 10 packet ids; a REQUEST lists at most 10
_BASE_DEVICES = (BASE_ROUTER, BASE_COMPUTER)
_NO_BODIES = (np.zeros(0, dtype=int), np.zeros(0), np.zeros((0, 3)))


class ArmWorld(Protocol):
    """Where a :class:`SimArm` is mounted when its base is not fixed (e.g. a hovering vehicle).

    The world builds the MuJoCo model around the arm, and steps the physics with its own
    forces and controllers; the simulated arm adds its drives and runs them every step.
    """

    def spec(self, robot, physics_dt: float) -> mujoco.MjSpec:
        """The world's model holding ``robot``'s body tree as :func:`uvms_jax.robot.add_robot`
        names it, with no actuators on the arm's joints; time step ``physics_dt`` [s]."""

    def prepare(self, model: mujoco.MjModel, data: mujoco.MjData) -> None:
        """Called once, with the arm at its initial positions and kinematics computed."""

    def step(self, model: mujoco.MjModel, data: mujoco.MjData) -> None:
        """One physics step (``mj_step``, or ``mj_step1`` and ``mj_step2`` with the world's forces
        between); the arm's actuator controls are already set."""


def _joint_index(names: Sequence[str], name: str, what: str) -> int:
    """Index of joint ``name`` in ``names`` (exact, else the one equal ignoring case); -1 for ""."""
    if not name:
        return -1
    if name in names:
        return list(names).index(name)
    folded = [k for k, n in enumerate(names) if n.lower() == name.lower()]
    if len(folded) != 1:
        raise ValueError(f"SimSettings.{what} {name!r} is not a joint of the arm ({', '.join(names)})")
    return folded[0]


class SimArm:
    """The simulated device: MuJoCo physics plus BPL behaviour.

    Args:
      robot: the arm (:class:`uvms_jax.robot.Robot`); its joint table, device ids included, is
        :func:`~uvms_jax.hw.joint_specs` of it (an arm without a hardware profile: consecutive
        ids, the gripper 1; an arm without a gripper: no jaws).
      config: servo, physics and the device-side faults (stuck joint, hardware status; joints
        named as the robot names them, case ignored).
      q0: ``(n + 1,)`` initial positions in plan order, the arm's joints then the jaws [rad …,
        mm] (``(n,)`` without a gripper); default mid-range arm and jaws at their lower limit.
      world: where the arm is mounted, if not on a fixed base (:class:`ArmWorld`, e.g. a
        hovering vehicle, :class:`uvms_jax.hover.HoverWorld`): its model holds the arm's body
        tree, and it steps the physics with its own forces (buoyancy included: the arm's then
        too, and ``base_rpy`` is not used).
    """

    def __init__(self, robot, config: SimSettings = SimSettings(), q0: Sequence[float] | None = None,
                 world: ArmWorld | None = None) -> None:
        import mujoco  # imported here: the protocol layer must not need MuJoCo

        from uvms_jax.robot import TOOL_SITE, base_body

        self._mj = mujoco
        self.robot = robot
        self.config = config
        self.world = world
        self.joints = joint_specs(robot)
        if world is None:
            spec = sim_spec(robot, physics_dt=config.physics_dt, dynamics=config.dynamics, base_rpy=config.base_rpy)
        else:
            spec = add_drives(world.spec(robot, config.physics_dt), robot, dynamics=config.dynamics)
        self.model = spec.compile()
        self.data = mujoco.MjData(self.model)
        names = [j.name for j in self.joints]
        self._qadr = np.array([self.model.jnt_qposadr[self.model.joint(n).id] for n in names])
        self._dadr = np.array([self.model.jnt_dofadr[self.model.joint(n).id] for n in names])
        self._act = np.array([self.model.actuator(f"v_{n}").id for n in names])
        self._iact = np.array([self.model.actuator(f"i_{n}").id for n in names])
        self._scale = np.array([_MM if j.unit == "mm" else 1.0 for j in self.joints])  # wire → MuJoCo
        self._vmax = np.array([j.max_velocity for j in self.joints])
        # Position limits, wire units and MuJoCo units: the firmware's limit stop.
        self._lower = np.array([j.lower for j in self.joints])
        self._upper = np.array([j.upper for j in self.joints])
        self._lower_mj, self._upper_mj = self._lower * self._scale, self._upper * self._scale
        self._index = {j.device_id: i for i, j in enumerate(self.joints)}
        q0 = _initial_positions(self.joints, q0)
        self.data.qpos[self._qadr] = q0 * self._scale
        self._mj.mj_forward(self.model, self.data)
        if world is not None:
            world.prepare(self.model, self.data)
        self._init_buoyancy()
        # The velocity loop's integral [rad; m], started at what holds the arm still where it is.
        self._integral = self._holding_torque() / _KI
        n = len(self.joints)
        self.mode = np.full(n, int(Mode.POSITION))
        self.target = q0.copy()  # wire units
        self.vel_target = np.zeros(n)
        self.stuck = _joint_index(names, config.stuck_joint, "stuck_joint")
        self._stuck_q = self.data.qpos[self._qadr].copy()
        self.fault_index = _joint_index(names, config.fault_joint, "fault_joint")
        self.limit_violations = 0
        self.demands = 0
        self.unanswered = 0  # requested ids a device does not answer
        self.ignored = 0  # received packets a device does not take (unknown id, bad size)
        # Heartbeat settings per device id: streamed packet ids, rate [Hz], next due time [s].
        self.heartbeat_ids: dict[int, tuple[int, ...]] = {}
        self.heartbeat_hz: dict[int, int] = {}
        self._next_heartbeat: dict[int, float] = {}
        self._tool = self.model.site(TOOL_SITE).id
        self._base = self.model.body(base_body(robot)).id
        self._jaws = robot.gripper is not None  # the last joint is the jaws
        self._init_current_limits()

    def _init_buoyancy(self) -> None:
        """Buoyancy of each body with mass: body ids, lifts [N] along the world's up, and the
        lift-weighted mean of the parts' centres of buoyancy less the body's centre of mass
        [m, in the body], fixed in the base frame (the base does not move). A world applies
        its own."""
        self._buoy_ids, lifts, arms = self._buoyant_bodies() if self.world is None else _NO_BODIES
        self._buoy_arm = arms
        lift = lifts[:, None] * world_up(self.config.base_rpy)  # (k, 3) [N]
        self.data.xfrc_applied[self._buoy_ids, :3] = lift
        # Its moment arm turns with the link: r × F = [F]×ᵀ r, whose row j is F × e_j (k, 3, 3) [N].
        self._buoy_moment = np.cross(lift[:, None, :], np.eye(3))
        # Views of MjData (fetching one is slow in a per-step loop) and the rows of the buoyant
        # bodies: a slice when their ids run on (they do along a chain).
        self._xmat, self._xfrc = self.data.xmat, self.data.xfrc_applied
        ids = self._buoy_ids
        contiguous = ids.size and np.array_equal(ids, np.arange(ids[0], ids[0] + ids.size))
        self._buoy_rows = slice(int(ids[0]), int(ids[0]) + ids.size) if contiguous else ids

    def _init_current_limits(self) -> None:
        """Each joint's torque constant [N·m/A or N/A] from its effort limit, and the velocity
        loop's integral bound from the current limit (none for the jaws)."""
        robot = self.robot
        efforts = np.array([*robot.effort_limits, *([robot.gripper.effort] if self._jaws else [])], dtype=float)
        efforts[~(efforts > 0)] = _DEFAULT_EFFORT
        self._torque_constant = efforts / (_EFFORT_CURRENT_MA * 1e-3)
        self._max_integral = self._torque_constant * _CURRENT_LIMIT_MA * 1e-3 / _KI
        # The jaws' fingers carry no load (gravity compensated): no integral, which would wind
        # up while they squeeze an object and hold them shut after the command to open.
        self._max_integral[[j.unit == "mm" for j in self.joints]] = 0.0
        np.clip(self._integral, -self._max_integral, self._max_integral, out=self._integral)

    def _buoyant_bodies(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(ids (k,), lifts (k,) [N], arms (k, 3) [m])`` of the moving bodies with displaced
        volume: the parts' lifts summed per body, the arm from the body's centre of mass to the
        lift-weighted centre of buoyancy of its parts, in the body frame (none without
        ``config.dynamics``, in air, or for bodies the model does not weigh)."""
        from uvms_jax.robot import BASE

        cfg, robot = self.config, self.robot
        weighed = massive_bodies(robot) if cfg.dynamics else set()
        per_body: dict[int, list] = {}
        for part in robot.inertials:
            if part.body != BASE and part.body in weighed and part.volume > 0 and cfg.water_density > 0:
                per_body.setdefault(part.body, []).append(part)
        ids, lifts, arms = [], [], []
        for body, parts in sorted(per_body.items()):
            b = self.model.body(robot.link_names[body]).id
            lift = [cfg.water_density * p.volume * GRAVITY for p in parts]
            cob = sum(l * np.asarray(p.cob) for l, p in zip(lift, parts)) / sum(lift)
            ids.append(b)
            lifts.append(sum(lift))
            arms.append(cob - self.model.body_ipos[b])
        return np.array(ids, dtype=int), np.array(lifts, dtype=float), np.array(arms, dtype=float).reshape(-1, 3)

    # -- physics ---------------------------------------------------------------------------
    @property
    def time(self) -> float:
        """Simulated time [s]."""
        return float(self.data.time)

    def positions(self) -> np.ndarray:
        """(n + 1,) positions in wire units (rad, mm), plan order: the arm's joints, then the jaws
        (``(n,)`` without a gripper)."""
        return self.data.qpos[self._qadr] / self._scale

    def velocities(self) -> np.ndarray:
        """(n + 1,) velocities in wire units (rad/s, mm/s)."""
        return self.data.qvel[self._dadr] / self._scale

    def step_to(self, t: float) -> None:
        """Advance physics (and the servo, every step) up to simulated time ``t`` [s]."""
        dt = self.model.opt.timestep
        if self.data.time + 0.5 * dt > t:
            return
        d, q_idx, d_idx, scale = self.data, self._qadr, self._dadr, self._scale
        qpos, qvel, ctrl = d.qpos, d.qvel, d.ctrl
        # the jaws stall at the object's width (none: -inf, never; no jaws: nothing to stall)
        width = self.config.object_width_mm * _MM if self.config.object_width_mm > 0 and self._jaws else -math.inf
        # modes and demands change only between calls (in handle): fixed for this stretch
        position = self.mode == int(Mode.POSITION)
        held = np.where(self.mode == int(Mode.VELOCITY), self.vel_target, 0.0)
        gain, vmax, lo, hi = self.config.servo_gain, self._vmax, -self._max_integral, self._max_integral
        act, iact, integral = self._act, self._iact, self._integral
        lower, upper, lower_mj, upper_mj = self._lower, self._upper, self._lower_mj, self._upper_mj
        steps = int(math.floor((t - d.time) / dt + 0.5))
        for _ in range(steps):
            q = qpos[q_idx] / scale
            v = np.where(position, gain * (self.target - q), held)
            # the limit stop: no demand drives a joint on past its limit (a velocity demand
            # slows as the position loop would, to stop there)
            np.clip(v, gain * (lower - q), gain * (upper - q), out=v)
            np.clip(v, -vmax, vmax, out=v)
            if self.stuck >= 0:
                v[self.stuck] = 0.0
            jaws_before = qpos[q_idx[-1]]  # the last joint: the jaws, if any (else width is -inf)
            v *= scale  # MuJoCo units
            ctrl[act] = v
            # integral of the speed error, clamped where the drive saturates (no wind-up)
            integral += (v - qvel[d_idx]) * dt
            np.clip(integral, lo, hi, out=integral)
            ctrl[iact] = _KI * integral
            if self.world is None:
                self._apply_buoyancy()
                self._mj.mj_step(self.model, d)
            else:
                self.world.step(self.model, d)
            # what the drive's lag still carries past a limit (MuJoCo's limits are soft) stops there
            qn = qpos[q_idx]
            if np.any(qn > upper_mj) or np.any(qn < lower_mj):
                past = np.flatnonzero((qn > upper_mj) | (qn < lower_mj))
                qpos[q_idx[past]] = np.clip(qn[past], lower_mj[past], upper_mj[past])
                qvel[d_idx[past]] = 0.0
            if self.stuck >= 0:
                qpos[q_idx[self.stuck]] = self._stuck_q[self.stuck]
                qvel[d_idx[self.stuck]] = 0.0
            if jaws_before >= width > qpos[q_idx[-1]]:  # closed onto the object: stall there
                qpos[q_idx[-1]] = width
                qvel[d_idx[-1]] = 0.0

    def hardware_status(self, i: int) -> HardwareStatus:
        """Status bits of joint index ``i`` at the current simulated time."""
        if i == self.fault_index and self.time >= self.config.fault_after_s:
            return HardwareStatus(self.config.fault_bits)
        return HardwareStatus.OK

    def currents(self) -> np.ndarray:
        """(n + 1,) motor currents [mA]: each joint's drive torque (jaws: force) over its torque constant."""
        force = self.data.actuator_force
        return (force[self._act] + force[self._iact]) / self._torque_constant * 1e3

    def _apply_buoyancy(self) -> None:
        """Set each link's buoyancy (along the world's up, at its centre of buoyancy) as an
        applied force.

        MuJoCo applies it at the centre of mass, so the lift's torque about that point goes
        with it: ``r × F``, r = R (cob - com) in MuJoCo's world (the base frame), F the lift
        along :func:`world_up` (F is set once; this runs every physics step, hence the
        precomputed matrix of ``r ↦ r × F``)."""
        if self._buoy_ids.size == 0:
            return
        r = np.einsum("kij,kj->ki", self._xmat[self._buoy_rows].reshape(-1, 3, 3), self._buoy_arm)
        self._xfrc[self._buoy_rows, 3:6] = np.einsum("kij,kj->ki", self._buoy_moment, r)

    def _holding_torque(self) -> np.ndarray:
        """(n + 1,) drive torques that hold the arm still in its current pose [N·m; N]."""
        mj, m, d = self._mj, self.model, self.data
        self._apply_buoyancy()
        load = d.qfrc_bias - d.qfrc_gravcomp  # gravity the drives carry (the arm is at rest)
        lift = np.zeros(m.nv)
        for body in range(m.nbody):
            mj.mj_applyFT(m, d, d.xfrc_applied[body, :3].copy(), d.xfrc_applied[body, 3:].copy(),
                          d.xipos[body].copy(), body, lift)
        return (load - lift)[self._dadr]

    def end_pose(self) -> np.ndarray:
        """(6,) tool-frame pose in the base frame: X, Y, Z [mm], then ZYX yaw, pitch, roll [rad]."""
        self._mj.mj_kinematics(self.model, self.data)
        d, t, b = self.data, self._tool, self._base
        R_base = d.xmat[b].reshape(3, 3)
        p = R_base.T @ (d.site_xpos[t] - d.xpos[b]) * MM_PER_M
        return np.concatenate([p, _ypr(R_base.T @ d.site_xmat[t].reshape(3, 3))])

    def end_velocity(self) -> np.ndarray:
        """(6,) tool-frame velocity relative to the base, in the base frame: X, Y, Z [mm/s],
        then the rates of the yaw, pitch and roll of :meth:`end_pose` [rad/s]."""
        mj, m, d = self._mj, self.model, self.data
        mj.mj_kinematics(m, d)
        mj.mj_comPos(m, d)
        mj.mj_comVel(m, d)
        tool, base = np.zeros(6), np.zeros(6)  # [angular (3), linear (3)] in the world, at each origin
        mj.mj_objectVelocity(m, d, mj.mjtObj.mjOBJ_SITE, self._tool, tool, 0)
        mj.mj_objectVelocity(m, d, mj.mjtObj.mjOBJ_BODY, self._base, base, 0)
        R_base = d.xmat[self._base].reshape(3, 3)
        linear = tool[3:] - base[3:] - np.cross(base[:3], d.site_xpos[self._tool] - d.xpos[self._base])
        yaw, pitch, _ = _ypr(R_base.T @ d.site_xmat[self._tool].reshape(3, 3))
        return np.concatenate([R_base.T @ linear * MM_PER_M, _ypr_rates(yaw, pitch, R_base.T @ (tool[:3] - base[:3]))])

    # -- protocol --------------------------------------------------------------------------
    def _devices(self, device_id: int) -> list[int]:
        """Device ids that take a packet addressed to ``device_id`` (broadcast: every joint)."""
        if device_id == BROADCAST:
            return [j.device_id for j in self.joints]
        return [device_id] if device_id in self._index or device_id in _BASE_DEVICES else []

    def answer(self, device_id: int, packet_id: int) -> bytes | None:
        """The data device ``device_id`` answers to a REQUEST of ``packet_id`` (None: not answered).

        Joints answer their state, limits, identity, environment and status; the base
        computer the end-effector pose and velocity; every device its identity, environment,
        status and heartbeat settings. Sizes and units follow docs/hardware.md.
        """
        pid = packet_id
        i = self._index.get(device_id)
        common = self._common(device_id, pid, i)
        if common is not None:
            return common
        if i is not None:
            j = self.joints[i]
            if pid == PacketID.POSITION:
                return encode_floats(float(self.positions()[i]))
            if pid == PacketID.VELOCITY:
                return encode_floats(float(self.velocities()[i]))
            if pid == PacketID.CURRENT:
                return encode_floats(float(self.currents()[i]))
            if pid == PacketID.MODE:
                return bytes((int(self.mode[i]),))
            if pid == PacketID.POSITION_LIMITS:  # max, then min
                return encode_floats(j.upper, j.lower)
            if pid == PacketID.VELOCITY_LIMITS:
                return encode_floats(j.max_velocity, -j.max_velocity)
            if pid == PacketID.CURRENT_LIMITS:
                return encode_floats(_CURRENT_LIMIT_MA, -_CURRENT_LIMIT_MA)
            return None
        if device_id == BASE_COMPUTER:
            if pid == PacketID.KM_END_POS:
                return encode_floats(*map(float, self.end_pose()))
            if pid == PacketID.KM_END_VEL:
                return encode_floats(*map(float, self.end_velocity()))
        return None

    def _common(self, device_id: int, pid: int, i: int | None) -> bytes | None:
        """Answers every device gives: identity, environment, status and heartbeat settings."""
        if pid == PacketID.SERIAL_NUMBER:
            return encode_floats(_SERIAL_BASE + device_id)
        if pid == PacketID.MODEL_NUMBER:
            return encode_floats(_MODEL_NUMBER)
        if pid == PacketID.DEVICE_ID:
            return bytes((device_id,))
        if pid == PacketID.SOFTWARE_VERSION:
            return bytes(_SOFTWARE_VERSION)
        if pid == PacketID.TEMPERATURE:
            return encode_floats(_TEMPERATURE_C)
        if pid == PacketID.HUMIDITY:
            return encode_floats(_HUMIDITY_PCT)
        if pid == PacketID.PRESSURE:
            return encode_floats(_PRESSURE_BAR)
        if pid == PacketID.VOLTAGE:
            return encode_floats(_VOLTAGE_V)
        if pid == PacketID.HARDWARE_STATUS:
            status = self.hardware_status(i) if i is not None else HardwareStatus.OK
            return int(status).to_bytes(4, "little")
        if pid == PacketID.HEARTBEAT_SET:
            ids = self.heartbeat_ids.get(device_id, ())
            return bytes(ids) + bytes(_HEARTBEAT_SLOTS - len(ids))
        if pid == PacketID.HEARTBEAT_FREQUENCY:
            return bytes((self.heartbeat_hz.get(device_id, 0),))
        return None

    def _reply(self, device_id: int, packet_id: int) -> bytes | None:
        data = self.answer(device_id, packet_id)
        return None if data is None else encode_packet(device_id, packet_id, data)

    def handle(self, pkt: Packet) -> list[bytes]:
        """Apply one received packet at the current simulated time.

        Returns:
          the encoded answers, one packet each, device by device (a broadcast REQUEST of k ids
          gives (n + 1)·k packets). Requests for ids a device does not answer, and packets of ids the
          device does not take, are ignored as the arm ignores them, and counted in
          :attr:`unanswered` and :attr:`ignored`.
        """
        out: list[bytes] = []
        pid, data = pkt.packet_id, pkt.data
        for did in self._devices(pkt.device_id):
            i = self._index.get(did)
            if pid == PacketID.REQUEST:
                for rid in data[:_HEARTBEAT_SLOTS]:  # a request lists at most 10 ids
                    a = self._reply(did, rid)
                    if a is None:
                        self.unanswered += 1
                    else:
                        out.append(a)
            elif pid in (PacketID.POSITION, PacketID.VELOCITY) and i is not None:
                self._demand(i, pid, data)
            elif pid == PacketID.MODE and len(data) == 1 and i is not None:
                self.mode[i] = data[0]
                self.vel_target[i] = 0.0
                self.target[i] = self.positions()[i]
            elif pid == PacketID.HEARTBEAT_SET and len(data) <= _HEARTBEAT_SLOTS:
                self.heartbeat_ids[did] = tuple(b for b in data if b)
            elif pid == PacketID.HEARTBEAT_FREQUENCY and len(data) == 1:
                self.heartbeat_hz[did] = data[0]
                self._next_heartbeat[did] = self.time if data[0] else math.inf
            else:
                self.ignored += 1
        return out

    def _demand(self, i: int, pid: int, data: bytes) -> None:
        self.demands += 1
        try:
            value = decode_float(data)
        except ValueError:
            self.ignored += 1
            return
        j = self.joints[i]
        if pid == PacketID.POSITION:
            if not j.contains(value):  # a real device clamps; the simulator counts and ignores
                self.limit_violations += 1
                return
            self.mode[i], self.target[i] = Mode.POSITION, value
        else:
            if not abs(value) <= j.max_velocity:
                self.limit_violations += 1
                return
            self.mode[i], self.vel_target[i] = Mode.VELOCITY, value

    def heartbeat(self) -> list[bytes]:
        """Heartbeat packets due at the current simulated time, one packet each ([] if none)."""
        out: list[bytes] = []
        now = self.time
        for did, due in self._next_heartbeat.items():
            hz = self.heartbeat_hz.get(did, 0)
            if not hz or now < due:
                continue
            self._next_heartbeat[did] = max(due + 1.0 / hz, now)
            out.extend(a for p in self.heartbeat_ids.get(did, ()) if (a := self._reply(did, p)) is not None)
        return out



def _ypr(R: np.ndarray) -> np.ndarray:
    """ZYX Euler angles (yaw, pitch, roll) [rad] of a rotation matrix ``R`` (3, 3)."""
    return np.array([math.atan2(R[1, 0], R[0, 0]), math.asin(max(-1.0, min(1.0, -R[2, 0]))),
                     math.atan2(R[2, 1], R[2, 2])])


def _ypr_rates(yaw: float, pitch: float, omega: np.ndarray) -> np.ndarray:
    """Yaw, pitch and roll rates [rad/s] for the angular velocity ``omega`` (3,) [rad/s, base
    frame]: ``ω = ψ̇ e_z + θ̇ R_z(ψ) e_y + φ̇ R_z(ψ) R_y(θ) e_x`` solved for the rates."""
    cy, sy, cp, sp = math.cos(yaw), math.sin(yaw), math.cos(pitch), math.sin(pitch)
    basis = np.array([[0.0, -sy, cy * cp], [0.0, cy, sy * cp], [1.0, 0.0, -sp]])
    return np.linalg.solve(basis, omega)


def _initial_positions(joints, q0) -> np.ndarray:
    """``(n + 1,)`` initial positions in wire units [rad …, mm]: ``q0``, or mid-range for the
    arm and the jaws' lower limit; a ValueError for a wrong count or a value outside a limit."""
    if q0 is None:
        q0 = [j.lower if j.unit == "mm" else 0.5 * (j.lower + j.upper) for j in joints]
    q0 = np.asarray(q0, dtype=float)
    if q0.shape != (len(joints),):
        raise ValueError(f"q0 must have {len(joints)} values ({', '.join(j.name for j in joints)}), got {q0.shape}")
    for j, v in zip(joints, q0):
        if not j.contains(v):
            raise ValueError(f"initial {j.name} = {v} outside [{j.lower}, {j.upper}]")
    return q0
