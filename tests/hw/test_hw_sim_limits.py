"""The simulated arm keeps its limits as the real controller does (demands stop at the limit,
MuJoCo's soft limits notwithstanding), and its queues are bounded (the oldest dropped, counted)."""

from __future__ import annotations

import numpy as np
import pytest

from _hw_helpers import BRAVO, BRAVO7, SimRun
from uvms_jax.hw import BROADCAST, PacketID, PacketReader, SimArm, SimSettings, encode_floats, encode_packet
from uvms_jax.hw._joints import wire_position
from uvms_jax.hw._sim_link import QUEUE_LIMIT

# Each joint starts this far inside a limit (rad; jaws mm): far enough to reach full speed.
START_INSIDE = np.array([0.4] * 6 + [15.0])


def _send(arm, device, pid, data):
    for p in PacketReader().feed(encode_packet(device, pid, data)):
        arm.handle(p)


@pytest.mark.parametrize("side", [+1, -1])
@pytest.mark.parametrize("demand", ["velocity", "position"])
def test_full_speed_demands_stop_at_the_limit(side, demand):
    """Every joint at once driven at full speed (or to its limit) towards one of its limits:
    none passes it (before the fix joint B passed by 0.0129 rad, the jaws by 0.15 mm), and each
    reaches it."""
    lower = np.array([j.lower for j in BRAVO7])
    upper = np.array([j.upper for j in BRAVO7])
    limit = upper if side > 0 else lower
    arm = SimArm(BRAVO, SimSettings(), limit - side * START_INSIDE)
    for j in BRAVO7:
        if demand == "velocity":
            _send(arm, j.device_id, PacketID.VELOCITY, encode_floats(side * j.max_velocity))
        else:
            _send(arm, j.device_id, PacketID.POSITION, encode_floats(wire_position(j, j.upper if side > 0 else j.lower)))
    assert arm.limit_violations == 0
    worst = np.full(len(BRAVO7), -np.inf)
    for t in np.arange(0.01, 2.0, 0.01):
        arm.step_to(t)
        worst = np.maximum(worst, side * (arm.positions() - limit))
    assert np.all(worst <= 1e-9), dict(zip([j.name for j in BRAVO7], worst))
    assert np.all(np.abs(arm.positions() - limit) < 1e-3 * np.where(START_INSIDE > 1, 10, 1))


def test_a_flood_of_requests_queues_at_most_the_limit():
    """2 000 broadcast requests of 10 ids each (140 000 answers, none read): the link queues
    QUEUE_LIMIT datagrams, drops and counts the oldest, and the client reads the newest."""
    run = SimRun()
    ids = [PacketID.POSITION, PacketID.VELOCITY, PacketID.MODE, PacketID.CURRENT, PacketID.HARDWARE_STATUS,
           PacketID.TEMPERATURE, PacketID.VOLTAGE, PacketID.SERIAL_NUMBER, PacketID.DEVICE_ID,
           PacketID.POSITION_LIMITS]
    request = encode_packet(BROADCAST, PacketID.REQUEST, bytes(ids))
    n = 2000
    for _ in range(n):
        run.transport.send(request)
    answers = n * 7 * len(ids)
    assert run.link.queued == QUEUE_LIMIT
    assert run.link.overflowed == answers - QUEUE_LIMIT
    reader, got = PacketReader(), []
    while datagram := run.transport.recv(0.0):
        got += reader.feed_datagram(datagram)
    assert len(got) == QUEUE_LIMIT and run.link.queued == 0
    assert got[-1].packet_id == ids[-1]  # the newest were kept
    assert run.link.overflowed == answers - QUEUE_LIMIT  # reading lost nothing more

