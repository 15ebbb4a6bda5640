"""The simulated Bravo 7 answers every request of the protocol listing, one packet per datagram."""

from __future__ import annotations

import struct

import numpy as np
import pytest

from uvms_jax.hw import (ANSWER_FORMATS, BASE_COMPUTER, BROADCAST, HardwareStatus, PacketID,
                         PacketReader, SimArm, SimSettings, SimLink, decode_answer, encode_packet)

from _hw_helpers import BRAVO, DeviceID, Q0, SimRun, urdf_link_frames, ypr_matrix

# Data sizes of the answers, from the protocol listing (docs/hardware.md), in bytes.
LISTED_SIZE = {
    PacketID.MODE: 1, PacketID.VELOCITY: 4, PacketID.POSITION: 4, PacketID.CURRENT: 4,
    PacketID.POSITION_LIMITS: 8, PacketID.VELOCITY_LIMITS: 8, PacketID.CURRENT_LIMITS: 8,
    PacketID.SERIAL_NUMBER: 4, PacketID.MODEL_NUMBER: 4, PacketID.DEVICE_ID: 1, PacketID.HUMIDITY: 4,
    PacketID.TEMPERATURE: 4, PacketID.PRESSURE: 4, PacketID.HARDWARE_STATUS: 4, PacketID.SOFTWARE_VERSION: 3,
    PacketID.VOLTAGE: 4, PacketID.HEARTBEAT_SET: 10, PacketID.HEARTBEAT_FREQUENCY: 1,
    PacketID.KM_END_POS: 24, PacketID.KM_END_VEL: 24,
}
JOINT_IDS = [p for p in LISTED_SIZE if p not in (PacketID.KM_END_POS, PacketID.KM_END_VEL)]
BASE_IDS = [PacketID.KM_END_POS, PacketID.KM_END_VEL, PacketID.SERIAL_NUMBER, PacketID.SOFTWARE_VERSION,
            PacketID.TEMPERATURE, PacketID.VOLTAGE, PacketID.HARDWARE_STATUS, PacketID.DEVICE_ID]


def test_answer_formats_are_the_listing():
    assert {p: f.size for p, f in ANSWER_FORMATS.items()} == LISTED_SIZE


@pytest.mark.parametrize("device", list(DeviceID)[:-1])
def test_every_joint_answers_every_listed_id_with_its_size(device):
    c = SimRun().client
    # a REQUEST lists at most 10 ids: ask in two halves
    got = {}
    for half in (JOINT_IDS[:10], JOINT_IDS[10:]):
        got.update(c.request(half, [device]))
    assert {p: len(got[(device, p)]) for p in JOINT_IDS} == {p: LISTED_SIZE[p] for p in JOINT_IDS}
    assert got[(device, PacketID.DEVICE_ID)] == bytes([device])
    assert got[(device, PacketID.HARDWARE_STATUS)] == bytes(4)
    assert len(got[(device, PacketID.SOFTWARE_VERSION)]) == 3


def test_base_computer_answers_the_end_effector_and_its_identity():
    c = SimRun().client
    got = c.request(BASE_IDS, [BASE_COMPUTER])
    assert {p: len(got[(BASE_COMPUTER, p)]) for p in BASE_IDS} == {p: LISTED_SIZE[p] for p in BASE_IDS}


def test_units_of_the_answers():
    run = SimRun(jaws=12.0)
    c = run.client
    v = c.read([PacketID.POSITION, PacketID.POSITION_LIMITS, PacketID.VELOCITY_LIMITS, PacketID.MODE,
                PacketID.TEMPERATURE, PacketID.HUMIDITY, PacketID.PRESSURE, PacketID.VOLTAGE,
                PacketID.CURRENT_LIMITS],
               [DeviceID.F, DeviceID.A])
    assert v[(DeviceID.F, PacketID.POSITION)][0] == pytest.approx(Q0[1], abs=1e-6)  # rad
    assert v[(DeviceID.A, PacketID.POSITION)][0] == pytest.approx(12.0, abs=1e-4)  # mm
    assert v[(DeviceID.F, PacketID.POSITION_LIMITS)] == pytest.approx((3.5, 0.0))  # max, min [rad]
    assert v[(DeviceID.A, PacketID.POSITION_LIMITS)] == pytest.approx((35.0, 0.0))  # [mm]
    assert v[(DeviceID.F, PacketID.VELOCITY_LIMITS)] == pytest.approx((0.5, -0.5))  # [rad/s]
    assert v[(DeviceID.F, PacketID.MODE)] == (2,)  # position mode
    cur_max, cur_min = v[(DeviceID.F, PacketID.CURRENT_LIMITS)]
    assert cur_max > 100 and cur_min == -cur_max  # mA, not A
    assert 0 < v[(DeviceID.F, PacketID.TEMPERATURE)][0] < 60  # °C
    assert 0 <= v[(DeviceID.F, PacketID.HUMIDITY)][0] <= 100  # %
    assert 0.5 < v[(DeviceID.F, PacketID.PRESSURE)][0] < 2  # bar
    assert 10 < v[(DeviceID.F, PacketID.VOLTAGE)][0] < 50  # V


def _datagrams_for(request: bytes, config: SimSettings = SimSettings()) -> list[bytes]:
    link = SimLink(SimArm(BRAVO, config, Q0 + [0.0]))
    link.receive(request, 0.0)
    return link.pop_due(0.0)


def test_broadcast_request_gives_one_datagram_per_packet():
    d = _datagrams_for(encode_packet(BROADCAST, PacketID.REQUEST, bytes([PacketID.POSITION])))
    assert len(d) == 7
    per = [PacketReader().feed(x) for x in d]
    assert all(len(p) == 1 for p in per)
    assert sorted(p[0].device_id for p in per) == list(range(1, 8))
    d2 = _datagrams_for(encode_packet(BROADCAST, PacketID.REQUEST, bytes([PacketID.POSITION, PacketID.VELOCITY])))
    assert len(d2) == 14


def test_coalesced_replies_are_one_datagram_and_the_client_reads_them_all():
    request = encode_packet(BROADCAST, PacketID.REQUEST, bytes([PacketID.POSITION]))
    d = _datagrams_for(request, SimSettings(coalesce=True))
    assert len(d) == 1 and len(PacketReader().feed(d[0])) == 7
    run = SimRun(SimSettings(coalesce=True))
    assert run.client.read_state().positions == pytest.approx(Q0 + [0.0], abs=1e-5)


def test_unknown_ids_are_ignored_and_counted():
    arm = SimArm(BRAVO, SimSettings(), Q0 + [0.0])
    link = SimLink(arm)
    link.receive(encode_packet(BROADCAST, PacketID.REQUEST, bytes([0x63, PacketID.KM_END_POS])), 0.0)
    assert link.pop_due(0.0) == [] and arm.unanswered == 14  # joints do not answer the pose
    link.receive(encode_packet(DeviceID.D, PacketID.OPENLOOP, struct.pack("<f", 0.3)), 0.0)
    link.receive(encode_packet(DeviceID.D, 0x77, b"\x01"), 0.0)
    link.receive(encode_packet(0x42, PacketID.REQUEST, bytes([PacketID.POSITION])), 0.0)  # no such device
    assert arm.ignored == 2 and link.pop_due(0.0) == []
    assert arm.mode[3] == 2 and arm.target[3] == pytest.approx(Q0[3])  # open-loop drive did nothing


def test_end_pose_is_the_urdf_forward_kinematics(rng):
    for _ in range(5):
        q = rng.uniform([0.2, 0.3, 0.3, 0.2, 0.3, 0.2], [6.0, 3.2, 3.2, 6.0, 3.2, 6.0])
        run = SimRun(q0=list(q))
        x, y, z, yaw, pitch, roll = run.client.read([PacketID.KM_END_POS], [BASE_COMPUTER])[(BASE_COMPUTER, PacketID.KM_END_POS)]
        T = urdf_link_frames(q)[-1]
        np.testing.assert_allclose([x, y, z], T[:3, 3] * 1e3, atol=1e-3)  # mm (float32 on the wire)
        np.testing.assert_allclose(ypr_matrix(yaw, pitch, roll), T[:3, :3], atol=1e-5)


def test_end_velocity_is_the_derivative_of_the_pose(rng):
    q = np.array([1.0, 1.4, 1.7, 2.0, 1.2, 0.7])
    qd = rng.uniform(-0.4, 0.4, 6)
    arm = SimArm(BRAVO, SimSettings(), list(q) + [0.0])
    arm.data.qvel[arm._dadr[:6]] = qd
    got = np.array(decode_answer(PacketID.KM_END_VEL, arm.answer(BASE_COMPUTER, PacketID.KM_END_VEL)))

    def pose(qq):
        T = urdf_link_frames(qq)[-1]
        R = T[:3, :3]
        return np.r_[T[:3, 3] * 1e3, np.arctan2(R[1, 0], R[0, 0]), np.arcsin(-R[2, 0]), np.arctan2(R[2, 1], R[2, 2])]

    h = 1e-6
    fd = (pose(q + h * qd) - pose(q - h * qd)) / (2 * h)
    np.testing.assert_allclose(got[:3], fd[:3], atol=1e-2)  # mm/s
    np.testing.assert_allclose(got[3:], fd[3:], atol=1e-4)  # rad/s


def test_four_status_bytes_reach_the_client():
    bits = HardwareStatus.MOTOR_OVER_CURRENT | HardwareStatus.OVER_TEMPERATURE
    run = SimRun(SimSettings(fault_joint="E", fault_bits=int(bits)))
    raw = run.client.request([PacketID.HARDWARE_STATUS], [DeviceID.E])[(DeviceID.E, PacketID.HARDWARE_STATUS)]
    assert raw == bytes([0x20, 0x20, 0x00, 0x00])  # byte A 0x20 over temperature, byte B 0x20 motor over current
    assert run.client.read_hardware_status()[DeviceID.E] == bits


def test_heartbeat_settings_read_back():
    run = SimRun()
    c = run.client
    c.set_heartbeat([PacketID.POSITION, PacketID.VELOCITY], 10, DeviceID.C)
    got = c.read([PacketID.HEARTBEAT_SET, PacketID.HEARTBEAT_FREQUENCY], [DeviceID.C])
    assert got[(DeviceID.C, PacketID.HEARTBEAT_SET)] == (3, 2) + (0,) * 8
    assert got[(DeviceID.C, PacketID.HEARTBEAT_FREQUENCY)] == (10,)


def test_malformed_answers_are_refused():
    with pytest.raises(ValueError, match="expected 4"):
        decode_answer(PacketID.POSITION, b"\x00\x00")
    with pytest.raises(ValueError, match="no known answer"):
        decode_answer(0x63, b"")


def test_datagrams_are_decoded_on_their_own():
    a = encode_packet(DeviceID.G, PacketID.POSITION, struct.pack("<f", 1.0))
    b = encode_packet(DeviceID.F, PacketID.POSITION, struct.pack("<f", 2.0))
    r = PacketReader()
    assert len(r.feed_datagram(a + b)) == 2
    assert r.feed_datagram(a[:5]) == [] and r.stats.unterminated == 1  # truncated datagram
    assert [p.device_id for p in r.feed_datagram(b)] == [DeviceID.F]  # not glued to the tail
