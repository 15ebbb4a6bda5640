"""Never outside the limits, to the last bit: the float32 on the wire is what is checked."""

from __future__ import annotations

import struct

import numpy as np
import pytest

from uvms_jax.hw import (LimitError, PacketID, PacketReader, encode_packet,
                         synchronised_move, wire_position)

from _hw_helpers import BRAVO7, DeviceID, Recorder, assert_within_limits, bravo7_client


LOWER = np.array([j.lower for j in BRAVO7])
UPPER = np.array([j.upper for j in BRAVO7])
VMAX = np.array([j.max_velocity for j in BRAVO7])
AMAX = np.array([j.max_acceleration for j in BRAVO7])
DEVICES = [j.device_id for j in BRAVO7]


def test_a_limit_float32_cannot_hold_is_sent_as_the_float32_inside():
    assert float(np.float32(6.3)) > 6.3  # the rounding the guard must not let through
    v = wire_position(BRAVO7[0], 6.3)
    assert v == float(np.nextafter(np.float32(6.3), np.float32(0))) and v <= 6.3
    assert wire_position(BRAVO7[1], 3.5) == 3.5  # representable: sent as it is
    with pytest.raises(LimitError):
        wire_position(BRAVO7[0], 6.3 + 1e-12)


def test_raw_float32_above_a_limit_is_refused():
    t = Recorder()
    above = struct.pack("<f", 6.3)  # float32 nearest 6.3 is 6.3000002
    with pytest.raises(LimitError, match="outside limits"):
        bravo7_client(t).send([(DeviceID.G, PacketID.POSITION, above)])
    assert t.sent == []


def _values(rng, n):
    """(n, 7) positions inside the limits, most of them at or within a few float32 steps of one."""
    kind = rng.integers(0, 5, (n, 7))
    u = rng.uniform(0, 1, (n, 7))
    tiny = rng.uniform(0, 1e-6, (n, 7))
    return np.select([kind == 0, kind == 1, kind == 2, kind == 3],
                     [LOWER + u * (UPPER - LOWER), UPPER - tiny, LOWER + tiny, UPPER], LOWER)


def _count_outside(n_plans: int, seed: int) -> tuple[int, int]:
    """Generated plans: an approach move from a measured start to the plan start, then a move to
    a goal; each streamed at sampled times through the client. Returns (demands, outside)."""
    rng = np.random.default_rng(seed)
    measured, start, goal = _values(rng, n_plans), _values(rng, n_plans), _values(rng, n_plans)
    t = Recorder()
    client = bravo7_client(t)
    for k in range(n_plans):
        for a, b in ((measured[k], start[k]), (start[k], goal[k])):
            move = synchronised_move(a, b, VMAX, AMAX)
            for tau in (0.0, rng.uniform(0, 1), 1.0):
                q, _ = move.sample(tau * move.duration)
                client.set_positions(zip(DEVICES, map(float, q)))
    reader = PacketReader()
    packets = [p for d in t.sent for p in reader.feed(d)]
    assert reader.stats.rejected == 0
    pos = np.array([struct.unpack("<f", p.data)[0] for p in packets])
    dev = np.array([p.device_id for p in packets])
    index = {d: i for i, d in enumerate(DEVICES)}
    j = np.array([index[d] for d in dev])
    outside = int(np.sum((pos < LOWER[j]) | (pos > UPPER[j])))  # exact float64 comparison
    assert all(p.packet_id == PacketID.POSITION for p in packets[:7])
    return len(packets), outside


def test_generated_plans_never_leave_the_limits():
    """5 000 plans by default (a few seconds); the slow test below runs 100 000."""
    n, outside = _count_outside(5_000, seed=0)
    assert n == 5_000 * 6 * 7 and outside == 0


@pytest.mark.slow
def test_generated_plans_never_leave_the_limits_1e5():
    n, outside = _count_outside(100_000, seed=1)
    assert n == 100_000 * 6 * 7 and outside == 0


def test_within_limits_helper_is_exact():
    """The test helper counts a float32 just above 6.3 as outside (it would have passed a float32 check)."""
    with pytest.raises(AssertionError):
        assert_within_limits([next(iter(PacketReader().feed(encode_packet(DeviceID.G, PacketID.POSITION,
                                                                           struct.pack("<f", 6.3)))))])
