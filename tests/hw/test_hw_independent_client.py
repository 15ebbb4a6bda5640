"""A second client, written here from the protocol description alone (docs/theory.md §6), reads
one packet per UDP datagram from ``uvms-hw sim`` running in its own process.

Nothing of ``uvms_jax.hw`` is used on the client side: CRC-8, COBS and the packet layout are
implemented below, and checked against the protocol's test vectors first.
"""

from __future__ import annotations

import math
import socket
import struct
import subprocess
import sys
import time

import pytest

# -- the protocol, from its description ------------------------------------------------------


def crc8(data: bytes) -> int:
    """Width 8, poly 0x4D, init 0, reflected in and out, final XOR 0xFF (bit by bit)."""
    poly = int(f"{0x4D:08b}"[::-1], 2)  # reflected polynomial
    r = 0
    for byte in data:
        r ^= byte
        for _ in range(8):
            r = (r >> 1) ^ poly if r & 1 else r >> 1
    return r ^ 0xFF


def cobs_encode(data: bytes) -> bytes:
    out, block = bytearray(), bytearray()
    for b in data:
        if b == 0:
            out += bytes([len(block) + 1]) + block
            block = bytearray()
        else:
            block.append(b)
            if len(block) == 254:
                out += bytes([255]) + block
                block = bytearray()
    return bytes(out + bytes([len(block) + 1]) + block)


def cobs_decode(data: bytes) -> bytes:
    out, i = bytearray(), 0
    while i < len(data):
        code = data[i]
        if code == 0 or i + code > len(data):
            raise ValueError("bad COBS")
        out += data[i + 1:i + code]
        i += code
        if code < 255 and i < len(data):
            out.append(0)
    return bytes(out)


def packet(device: int, pid: int, data: bytes = b"") -> bytes:
    body = data + bytes([pid, device, len(data) + 4])
    return cobs_encode(body + bytes([crc8(body)])) + b"\x00"


def parse_one(datagram: bytes) -> tuple[int, int, bytes]:
    """The single packet of a datagram, as a client that reads one packet per datagram does."""
    assert datagram.endswith(b"\x00") and datagram.count(b"\x00") == 1, datagram.hex(" ")
    raw = cobs_decode(datagram[:-1])
    assert raw[-2] == len(raw) and crc8(raw[:-1]) == raw[-1]
    return raw[-3], raw[-4], raw[:-4]


def test_independent_codec_matches_the_protocol_vectors():
    assert crc8(b"123456789") == 0x7B
    assert packet(0x01, 0x03, struct.pack("<f", 1.0)).hex(" ") == "01 01 07 80 3f 03 01 08 51 00"
    assert packet(0x02, 0x02, struct.pack("<f", -0.5)).hex(" ") == "01 01 01 06 bf 02 02 08 09 00"
    assert packet(0xFF, 0x60, bytes([0x03, 0x02])).hex(" ") == "07 03 02 60 ff 06 0b 00"
    assert packet(0x05, 0x01, bytes([0x02])).hex(" ") == "06 02 01 05 05 9c 00"
    assert parse_one(packet(0x07, 0x60, bytes([0x03]))) == (0x07, 0x60, b"\x03")


# -- against the simulator process -----------------------------------------------------------

# Request ids and data sizes of the listing; joints 0x01..0x07 answer these.
JOINT_SIZES = {0x01: 1, 0x02: 4, 0x03: 4, 0x05: 4, 0x10: 8, 0x11: 8, 0x12: 8, 0x61: 4, 0x62: 4, 0x64: 1,
               0x65: 4, 0x66: 4, 0x67: 4, 0x68: 4, 0x6C: 3, 0x90: 4, 0x91: 10, 0x92: 1}


@pytest.fixture(scope="module")
def sim():
    probe = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    probe.bind(("127.0.0.1", 0))
    port = probe.getsockname()[1]
    probe.close()
    proc = subprocess.Popen([sys.executable, "-m", "uvms_jax.hw.cli", "sim", "--port", str(port)],
                            stderr=subprocess.DEVNULL)
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sock.bind(("127.0.0.1", 0))
    addr = ("127.0.0.1", port)
    try:
        deadline = time.monotonic() + 60.0  # the process imports MuJoCo first
        sock.settimeout(0.2)
        while True:
            assert proc.poll() is None, "uvms-hw sim exited"
            sock.sendto(packet(0x07, 0x60, bytes([0x03])), addr)
            try:
                sock.recvfrom(4096)
                break
            except TimeoutError:
                assert time.monotonic() < deadline, "uvms-hw sim did not answer"
        yield sock, addr
    finally:
        sock.close()
        proc.terminate()
        proc.wait(10)


def ask(sim, device: int, ids: list[int], expect: int, wait: float = 1.0) -> list[tuple[int, int, bytes]]:
    """Send one REQUEST and collect ``expect`` datagrams (one packet each)."""
    sock, addr = sim
    sock.settimeout(0.01)
    while True:  # drop anything left over
        try:
            sock.recvfrom(4096)
        except TimeoutError:
            break
    sock.sendto(packet(device, 0x60, bytes(ids)), addr)
    got, deadline = [], time.monotonic() + wait
    sock.settimeout(0.05)
    while len(got) < expect and time.monotonic() < deadline:
        try:
            got.append(parse_one(sock.recvfrom(4096)[0]))
        except TimeoutError:
            pass
    return got


def test_every_joint_answers_the_listing_one_packet_per_datagram(sim):
    ids = list(JOINT_SIZES)
    for device in range(0x01, 0x08):
        got = ask(sim, device, ids[:10], 10) + ask(sim, device, ids[10:], len(ids) - 10)
        assert {(d, p) for d, p, _ in got} == {(device, p) for p in ids}
        assert {p: len(data) for _, p, data in got} == JOINT_SIZES
        answers = {p: data for _, p, data in got}
        assert answers[0x64] == bytes([device])
        hi, lo = struct.unpack("<2f", answers[0x10])  # max, then min
        assert hi > lo >= 0.0


def test_broadcast_request_is_seven_datagrams(sim):
    got = ask(sim, 0xFF, [0x03], 7)
    assert sorted(d for d, _, _ in got) == list(range(1, 8))
    assert len(ask(sim, 0xFF, [0x03, 0x02], 14)) == 14


def test_end_effector_pose_from_the_base_computer(sim):
    ((device, pid, data),) = ask(sim, 0x0E, [0xA1], 1)
    x, y, z, yaw, pitch, roll = struct.unpack("<6f", data)
    assert (device, pid) == (0x0E, 0xA1)
    assert 50 < math.dist((x, y, z), (0, 0, 0)) < 1000  # mm: within the 0.9 m reach
    assert all(-math.pi <= a <= math.pi for a in (yaw, pitch, roll))


def test_unknown_ids_get_no_answer(sim):
    assert ask(sim, 0x03, [0x63, 0xA1], 1, wait=0.3) == []


def test_jaws_move_in_millimetres(sim):
    sock, addr = sim
    sock.sendto(packet(0x01, 0x03, struct.pack("<f", 4.0)), addr)  # 4 mm at 20 mm/s
    deadline = time.monotonic() + 5.0
    pos = math.nan
    while time.monotonic() < deadline:
        (_, _, data), = ask(sim, 0x01, [0x03], 1)
        pos = struct.unpack("<f", data)[0]
        if abs(pos - 4.0) < 0.05:
            break
        time.sleep(0.05)
    assert abs(pos - 4.0) < 0.05
