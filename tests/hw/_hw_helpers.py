"""Helpers for the hardware-runner tests: in-process simulated runs (imported by the tests)."""

from __future__ import annotations

import enum

from uvms_jax.hw import (BROADCAST, Executor, ExecutorSettings, LoopbackTransport, PacketID, PacketReader, ReachArm,
                         SimArm, SimLink, SimSettings, VirtualClock, decode_float, joint_specs, parse_plan)
from uvms_jax.robot import load_arm

BRAVO = load_arm("bravo7")  # the robot the hardware tests drive
BRAVO7 = joint_specs(BRAVO)  # its joint table: G … B [rad], jaws A [mm]
JAWS = BRAVO7[-1]
# The Bravo 7's device ids by joint letter (A = jaws 0x01 … G = 0x07), and broadcast.
DeviceID = enum.IntEnum("DeviceID", sorted(((j.name, j.device_id) for j in BRAVO7), key=lambda p: p[1])
                        + [("BROADCAST", BROADCAST)])

Q0 = [1.0, 1.5, 1.5, 2.0, 1.5, 2.0]
Q1 = [1.2, 1.3, 1.7, 2.0, 1.4, 2.3]


def bravo7_client(transport, **kw) -> ReachArm:
    """A client of the Bravo 7's joint table over ``transport``."""
    return ReachArm(transport, BRAVO7, **kw)


def short_plan(q0=Q0, q1=Q1):
    """A sped-up plan: out and back with a gripper step in between (~3 s simulated)."""
    return parse_plan({
        "joint_names": list("GFEDCB"),
        "segments": [
            {"name": "out", "t": [0.0, 0.8], "q": [list(q0), list(q1)], "gripper": {"jaws_mm": 10.0}},
            {"name": "back", "t": [0.0, 0.8], "q": [list(q1), list(q0)]},
        ],
    })


class SimRun:
    """A client + executor wired to a simulated arm on a virtual clock."""

    def __init__(self, sim: SimSettings = SimSettings(), hw: ExecutorSettings = ExecutorSettings(), q0=Q0, jaws=0.0,
                 robot=BRAVO):
        self.clock = VirtualClock()
        self.arm = SimArm(robot, sim, list(q0) + [jaws])
        self.link = SimLink(self.arm)
        self.transport = LoopbackTransport(self.link, self.clock)
        self.client = ReachArm(self.transport, self.arm.joints, clock=self.clock.now)
        self.executor = Executor(self.client, hw, sleep=self.clock.sleep)

    def sent_packets(self):
        """Every packet the client wrote, decoded."""
        r = PacketReader()
        out = [p for d in self.transport.sent for p in r.feed(d)]
        assert r.stats.rejected == 0
        return out


def assert_within_limits(packets) -> None:
    """No POSITION/VELOCITY demand outside the Bravo 7 limits (docs/theory.md §1.3) (as float32 on the wire)."""
    spec = {j.device_id: j for j in BRAVO7}
    for p in packets:
        if p.packet_id == PacketID.POSITION:
            assert spec[p.device_id].contains(decode_float(p.data)), p
        elif p.packet_id == PacketID.VELOCITY:
            assert abs(decode_float(p.data)) <= spec[p.device_id].max_velocity, p




def _rot(axis, angle):
    """Rotation matrix about a unit ``axis`` by ``angle`` [rad] (Rodrigues)."""
    import numpy as np

    k = np.asarray(axis, dtype=float)
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + np.sin(angle) * K + (1 - np.cos(angle)) * K @ K


def _rpy(rpy):
    """URDF roll-pitch-yaw: R = Rz(yaw) Ry(pitch) Rx(roll)."""
    r, p, y = rpy
    return _rot((0, 0, 1), y) @ _rot((0, 1, 0), p) @ _rot((1, 0, 0), r)


def urdf_link_frames(q):
    """Independent numpy FK of the Bravo 7 URDF (docs/theory.md §1.3 table): the 4×4 frame of
    each link G…B after its joint, then the tool frame, in the base frame [m]."""
    import numpy as np

    from uvms_jax import bravo7

    T = np.eye(4)
    frames = []
    for joint, angle in zip(bravo7.ARM_JOINTS, q):
        origin = np.eye(4)
        origin[:3, :3], origin[:3, 3] = _rpy(joint.rpy), joint.xyz
        motion = np.eye(4)
        motion[:3, :3] = _rot(joint.axis, angle)
        T = T @ origin @ motion
        frames.append(T)
    tool = np.eye(4)
    tool[:3, :3], tool[:3, 3] = _rpy(bravo7.TOOL_RPY), bravo7.TOOL_XYZ
    frames.append(T @ tool)
    return frames


def ypr_matrix(yaw, pitch, roll):
    """Rotation of ZYX Euler angles: Rz(yaw) Ry(pitch) Rx(roll)."""
    return _rpy((roll, pitch, yaw))


class Recorder:
    """Transport that keeps what is sent and never answers."""

    def __init__(self):
        self.sent = []

    def send(self, data):
        self.sent.append(data)

    def recv(self, timeout):
        return b""

    def close(self):
        pass
