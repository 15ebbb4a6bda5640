"""Simulated Bravo 7 speaking BPL, backed by MuJoCo joint-space physics, with fault injection.

The physics model is deliberately small and private to ``hw`` (it does not depend on
``uvms_jax.kin``): the six revolute joints of :mod:`uvms_jax.bravo7` (origins, axes and limits
of the public URDF, docs/theory.md §1.3) with capsule links carrying the manufacturer's masses
and inertias under gravity and buoyancy (docs/hardware.md §3), and the jaws as one slide joint.
The physics runs in the arm's base frame; the base's orientation in the world
(``SimConfig.base_rpy``: upright, or hanging under a vehicle) turns gravity and buoyancy.
The device firmware is modelled as a servo that turns the demand into a joint speed every
physics step — POSITION mode ``v = clip(gain·(q* - q), ±v_max)``, VELOCITY mode
``v = clip(v*, ±v_max)``, other modes ``v = 0`` — tracked by a MuJoCo velocity actuator plus an
integral of the speed error (a second, torque actuator) that carries the load.

The devices answer every request of the protocol listing (docs/hardware.md §1), each answer
in its own datagram.

Layers:
  * :class:`SimArm` — the device: physics, modes, demands, BPL request answers, heartbeats.
    Demands outside the limits are ignored and counted (``limit_violations``), never obeyed.
  * :class:`SimLink` — the arm plus faults (drop, corruption, latency), shared by
  * :class:`SimServer` — a UDP server thread on 127.0.0.1 (ephemeral port by default), and
  * :class:`LoopbackTransport` — an in-process :class:`~uvms_jax.hw.Transport` on a
    :class:`VirtualClock`, so tests run a whole plan in simulated time without sockets.
"""

from __future__ import annotations

import collections
import heapq
import math
import random
import socket
import threading
import time
from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from uvms_jax import bravo7

from ._codec import Packet, PacketReader, decode_float, encode_floats, encode_packet
from ._config import SimConfig
from ._ids import BASE_COMPUTER, BASE_ROUTER, BROADCAST, HardwareStatus, Mode, PacketID
from ._joints import BRAVO7, MM_PER_M, JointSpec

if TYPE_CHECKING:
    import mujoco

__all__ = ["LoopbackTransport", "SimArm", "SimLink", "SimServer", "VirtualClock", "sim_spec"]

_MM = 1.0 / MM_PER_M  # jaws: mm on the wire, m in MuJoCo

# Physics of the simulated device (not Bravo 7 data): rotor inertia and damping per joint
# [kg·m², N·m·s/rad; jaws kg, N·s/m], the jaws' fingers box [m, kg], the velocity servo gain
# and the integral gain of the velocity loop [N·m/rad; N/m], which holds a load (gravity less
# buoyancy) with no steady speed error: the arm sags while the integral builds, then recovers.
_HINGE_ARMATURE, _HINGE_DAMPING = 0.05, 0.1
_JAWS_ARMATURE, _JAWS_DAMPING = 0.5, 1.0
_JAWS_HALF_SIZE, _JAWS_MASS = (0.01, 0.02, 0.02), 0.2
_KV = 30.0
_KI = 300.0
_GRAVITY = 9.81  # [m/s²]

# What the simulated devices report about themselves (the simulator's values, not a real
# arm's): serial number = base + device id, model number, software version (major, sub-major,
# minor), and a steady environment inside the housings.
_SERIAL_BASE = 7000.0
_MODEL_NUMBER = 7.0
_SOFTWARE_VERSION = (0, 1, 0)
_TEMPERATURE_C, _HUMIDITY_PCT, _PRESSURE_BAR, _VOLTAGE_V = 20.0, 15.0, 1.0, 24.0
# Motor current model: the URDF effort (9 N·m; jaws 10 N) takes this current, and the drive
# stops at the current limit (torque saturates there).
_EFFORT_CURRENT_MA = 2000.0
_CURRENT_LIMIT_MA = 4000.0
_HEARTBEAT_SLOTS = 10  # HEARTBEAT_SET carries 10 packet ids; a REQUEST lists at most 10
_BASE_DEVICES = (BASE_ROUTER, BASE_COMPUTER)


def _world_up(base_rpy: Sequence[float] = SimConfig.base_rpy) -> np.ndarray:
    """(3,) unit vector of the world's up (+z) in the arm's base frame, ``R^T e_z`` for the base
    orientation R = Rz(yaw) Ry(pitch) Rx(roll) of ``base_rpy`` (URDF roll, pitch, yaw [rad]).

    Gravity acts along minus this vector, buoyancy along it; (0, 0, 0) gives exactly
    (0, 0, 1) (the upright base), (π, 0, 0) about (0, 0, -1) (the base hanging).
    """
    import mujoco  # imported here: the protocol layer must not need MuJoCo

    q = np.zeros(4)
    mujoco.mju_euler2Quat(q, np.asarray(base_rpy, dtype=float), "XYZ")  # as the URDF origins below
    mujoco.mju_negQuat(q, q)  # the inverse rotation: world → base
    up = np.zeros(3)
    mujoco.mju_rotVecQuat(up, np.array([0.0, 0.0, 1.0]), q)
    return up


def sim_spec(joints: Sequence[JointSpec] = BRAVO7, kv: float = _KV,
             physics_dt: float = SimConfig.physics_dt, dynamics: bool = True,
             base_rpy: Sequence[float] = SimConfig.base_rpy) -> mujoco.MjSpec:
    """MuJoCo model of the simulated arm: six hinges G…B, jaws slide A, a velocity actuator and
    an integral-torque motor on each.

    Geometry from :mod:`uvms_jax.bravo7` (URDF joint origins and axes, tool frame, link
    radius); position limits from ``joints`` (wire units: rad, jaws mm). Links are capsules
    from each joint to the next (no contacts). With ``dynamics`` each link carries the
    manufacturer's mass, centre of mass and inertia (:func:`uvms_jax.bravo7.urdf_inertials`;
    the closed jaws' as a body fixed to link B at the tool frame, ``"jaws_housing"``) under
    gravity along the world's -z (:func:`_world_up`: the base's -z when upright); buoyancy is
    applied by :class:`SimArm`. MuJoCo's world is the arm's base frame. Without it the
    capsules have the density of water and are gravity compensated. The jaws' fingers (the
    slide) are light and gravity compensated either way.

    Args:
      joints: limits of G…B then A, by name.
      kv: velocity actuator gain [N·m·s/rad; N·s/m for the jaws].
      physics_dt: time step [s].
      dynamics: the manufacturer's mass properties, gravity on.
      base_rpy: orientation of the base in the world, URDF roll, pitch, yaw [rad]
        (:attr:`SimConfig.base_rpy`); it sets the gravity vector.

    Returns:
      an uncompiled ``mujoco.MjSpec`` (``.compile()`` gives the ``MjModel``).
    """
    import mujoco  # imported here: the protocol layer must not need MuJoCo

    limits = {j.name: j for j in joints}
    spec = mujoco.MjSpec()
    spec.modelname = "bravo7_hw_sim"
    spec.compiler.degree = False
    spec.compiler.eulerseq = "XYZ"  # URDF rpy: extrinsic roll, pitch, yaw
    spec.option.timestep = physics_dt
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    spec.option.gravity = -_GRAVITY * _world_up(base_rpy)
    spec.default.geom.contype = 0  # joint-space physics: nothing collides
    spec.default.geom.conaffinity = 0
    spec.default.geom.density = 1000.0
    inertials = dict(zip(bravo7.INERTIAL_BODIES, bravo7.urdf_inertials())) if dynamics else {}

    def place(frame, xyz, rpy) -> None:
        frame.pos = xyz
        frame.alt.type = mujoco.mjtOrientation.mjORIENTATION_EULER
        frame.alt.euler = rpy

    def carry(body, inertial) -> None:
        body.explicitinertial = True
        body.mass = inertial.mass
        body.ipos = inertial.com
        body.fullinertia = inertial.inertia

    parent = spec.worldbody
    chain = bravo7.ARM_JOINTS
    for k, joint in enumerate(chain):
        body = parent.add_body(name=f"link_{joint.name}", gravcomp=0.0 if dynamics else 1.0)
        place(body, joint.xyz, joint.rpy)
        if dynamics:
            carry(body, inertials[joint.name])
        lim = limits[joint.name]
        body.add_joint(name=joint.name, type=mujoco.mjtJoint.mjJNT_HINGE, axis=joint.axis,
                       range=[lim.lower, lim.upper], limited=mujoco.mjtLimited.mjLIMITED_TRUE,
                       armature=_HINGE_ARMATURE, damping=_HINGE_DAMPING)
        end = chain[k + 1].xyz if k + 1 < len(chain) else bravo7.TOOL_XYZ
        body.add_geom(type=mujoco.mjtGeom.mjGEOM_CAPSULE, fromto=[0, 0, 0, *end], size=[bravo7.LINK_RADIUS, 0, 0])
        parent = body
    tool = parent.add_frame()
    place(tool, bravo7.TOOL_XYZ, bravo7.TOOL_RPY)
    tool.add_site(name="tool")  # the tool frame: what KM_END_POS reports
    if dynamics:  # the closed jaws' mass, rigid on link B
        carry(tool.add_body(name="jaws_housing"), inertials["tool"])
    jaws = tool.add_body(name="jaws", gravcomp=1.0)
    place(jaws, bravo7.JAWS.xyz, bravo7.JAWS.rpy)
    lim = limits[bravo7.JAWS.name]
    jaws.add_joint(name=bravo7.JAWS.name, type=mujoco.mjtJoint.mjJNT_SLIDE, axis=bravo7.JAWS.axis,
                   range=[lim.lower * _MM, lim.upper * _MM], limited=mujoco.mjtLimited.mjLIMITED_TRUE,
                   armature=_JAWS_ARMATURE, damping=_JAWS_DAMPING)
    jaws.add_geom(type=mujoco.mjtGeom.mjGEOM_BOX, size=_JAWS_HALF_SIZE, mass=_JAWS_MASS)
    for joint in bravo7.JOINTS:
        act = spec.add_actuator(name=f"v_{joint.name}", target=joint.name, trntype=mujoco.mjtTrn.mjTRN_JOINT)
        act.set_to_velocity(kv=kv)
        spec.add_actuator(name=f"i_{joint.name}", target=joint.name, trntype=mujoco.mjtTrn.mjTRN_JOINT)
    return spec


class SimArm:
    """The simulated device: MuJoCo physics plus BPL behaviour.

    Args:
      config: servo, physics and the device-side faults (stuck joint, hardware status).
      q0: initial positions in plan order G, F, E, D, C, B, A [rad …, mm]; default mid-range
        arm and jaws at 0 mm.
      joints: joint specs (limits, speed limits).
    """

    def __init__(self, config: SimConfig = SimConfig(), q0: Sequence[float] | None = None,
                 joints: Sequence[JointSpec] = BRAVO7) -> None:
        import mujoco  # imported here: the protocol layer must not need MuJoCo

        self._mj = mujoco
        self.config = config
        self.joints = tuple(joints)
        self.model = sim_spec(self.joints, physics_dt=config.physics_dt, dynamics=config.dynamics,
                              base_rpy=config.base_rpy).compile()
        self.data = mujoco.MjData(self.model)
        names = [j.name for j in self.joints]
        self._qadr = np.array([self.model.jnt_qposadr[self.model.joint(n).id] for n in names])
        self._dadr = np.array([self.model.jnt_dofadr[self.model.joint(n).id] for n in names])
        self._act = np.array([self.model.actuator(f"v_{n}").id for n in names])
        self._iact = np.array([self.model.actuator(f"i_{n}").id for n in names])
        self._scale = np.array([_MM if j.unit == "mm" else 1.0 for j in self.joints])  # wire → MuJoCo
        self._vmax = np.array([j.max_velocity for j in self.joints])
        self._index = {j.device_id: i for i, j in enumerate(self.joints)}
        if q0 is None:
            q0 = [0.0 if j.unit == "mm" else 0.5 * (j.lower + j.upper) for j in self.joints]
        q0 = np.asarray(q0, dtype=float)
        if q0.shape != (len(self.joints),):
            raise ValueError(f"q0 must have {len(self.joints)} values (G…B, A), got {q0.shape}")
        for j, v in zip(self.joints, q0):
            if not j.contains(v):
                raise ValueError(f"initial {j.name} = {v} outside [{j.lower}, {j.upper}]")
        self.data.qpos[self._qadr] = q0 * self._scale
        self._mj.mj_forward(self.model, self.data)
        # Buoyancy of each link with mass: body ids, centres of buoyancy in the bodies [m], lifts
        # [N] along the world's up, fixed in the base frame (the base does not move).
        buoyant = [(self.model.body("jaws_housing" if body == "tool" else f"link_{body}").id, inertial)
                   for body, inertial in zip(bravo7.INERTIAL_BODIES, bravo7.urdf_inertials())
                   if body != "base" and config.dynamics and config.water_density > 0]
        self._buoy_ids = np.array([b for b, _ in buoyant], dtype=int)
        lifts = np.array([config.water_density * i.volume * _GRAVITY for _, i in buoyant])
        self._buoy_arm = np.array([np.subtract(i.cob, i.com) for _, i in buoyant]).reshape(-1, 3)
        lift = lifts[:, None] * _world_up(config.base_rpy)  # (k, 3) [N]
        self.data.xfrc_applied[self._buoy_ids, :3] = lift
        # Its moment arm turns with the link: r × F = [F]×ᵀ r, whose row j is F × e_j (k, 3, 3) [N].
        self._buoy_moment = np.cross(lift[:, None, :], np.eye(3))
        # Views of MjData (fetching one is slow in a per-step loop) and the rows of the buoyant
        # bodies: a slice when their ids run on (they do: G…B, then the jaws' housing).
        self._xmat, self._xfrc = self.data.xmat, self.data.xfrc_applied
        ids = self._buoy_ids
        contiguous = ids.size and np.array_equal(ids, np.arange(ids[0], ids[0] + ids.size))
        self._buoy_rows = slice(int(ids[0]), int(ids[0]) + ids.size) if contiguous else ids
        # The velocity loop's integral [rad; m], started at what holds the arm still where it is.
        self._integral = self._holding_torque() / _KI
        n = len(self.joints)
        self.mode = np.full(n, int(Mode.POSITION))
        self.target = q0.copy()  # wire units
        self.vel_target = np.zeros(n)
        self.stuck = -1 if not config.stuck_joint else names.index(config.stuck_joint)
        self._stuck_q = self.data.qpos[self._qadr].copy()
        self.fault_index = -1 if not config.fault_joint else names.index(config.fault_joint)
        self.limit_violations = 0
        self.demands = 0
        self.unanswered = 0  # requested ids a device does not answer
        self.ignored = 0  # received packets a device does not take (unknown id, bad size)
        # Heartbeat settings per device id: streamed packet ids, rate [Hz], next due time [s].
        self.heartbeat_ids: dict[int, tuple[int, ...]] = {}
        self.heartbeat_hz: dict[int, int] = {}
        self._next_heartbeat: dict[int, float] = {}
        self._tool = self.model.site("tool").id
        efforts = {j.name: j.effort for j in bravo7.JOINTS}
        self._torque_constant = np.array([efforts[j.name] for j in self.joints]) / (_EFFORT_CURRENT_MA * 1e-3)
        self._max_integral = self._torque_constant * _CURRENT_LIMIT_MA * 1e-3 / _KI
        # The jaws' fingers carry no load (gravity compensated): no integral, which would wind
        # up while they squeeze an object and hold them shut after the command to open.
        self._max_integral[[j.unit == "mm" for j in self.joints]] = 0.0
        np.clip(self._integral, -self._max_integral, self._max_integral, out=self._integral)

    # -- physics ---------------------------------------------------------------------------
    @property
    def time(self) -> float:
        """Simulated time [s]."""
        return float(self.data.time)

    def positions(self) -> np.ndarray:
        """(n,) positions in wire units (rad, mm), plan order G…B, A."""
        return self.data.qpos[self._qadr] / self._scale

    def velocities(self) -> np.ndarray:
        """(n,) velocities in wire units (rad/s, mm/s)."""
        return self.data.qvel[self._dadr] / self._scale

    def step_to(self, t: float) -> None:
        """Advance physics (and the servo, every step) up to simulated time ``t`` [s]."""
        dt = self.model.opt.timestep
        if self.data.time + 0.5 * dt > t:
            return
        d, q_idx, d_idx, scale = self.data, self._qadr, self._dadr, self._scale
        qpos, qvel, ctrl = d.qpos, d.qvel, d.ctrl
        width = self.config.object_width_mm * _MM if self.config.object_width_mm > 0 else -math.inf
        # modes and demands change only between calls (in handle): fixed for this stretch
        position = self.mode == int(Mode.POSITION)
        held = np.where(self.mode == int(Mode.VELOCITY), self.vel_target, 0.0)
        gain, vmax, lo, hi = self.config.servo_gain, self._vmax, -self._max_integral, self._max_integral
        act, iact, integral = self._act, self._iact, self._integral
        steps = int(math.floor((t - d.time) / dt + 0.5))
        for _ in range(steps):
            v = np.where(position, gain * (self.target - qpos[q_idx] / scale), held)
            np.clip(v, -vmax, vmax, out=v)
            if self.stuck >= 0:
                v[self.stuck] = 0.0
            jaws_before = qpos[q_idx[-1]]
            v *= scale  # MuJoCo units
            ctrl[act] = v
            # integral of the speed error, clamped where the drive saturates (no wind-up)
            integral += (v - qvel[d_idx]) * dt
            np.clip(integral, lo, hi, out=integral)
            ctrl[iact] = _KI * integral
            self._apply_buoyancy()
            self._mj.mj_step(self.model, d)
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
        """(n,) motor currents [mA]: each joint's drive torque (jaws: force) over its torque constant."""
        force = self.data.actuator_force
        return (force[self._act] + force[self._iact]) / self._torque_constant * 1e3

    def _apply_buoyancy(self) -> None:
        """Set each link's buoyancy (along the world's up, at its centre of buoyancy) as an
        applied force.

        MuJoCo applies it at the centre of mass, so the lift's torque about that point goes
        with it: ``r × F``, r = R (cob - com) in MuJoCo's world (the base frame), F the lift
        along :func:`_world_up` (F is set once; this runs every physics step, hence the
        precomputed matrix of ``r ↦ r × F``)."""
        if self._buoy_ids.size == 0:
            return
        r = np.einsum("kij,kj->ki", self._xmat[self._buoy_rows].reshape(-1, 3, 3), self._buoy_arm)
        self._xfrc[self._buoy_rows, 3:6] = np.einsum("kij,kj->ki", self._buoy_moment, r)

    def _holding_torque(self) -> np.ndarray:
        """(n,) drive torques that hold the arm still in its current pose [N·m; N]."""
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
        p = self.data.site_xpos[self._tool] * MM_PER_M
        return np.concatenate([p, _ypr(self.data.site_xmat[self._tool].reshape(3, 3))])

    def end_velocity(self) -> np.ndarray:
        """(6,) tool-frame velocity in the base frame: X, Y, Z [mm/s], then the rates of the
        yaw, pitch and roll of :meth:`end_pose` [rad/s]."""
        mj = self._mj
        mj.mj_kinematics(self.model, self.data)
        mj.mj_comPos(self.model, self.data)
        mj.mj_comVel(self.model, self.data)
        v = np.zeros(6)  # [angular (3), linear (3)] in the world frame, at the site
        mj.mj_objectVelocity(self.model, self.data, mj.mjtObj.mjOBJ_SITE, self._tool, v, 0)
        yaw, pitch, _ = _ypr(self.data.site_xmat[self._tool].reshape(3, 3))
        return np.concatenate([v[3:] * MM_PER_M, _ypr_rates(yaw, pitch, v[:3])])

    # -- protocol --------------------------------------------------------------------------
    def _devices(self, device_id: int) -> list[int]:
        """Device ids that take a packet addressed to ``device_id`` (broadcast: the seven joints)."""
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
          gives 7·k packets). Requests for ids a device does not answer, and packets of ids the
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


class SimLink:
    """A :class:`SimArm` behind a faulty link: drops, corruption and latency (seeded).

    Each answer leaves as its own datagram, as each device of a Bravo 7 answers for itself
    over UDP; with ``config.coalesce`` the answers to one received datagram share one (a byte
    stream's view, as on serial). Drops, corruption and latency apply per datagram.
    """

    def __init__(self, arm: SimArm, config: SimConfig | None = None) -> None:
        self.arm = arm
        self.config = arm.config if config is None else config
        self._rng = random.Random(self.config.seed)
        self._reader = PacketReader()
        self._outbox: list[tuple[float, int, bytes]] = []
        self._seq = 0
        self.dropped = self.corrupted = 0

    @property
    def reader_stats(self):
        """Decoder statistics of what the device received."""
        return self._reader.stats

    def receive(self, datagram: bytes, now: float) -> None:
        """A datagram arrives from the client at simulated time ``now`` [s]."""
        if self._rng.random() < self.config.drop:
            self.dropped += 1
            return
        self.arm.step_to(now)
        self._emit([a for p in self._reader.feed(datagram) for a in self.arm.handle(p)], now)

    def tick(self, now: float) -> None:
        """Advance physics to ``now`` and emit due heartbeats."""
        self.arm.step_to(now)
        self._emit(self.arm.heartbeat(), now)

    def _emit(self, packets: list[bytes], now: float) -> None:
        if not packets:
            return
        for data in [b"".join(packets)] if self.config.coalesce else packets:
            if self._rng.random() < self.config.drop:
                self.dropped += 1
                continue
            if self._rng.random() < self.config.corrupt:
                self.corrupted += 1
                b = bytearray(data)
                b[self._rng.randrange(len(b))] ^= self._rng.randrange(1, 256)
                data = bytes(b)
            self._seq += 1
            heapq.heappush(self._outbox, (now + self.config.latency_s, self._seq, data))

    def next_due(self) -> float:
        """Time the next queued datagram is due [s] (inf if none)."""
        return self._outbox[0][0] if self._outbox else math.inf

    def pop_due(self, now: float) -> list[bytes]:
        """Every datagram due by ``now``, in order."""
        out = []
        while self._outbox and self._outbox[0][0] <= now:
            out.append(heapq.heappop(self._outbox)[2])
        return out


class VirtualClock:
    """Simulated time for in-process runs: ``now()`` and ``sleep(dt)`` that just advances."""

    def __init__(self, t0: float = 0.0) -> None:
        self.t = t0

    def now(self) -> float:
        """Current simulated time [s]."""
        return self.t

    def sleep(self, dt: float) -> None:
        """Advance simulated time by ``dt`` [s] (negative values are ignored)."""
        if dt > 0:
            self.t += dt


class LoopbackTransport:
    """In-process transport to a :class:`SimLink` on a :class:`VirtualClock` (no sockets).

    ``recv`` returns one datagram, as a UDP socket does, advancing the clock to the next one
    (or by the whole timeout), so a run costs only its computation time. ``sent`` keeps every
    datagram the client wrote.
    """

    datagrams = True  # each recv is one whole datagram

    def __init__(self, link: SimLink, clock: VirtualClock, *, tick: float = 0.01) -> None:
        self.link, self.clock = link, clock
        self.name = "loopback"
        self.sent: list[bytes] = []
        self._tick = tick
        self._inbox: collections.deque[bytes] = collections.deque()

    def send(self, data: bytes) -> None:
        self.sent.append(bytes(data))
        self.link.receive(data, self.clock.now())

    def recv(self, timeout: float) -> bytes:
        end = self.clock.now() + max(timeout, 0.0)
        while True:
            if self._inbox:
                return self._inbox.popleft()
            self.link.tick(self.clock.now())
            self._inbox.extend(self.link.pop_due(self.clock.now()))
            if self._inbox:
                return self._inbox.popleft()
            nxt = min(self.link.next_due(), end, self.clock.now() + self._tick)
            if self.clock.now() >= end:
                return b""
            self.clock.sleep(nxt - self.clock.now())

    def close(self) -> None:
        pass


class SimServer:
    """UDP server thread speaking BPL for a :class:`SimArm` (real time, 127.0.0.1).

    Replies go to the address of the last datagram received. Use as a context manager::

        with SimServer(SimArm(cfg, q0)) as server:
            transport = UdpTransport(*server.address)
    """

    def __init__(self, arm: SimArm, config: SimConfig | None = None, host: str = "127.0.0.1",
                 port: int = 0, poll_s: float = 0.002) -> None:
        self.link = SimLink(arm, config)
        self.arm = arm
        self._sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self._sock.bind((host, port))
        self.address: tuple[str, int] = self._sock.getsockname()
        self._poll = poll_s
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self.lock = threading.Lock()
        self.error: BaseException | None = None

    def start(self) -> SimServer:
        """Start the server thread (simulated time 0 = now)."""
        self._t0 = time.monotonic() - self.arm.time
        self._thread = threading.Thread(target=self._run, name="bravo7-sim", daemon=True)
        self._thread.start()
        return self

    def stop(self) -> None:
        """Stop the thread and close the socket."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=2.0)
        self._sock.close()

    def __enter__(self) -> SimServer:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()

    def _run(self) -> None:
        peer = None
        try:
            while not self._stop.is_set():
                now = time.monotonic() - self._t0
                wait = min(self._poll, max(self.link.next_due() - now, 0.0))
                self._sock.settimeout(max(wait, 1e-4))
                try:
                    data, peer_addr = self._sock.recvfrom(65536)
                except (TimeoutError, BlockingIOError):
                    data = None
                except OSError:
                    if self._stop.is_set():
                        return
                    raise
                now = time.monotonic() - self._t0
                with self.lock:
                    if data is not None:
                        peer = peer_addr
                        self.link.receive(data, now)
                    self.link.tick(now)
                    out = self.link.pop_due(now)
                if peer is not None:
                    for datagram in out:
                        self._sock.sendto(datagram, peer)
        except BaseException as e:  # surfaced to tests through .error
            self.error = e
