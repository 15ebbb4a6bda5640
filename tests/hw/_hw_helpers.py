"""Helpers for the hardware-runner tests: in-process simulated runs (imported by the tests)."""

from __future__ import annotations

from uvms_jax.hw import (BRAVO7, Bravo7, Executor, HwConfig, LoopbackTransport, PacketID, PacketReader,
                         SimArm, SimConfig, SimLink, VirtualClock, decode_float, parse_plan)

Q0 = [1.0, 1.5, 1.5, 2.0, 1.5, 2.0]
Q1 = [1.2, 1.3, 1.7, 2.0, 1.4, 2.3]


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

    def __init__(self, sim: SimConfig = SimConfig(), hw: HwConfig = HwConfig(), q0=Q0, jaws=0.0):
        self.clock = VirtualClock()
        self.arm = SimArm(sim, list(q0) + [jaws])
        self.link = SimLink(self.arm)
        self.transport = LoopbackTransport(self.link, self.clock)
        self.client = Bravo7(self.transport, clock=self.clock.now)
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


