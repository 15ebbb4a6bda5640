"""States that pass the 8-bit CRC but jump implausibly are corrupted frames, not the arm's state;
and the state can be streamed (heartbeat) instead of requested every tick."""

from __future__ import annotations

import itertools
import math
import random
import struct

import numpy as np

from uvms_jax.hw import (ExecutorSettings, PacketID, PacketReader, SimSettings, crc8, decode_float,
                         encode_packet)

from _hw_helpers import BRAVO7, SimRun, assert_within_limits, short_plan

GATE = ExecutorSettings().gate_threshold_rad


def test_the_crc_lets_about_one_in_300_three_bit_errors_through():
    """Why the plausibility check exists. Every 3-bit error of an 8-byte POSITION packet, tried
    exhaustively: an 8-bit CRC whose polynomial has an odd number of terms does not catch all
    of them, and of those beyond its reach about 1/256 pass — here 1 in ~300, a few frames a
    minute on a 100 Hz, 14-packet state stream with a noisy link."""
    body = struct.pack("<f", 1.0) + bytes([PacketID.POSITION, 0x05, 8])
    packet = body + bytes([crc8(body)])
    nbits = 8 * len(packet)
    undetected = total = 0
    for bits in itertools.combinations(range(nbits), 3):
        b = bytearray(packet)
        for bit in bits:
            b[bit // 8] ^= 1 << (bit % 8)
        undetected += crc8(bytes(b[:-1])) == b[-1]
        total += 1
    assert total == math.comb(nbits, 3)
    assert total / 512 < undetected < total / 128


class Corrupting:
    """Wraps a transport: some POSITION answers are replaced by a valid packet (right CRC) whose
    value jumped by ``jump`` — a corrupted frame that the CRC let through."""

    def __init__(self, inner, rate: float, jump: float, seed: int = 0):
        self.inner, self.rate, self.jump = inner, rate, jump
        self.rng = random.Random(seed)
        self.injected = 0
        self.datagrams = True
        self.name = "corrupting"

    def send(self, data):
        self.inner.send(data)

    def recv(self, timeout):
        data = self.inner.recv(timeout)
        pkts = PacketReader().feed_datagram(data) if data else []
        if len(pkts) == 1 and pkts[0].packet_id == PacketID.POSITION and self.rng.random() < self.rate:
            p = pkts[0]
            self.injected += 1
            return encode_packet(p.device_id, p.packet_id, struct.pack("<f", decode_float(p.data) + self.jump))
        return data

    def close(self):
        self.inner.close()


def _corrupted_run(rate, jump, seed=0, hw=ExecutorSettings()):
    run = SimRun(hw=hw)
    run.client.transport = Corrupting(run.transport, rate, jump, seed)
    res = run.executor.run(short_plan())
    return run, res


def test_implausible_states_are_skipped_and_the_run_completes():
    run, res = _corrupted_run(rate=0.01, jump=0.8)
    assert run.client.transport.injected > 5
    assert res.ok, res.reason
    assert res.rejected_states > 0
    assert res.max_gate_error_rad <= GATE
    # no logged measurement shows the jump: each is near what was commanded
    n = len(BRAVO7)
    rows = np.array([r[4:] for r in run.executor.log.rows], dtype=float)
    cmd, meas = rows[:, :n], rows[:, n:]
    ok = np.isfinite(meas[:, 0])
    assert np.max(np.abs(meas[ok, :6] - cmd[ok, :6])) < 0.3
    assert_within_limits(run.sent_packets())


def test_a_jump_into_the_limits_margin_does_not_abort():
    """A corrupted reading 3 rad off would otherwise read as a limit breach or a lag, and abort."""
    run, res = _corrupted_run(rate=0.02, jump=-3.0, seed=3)
    assert res.ok, res.reason
    assert res.rejected_states > 0


def test_persistent_corruption_stops_into_hold():
    run, res = _corrupted_run(rate=0.6, jump=0.8, seed=1)
    assert not res.ok and ("lost link" in res.reason or "start states" in res.reason), res.reason
    tail = [p for d in run.transport.sent[-3:] for p in PacketReader().feed(d)]
    assert all(p.packet_id == PacketID.VELOCITY and decode_float(p.data) == 0.0 for p in tail)


def test_streamed_state_run_sends_no_request_per_tick():
    run = SimRun(hw=ExecutorSettings(stream_hz=50))
    res = run.executor.run(short_plan())
    assert res.ok, res.reason
    assert res.max_gate_error_rad <= GATE
    requests = [p for d in run.transport.sent for p in PacketReader().feed(d) if p.packet_id == PacketID.REQUEST]
    polled = SimRun()
    polled_res = polled.executor.run(short_plan())
    polled_requests = [p for d in polled.transport.sent for p in PacketReader().feed(d)
                       if p.packet_id == PacketID.REQUEST]
    # only the hardware-status requests (every status_period_s) and the connect remain
    assert len(requests) < 0.3 * len(polled_requests) and polled_res.ticks > 100
    assert run.arm.heartbeat_hz[0x07] == 0  # streaming stopped at the end


def test_streamed_state_with_drops_completes_or_holds():
    run = SimRun(SimSettings(drop=0.1, seed=4), ExecutorSettings(stream_hz=50))
    res = run.executor.run(short_plan())
    assert run.arm.limit_violations == 0
    assert res.ok or "lost link" in res.reason, res.reason
