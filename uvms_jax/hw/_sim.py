"""Simulated Bravo 7 speaking BPL, backed by MuJoCo joint-space physics, with fault injection.

The physics model is deliberately small and private to ``hw`` (it does not depend on
``uvms_jax.kin``): the six revolute joints of :mod:`uvms_jax.bravo7` (origins, axes and limits
of the public URDF, docs/theory.md §1.3) with capsule links, gravity compensated (an underwater
arm is near neutral buoyancy), and the jaws as one slide joint. Each joint is driven by a
MuJoCo velocity actuator; the device firmware is modelled as a servo that turns the demand into
a joint speed every physics step: POSITION mode ``v = clip(gain·(q* - q), ±v_max)``, VELOCITY
mode ``v = clip(v*, ±v_max)``, other modes ``v = 0``.

Layers:
  * :class:`SimArm` — the device: physics, modes, demands, BPL request answers, heartbeats.
    Demands outside the limits are ignored and counted (``limit_violations``), never obeyed.
  * :class:`SimLink` — the arm plus faults (drop, corruption, latency), shared by
  * :class:`SimServer` — a UDP server thread on 127.0.0.1 (ephemeral port by default), and
  * :class:`LoopbackTransport` — an in-process :class:`~uvms_jax.hw.Transport` on a
    :class:`VirtualClock`, so tests run a whole plan in simulated time without sockets.
"""

from __future__ import annotations

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
from ._ids import BROADCAST, HardwareStatus, Mode, PacketID
from ._joints import BRAVO7, MM_PER_M, JointSpec

if TYPE_CHECKING:
    import mujoco

__all__ = ["LoopbackTransport", "SimArm", "SimLink", "SimServer", "VirtualClock", "sim_spec"]

_MM = 1.0 / MM_PER_M  # jaws: mm on the wire, m in MuJoCo

# Physics of the simulated device (not Bravo 7 data): rotor inertia and damping per joint
# [kg·m², N·m·s/rad; jaws kg, N·s/m], the jaws' box [m, kg] and the velocity servo gain.
_HINGE_ARMATURE, _HINGE_DAMPING = 0.05, 0.1
_JAWS_ARMATURE, _JAWS_DAMPING = 0.5, 1.0
_JAWS_HALF_SIZE, _JAWS_MASS = (0.01, 0.02, 0.02), 0.2
_KV = 30.0


def sim_spec(joints: Sequence[JointSpec] = BRAVO7, kv: float = _KV,
             physics_dt: float = SimConfig.physics_dt) -> mujoco.MjSpec:
    """MuJoCo model of the simulated arm: six hinges G…B, jaws slide A, one velocity actuator each.

    Geometry from :mod:`uvms_jax.bravo7` (URDF joint origins and axes, tool frame, link
    radius); position limits from ``joints`` (wire units: rad, jaws mm). Links are capsules
    from each joint to the next (density 1000 kg/m³, no contacts), all gravity compensated.

    Args:
      joints: limits of G…B then A, by name.
      kv: velocity actuator gain [N·m·s/rad; N·s/m for the jaws].
      physics_dt: time step [s].

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
    spec.default.geom.contype = 0  # joint-space physics: nothing collides
    spec.default.geom.conaffinity = 0
    spec.default.geom.density = 1000.0

    def place(frame, xyz, rpy) -> None:
        frame.pos = xyz
        frame.alt.type = mujoco.mjtOrientation.mjORIENTATION_EULER
        frame.alt.euler = rpy

    parent = spec.worldbody
    chain = bravo7.ARM_JOINTS
    for k, joint in enumerate(chain):
        body = parent.add_body(name=f"link_{joint.name}", gravcomp=1.0)
        place(body, joint.xyz, joint.rpy)
        lim = limits[joint.name]
        body.add_joint(name=joint.name, type=mujoco.mjtJoint.mjJNT_HINGE, axis=joint.axis,
                       range=[lim.lower, lim.upper], limited=mujoco.mjtLimited.mjLIMITED_TRUE,
                       armature=_HINGE_ARMATURE, damping=_HINGE_DAMPING)
        end = chain[k + 1].xyz if k + 1 < len(chain) else bravo7.TOOL_XYZ
        body.add_geom(type=mujoco.mjtGeom.mjGEOM_CAPSULE, fromto=[0, 0, 0, *end], size=[bravo7.LINK_RADIUS, 0, 0])
        parent = body
    tool = parent.add_frame()
    place(tool, bravo7.TOOL_XYZ, bravo7.TOOL_RPY)
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
        self.model = sim_spec(self.joints, physics_dt=config.physics_dt).compile()
        self.data = mujoco.MjData(self.model)
        names = [j.name for j in self.joints]
        self._qadr = np.array([self.model.jnt_qposadr[self.model.joint(n).id] for n in names])
        self._dadr = np.array([self.model.jnt_dofadr[self.model.joint(n).id] for n in names])
        self._act = np.array([self.model.actuator(f"v_{n}").id for n in names])
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
        n = len(self.joints)
        self.mode = np.full(n, int(Mode.POSITION))
        self.target = q0.copy()  # wire units
        self.vel_target = np.zeros(n)
        self.stuck = -1 if not config.stuck_joint else names.index(config.stuck_joint)
        self._stuck_q = self.data.qpos[self._qadr].copy()
        self.fault_index = -1 if not config.fault_joint else names.index(config.fault_joint)
        self.limit_violations = 0
        self.demands = 0
        self.unanswered = 0
        self.heartbeat_ids: dict[int, tuple[int, ...]] = {}
        self.heartbeat_hz = 0
        self._next_heartbeat = math.inf

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
        q_idx, d_idx = self._qadr, self._dadr
        width = self.config.object_width_mm * _MM if self.config.object_width_mm > 0 else -math.inf
        while self.data.time + 0.5 * dt <= t:
            q = self.data.qpos[q_idx] / self._scale
            v = np.where(self.mode == Mode.POSITION, self.config.servo_gain * (self.target - q),
                         np.where(self.mode == Mode.VELOCITY, self.vel_target, 0.0))
            v = np.clip(v, -self._vmax, self._vmax)
            if self.stuck >= 0:
                v[self.stuck] = 0.0
            jaws_before = self.data.qpos[q_idx[-1]]
            self.data.ctrl[self._act] = v * self._scale
            self._mj.mj_step(self.model, self.data)
            if self.stuck >= 0:
                self.data.qpos[q_idx[self.stuck]] = self._stuck_q[self.stuck]
                self.data.qvel[d_idx[self.stuck]] = 0.0
            if jaws_before >= width > self.data.qpos[q_idx[-1]]:  # closed onto the object: stall there
                self.data.qpos[q_idx[-1]] = width
                self.data.qvel[d_idx[-1]] = 0.0

    def hardware_status(self, i: int) -> HardwareStatus:
        """Status bits of joint index ``i`` at the current simulated time."""
        if i == self.fault_index and self.time >= self.config.fault_after_s:
            return HardwareStatus(self.config.fault_bits)
        return HardwareStatus.OK

    # -- protocol --------------------------------------------------------------------------
    def _devices(self, device_id: int) -> list[int]:
        if device_id == BROADCAST:
            return list(range(len(self.joints)))
        i = self._index.get(device_id)
        return [] if i is None else [i]

    def _answer(self, i: int, pid: int) -> bytes | None:
        did = self.joints[i].device_id
        if pid == PacketID.POSITION:
            return encode_packet(did, pid, encode_floats(float(self.positions()[i])))
        if pid == PacketID.VELOCITY:
            return encode_packet(did, pid, encode_floats(float(self.velocities()[i])))
        if pid == PacketID.HARDWARE_STATUS:
            return encode_packet(did, pid, bytes((int(self.hardware_status(i)),)))
        if pid == PacketID.MODE:
            return encode_packet(did, pid, bytes((int(self.mode[i]),)))
        if pid == PacketID.POSITION_LIMITS:
            j = self.joints[i]
            return encode_packet(did, pid, encode_floats(j.lower, j.upper))
        if pid == PacketID.VELOCITY_LIMITS:
            j = self.joints[i]
            return encode_packet(did, pid, encode_floats(-j.max_velocity, j.max_velocity))
        if pid == PacketID.HEARTBEAT_FREQUENCY:
            return encode_packet(did, pid, bytes((self.heartbeat_hz,)))
        return None

    def handle(self, pkt: Packet) -> bytes:
        """Apply one received packet at the current simulated time; returns the reply bytes."""
        out = []
        pid, data = pkt.packet_id, pkt.data
        for i in self._devices(pkt.device_id):
            if pid == PacketID.REQUEST:
                for rid in data:
                    a = self._answer(i, rid)
                    if a is None:
                        self.unanswered += 1
                    else:
                        out.append(a)
            elif pid in (PacketID.POSITION, PacketID.VELOCITY):
                self._demand(i, pid, data)
            elif pid == PacketID.MODE and len(data) == 1:
                self.mode[i] = data[0]
                self.vel_target[i] = 0.0
                self.target[i] = self.positions()[i]
            elif pid == PacketID.HEARTBEAT_SET:
                self.heartbeat_ids[i] = tuple(data)
            elif pid == PacketID.HEARTBEAT_FREQUENCY and len(data) == 1:
                self.heartbeat_hz = data[0]
                self._next_heartbeat = self.time if data[0] else math.inf
        return b"".join(out)

    def _demand(self, i: int, pid: int, data: bytes) -> None:
        self.demands += 1
        try:
            value = decode_float(data)
        except ValueError:
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

    def heartbeat(self) -> bytes:
        """Heartbeat packets due at the current simulated time (``b""`` if none)."""
        if self.time < self._next_heartbeat or not self.heartbeat_hz:
            return b""
        self._next_heartbeat = max(self._next_heartbeat + 1.0 / self.heartbeat_hz, self.time)
        return b"".join(a for i, ids in self.heartbeat_ids.items() for p in ids
                        if (a := self._answer(i, p)) is not None)


class SimLink:
    """A :class:`SimArm` behind a faulty link: drops, corruption and latency (seeded)."""

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
        reply = b"".join(self.arm.handle(p) for p in self._reader.feed(datagram))
        if reply:
            self._emit(reply, now)

    def tick(self, now: float) -> None:
        """Advance physics to ``now`` and emit due heartbeats."""
        self.arm.step_to(now)
        hb = self.arm.heartbeat()
        if hb:
            self._emit(hb, now)

    def _emit(self, data: bytes, now: float) -> None:
        if self._rng.random() < self.config.drop:
            self.dropped += 1
            return
        if self._rng.random() < self.config.corrupt:
            self.corrupted += 1
            b = bytearray(data)
            b[self._rng.randrange(len(b))] ^= self._rng.randrange(1, 256)
            data = bytes(b)
        self._seq += 1
        heapq.heappush(self._outbox, (now + self.config.latency_s, self._seq, data))

    def next_due(self) -> float:
        """Time the next queued reply is due [s] (inf if none)."""
        return self._outbox[0][0] if self._outbox else math.inf

    def pop_due(self, now: float) -> bytes:
        """All replies due by ``now``, concatenated."""
        out = []
        while self._outbox and self._outbox[0][0] <= now:
            out.append(heapq.heappop(self._outbox)[2])
        return b"".join(out)


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

    ``recv`` advances the clock to the next reply (or by the whole timeout), so a run costs
    only its computation time. ``sent`` keeps every datagram the client wrote.
    """

    def __init__(self, link: SimLink, clock: VirtualClock, *, tick: float = 0.01) -> None:
        self.link, self.clock = link, clock
        self.name = "loopback"
        self.sent: list[bytes] = []
        self._tick = tick

    def send(self, data: bytes) -> None:
        self.sent.append(bytes(data))
        self.link.receive(data, self.clock.now())

    def recv(self, timeout: float) -> bytes:
        end = self.clock.now() + max(timeout, 0.0)
        while True:
            self.link.tick(self.clock.now())
            data = self.link.pop_due(self.clock.now())
            if data:
                return data
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
                if out and peer is not None:
                    self._sock.sendto(out, peer)
        except BaseException as e:  # surfaced to tests through .error
            self.error = e
