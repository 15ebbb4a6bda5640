"""Client send guard, requests, heartbeat; UDP and serial transports."""

from __future__ import annotations

import time

import pytest

from uvms_jax.hw import (BROADCAST, HardwareStatus, LimitError, LinkError, Mode, PacketID,
                         PacketReader, SerialTransport, SimArm, SimSettings, SimServer, UdpTransport, encode_floats,
                         parse_host_port)

from _hw_helpers import BRAVO, DeviceID, Q0, Recorder, SimRun, bravo7_client


class Broken(Recorder):
    def send(self, data):
        raise LinkError("cable cut")


@pytest.mark.parametrize(("device", "value"), [(DeviceID.G, -0.001), (DeviceID.G, 6.31), (DeviceID.F, 3.6),
                                               (DeviceID.A, 35.5), (DeviceID.A, -1.0), (DeviceID.B, float("nan"))])
def test_guard_refuses_positions_outside_limits(device, value):
    t = Recorder()
    c = bravo7_client(t)
    with pytest.raises((LimitError, ValueError)):
        c.set_positions([(DeviceID.E, 1.0), (device, value)])
    assert t.sent == []  # nothing of the batch went out


def test_guard_accepts_limit_edges_as_float32():
    t = Recorder()
    c = bravo7_client(t)
    c.set_positions([(DeviceID.G, 0.0), (DeviceID.G, 6.3), (DeviceID.A, 35.0), (DeviceID.F, 3.5)])
    assert len(t.sent) == 1


def test_guard_velocity_broadcast_and_packet_ids():
    c = bravo7_client(Recorder())
    with pytest.raises(LimitError, match="exceeds"):
        c.set_velocities([(DeviceID.D, 0.51)])
    with pytest.raises(LimitError, match="broadcast"):
        c.set_positions([(BROADCAST, 1.0)])
    with pytest.raises(ValueError, match="not allowed"):
        c.send([(DeviceID.D, PacketID.RELATIVE_POSITION, encode_floats(0.1))])
    with pytest.raises(ValueError, match="not allowed"):
        c.send([(DeviceID.D, PacketID.POSITION_LIMITS, encode_floats(-9, 9))])
    with pytest.raises(ValueError, match="mode"):
        c.send([(DeviceID.D, PacketID.MODE, bytes([Mode.OPENLOOP]))])
    with pytest.raises(LimitError, match="no joint limits"):
        c.set_positions([(0x08, 1.0)])


def test_hold_never_raises():
    assert bravo7_client(Broken()).hold() is False
    t = Recorder()
    assert bravo7_client(t).hold(repeats=2) is True
    pkts = [p for d in t.sent for p in PacketReader().feed(d)]
    assert len(pkts) == 14 and all(p.packet_id == PacketID.VELOCITY and p.data == encode_floats(0.0) for p in pkts)


def test_request_timeout_names_missing():
    c = bravo7_client(Recorder(), request_timeout=0.001)
    with pytest.raises(LinkError, match="POSITION@0x07"):
        c.read_state([DeviceID.G])


def test_reads_over_loopback():
    run = SimRun(SimSettings(fault_joint="C", fault_bits=HardwareStatus.OVER_TEMPERATURE))
    c = run.client
    s = c.read_state()
    assert s.positions == pytest.approx(Q0 + [0.0], abs=1e-5)
    status = c.read_hardware_status()
    assert status[DeviceID.C] == HardwareStatus.OVER_TEMPERATURE and status[DeviceID.G] == HardwareStatus.OK
    assert c.read_position_limits()[DeviceID.F] == pytest.approx((0.0, 3.5))
    c.set_velocities([(DeviceID.G, 0.4)])
    run.clock.sleep(1.0)
    assert c.read_state([DeviceID.G]).positions[0] == pytest.approx(Q0[0] + 0.4, abs=0.02)
    c.set_mode(Mode.ZERO_VELOCITY)
    run.clock.sleep(0.5)
    assert abs(c.read_state([DeviceID.G]).velocities[0]) < 1e-3


def test_heartbeat_streams_without_requests():
    run = SimRun()
    c = run.client
    c.set_heartbeat([PacketID.POSITION], 20)
    sent = len(run.transport.sent)
    n = 0
    while run.clock.now() < 1.0:  # ~1 s of simulated time
        n += c.poll(0.05)
    assert 7 * 19 <= n <= 7 * 21  # 20 Hz × 7 devices, one packet per datagram
    assert len(run.transport.sent) == sent  # nothing was asked for
    assert (DeviceID.E, PacketID.POSITION) in c.latest
    c.set_heartbeat([PacketID.POSITION], 0)
    while c.poll(0.0):  # what was already under way
        pass
    run.clock.sleep(0.5)
    assert sum(c.poll(0.05) for _ in range(5)) == 0


def test_stream_state_replaces_polling():
    """A 50 Hz state stream: one fresh state per tick, and no request sent per tick."""
    run = SimRun()
    c = run.client
    c.start_stream(50)
    sent = len(run.transport.sent)
    since, states = -1.0, []
    for _ in range(25):
        run.clock.sleep(0.02)
        s = c.stream_state(since=since, timeout=0.05)
        assert s.t > since
        since = s.t
        states.append(s)
    assert len(run.transport.sent) == sent
    assert states[-1].positions == pytest.approx(Q0 + [0.0], abs=1e-5)
    assert c.stop_stream()
    while c.poll(0.0):
        pass
    run.clock.sleep(0.1)
    with pytest.raises(LinkError, match="stream: nothing new"):
        c.stream_state(since=run.clock.now(), timeout=0.1)


def test_udp_round_trip_with_server():
    with SimServer(SimArm(BRAVO, SimSettings(), Q0 + [5.0])) as server:
        with bravo7_client(UdpTransport(*server.address), request_timeout=0.2) as c:
            s = c.read_state()
            assert s.positions[-1] == pytest.approx(5.0, abs=1e-4)
            c.set_positions([(DeviceID.A, 8.0)])
            deadline = time.monotonic() + 3.0  # 3 mm at 20 mm/s plus the servo tail: < 1 s
            while time.monotonic() < deadline and abs(c.read_state([DeviceID.A]).positions[0] - 8.0) >= 0.05:
                time.sleep(0.02)
            assert abs(c.read_state([DeviceID.A]).positions[0] - 8.0) < 0.05
    assert server.error is None


def test_udp_silence_is_a_timeout_not_a_crash():
    with UdpTransport("127.0.0.1", 9) as t:  # discard port: nobody answers
        t.send(b"\x01\x00")
        assert t.recv(0.01) == b""


def test_serial_loopback_url():
    with SerialTransport("loop://") as t:
        t.send(b"abc\x00")
        assert t.recv(0.2) == b"abc\x00"
        assert t.recv(0.01) == b""
    with pytest.raises(LinkError, match="cannot open"):
        SerialTransport("/dev/does-not-exist-bravo7")


def test_parse_host_port():
    assert parse_host_port("192.168.2.3:6789") == ("192.168.2.3", 6789)
    for bad in ("nohost", ":80", "h:0", "h:x"):
        with pytest.raises(ValueError, match="HOST:PORT"):
            parse_host_port(bad)
