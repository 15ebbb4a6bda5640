"""Protocol codec: docs/theory.md §6 test vectors, an independent SDK-style encoder, fuzzing."""

from __future__ import annotations

import struct
import time

import crcmod
import numpy as np
import pytest
from hypothesis import given, settings
from crc import Calculator
from hypothesis import strategies as st

from _hw_helpers import DeviceID
from uvms_jax.hw import (CRC8_CONFIG, Mode, Packet, PacketID, PacketReader, crc8, decode_float, decode_floats,
                         decode_frame, encode_floats, encode_packet)

_CRC8 = Calculator(CRC8_CONFIG, optimized=True)  # the crc library itself, as the codec configures it

# docs/theory.md §6 test vectors: (device, packet id, data) ↔ bytes on the wire.
VECTORS = [
    ((DeviceID.A, PacketID.POSITION, struct.pack("<f", 1.0)), "01 01 07 80 3f 03 01 08 51 00"),
    ((DeviceID.B, PacketID.VELOCITY, struct.pack("<f", -0.5)), "01 01 01 06 bf 02 02 08 09 00"),
    ((DeviceID.G, PacketID.REQUEST, bytes([PacketID.POSITION])), "06 03 60 07 05 18 00"),
    ((DeviceID.BROADCAST, PacketID.REQUEST, bytes([PacketID.POSITION, PacketID.VELOCITY])),
     "07 03 02 60 ff 06 0b 00"),
    ((DeviceID.E, PacketID.MODE, bytes([Mode.POSITION])), "06 02 01 05 05 9c 00"),
]


# ---- independent reference: the SDK's algorithm written from docs/theory.md §6, not from the codec ----
def ref_crc8(data: bytes) -> int:
    """crcmod.mkCrcFun(0x14D, initCrc=0xFF, xorOut=0xFF) (reflected), bit by bit.

    crcmod's initCrc already includes the final XOR, so the register starts at 0xFF ^ 0xFF.
    """
    poly_reflected = int(f"{0x4D:08b}"[::-1], 2)  # 0x4D bit-reversed = 0xB2
    reg = 0xFF ^ 0xFF
    for byte in data:
        reg ^= byte
        for _ in range(8):
            reg = (reg >> 1) ^ poly_reflected if reg & 1 else reg >> 1
    return reg ^ 0xFF


def ref_cobs_encode(data: bytes) -> bytes:
    """Consistent Overhead Byte Stuffing, textbook form (no trailing delimiter)."""
    out, block = bytearray(), bytearray()
    for b in data:
        if b == 0:
            out += bytes([len(block) + 1]) + block
            block.clear()
        else:
            block.append(b)
            if len(block) == 254:
                out += bytes([255]) + block
                block.clear()
    out += bytes([len(block) + 1]) + block
    return bytes(out)


def ref_encode(device_id: int, packet_id: int, data: bytes) -> bytes:
    body = data + bytes([packet_id, device_id, len(data) + 4])
    return ref_cobs_encode(body + bytes([ref_crc8(body)])) + b"\x00"


def test_check_value():
    assert crc8(b"123456789") == 0x7B
    assert ref_crc8(b"123456789") == 0x7B
    assert _CRC8.checksum(b"123456789") == 0x7B  # the crc library itself, as configured


@pytest.mark.parametrize(("packet", "wire"), VECTORS)
def test_vectors_encode(packet, wire):
    assert encode_packet(*packet).hex(" ") == wire


@pytest.mark.parametrize(("packet", "wire"), VECTORS)
def test_vectors_decode(packet, wire):
    r = PacketReader()
    assert r.feed(bytes.fromhex(wire)) == [Packet(*packet)]
    assert decode_frame(bytes.fromhex(wire)[:-1]) == Packet(*packet)


def test_vectors_reference_encoder_agrees():
    for packet, wire in VECTORS:
        assert ref_encode(*packet).hex(" ") == wire


def test_table_crc_matches_library(rng):
    for n in range(0, 300, 7):
        data = rng.integers(0, 256, n, dtype=np.uint8).tobytes()
        assert crc8(data) == _CRC8.checksum(data) == ref_crc8(data)


def test_crc_matches_sdk_library():
    """The Reach SDK computes its CRC with crcmod; ours must agree."""
    sdk = crcmod.mkCrcFun(0x14D, initCrc=0xFF, xorOut=0xFF)
    for data in (b"", b"123456789", bytes(range(200))):
        assert sdk(data) == crc8(data)


@settings(max_examples=300, deadline=None)
@given(device=st.integers(0, 255), pid=st.integers(0, 255), data=st.binary(max_size=251))
def test_sdk_bytes_decode_to_same_packet(device, pid, data):
    wire = ref_encode(device, pid, data)
    assert encode_packet(device, pid, data) == wire
    assert PacketReader().feed(wire) == [Packet(device, pid, data)]


@settings(max_examples=100, deadline=None)
@given(packets=st.lists(st.tuples(st.integers(0, 255), st.integers(0, 255), st.binary(max_size=40)), max_size=8),
       cuts=st.lists(st.integers(0, 400), max_size=6))
def test_stream_split_anywhere(packets, cuts):
    stream = b"".join(ref_encode(*p) for p in packets)
    r = PacketReader()
    got = []
    last = 0
    for c in sorted(set(min(c, len(stream)) for c in cuts)) + [len(stream)]:
        got += r.feed(stream[last:c])
        last = c
    assert got == [Packet(*p) for p in packets]
    assert r.stats.rejected == 0


def test_garbage_and_errors_counted_not_raised():
    good = encode_packet(3, PacketID.POSITION, encode_floats(0.25))
    bad_crc = bytearray(good)
    bad_crc[3] ^= 0x01
    no_len = ref_cobs_encode(b"\x01\x02\x03\x09\x55") + b"\x00"  # length byte says 9, packet is 5
    bad_cobs = b"\x09\x01\x00"  # code byte promises 8 bytes that are not there
    r = PacketReader()
    out = r.feed(b"\xff\xfe" + b"\x00" + bytes(bad_crc) + no_len + bad_cobs + good + b"\x00\x00")
    assert out == [Packet(3, PacketID.POSITION, encode_floats(0.25))]
    assert r.stats.crc_errors == 1 and r.stats.length_errors == 1 and r.stats.cobs_errors >= 1
    r.feed(b"\x01" * 5000)  # no delimiter at all: dropped as overflow, not buffered forever
    assert r.stats.overflows == 1
    assert r.feed(good) == [Packet(3, PacketID.POSITION, encode_floats(0.25))]


def test_fuzz_1e5_random_strings_never_raise():
    rng = np.random.default_rng(1234)
    blob = rng.integers(0, 256, 100_000 * 16, dtype=np.uint8)
    blob[rng.random(blob.size) < 0.08] = 0  # plenty of delimiters so frames get decoded
    lengths = rng.integers(0, 33, 100_000)
    offsets = np.concatenate([[0], np.cumsum(lengths)])
    data = blob.tobytes()
    r = PacketReader()
    t = time.perf_counter()
    n = 0
    for i in range(100_000):
        n += len(r.feed(data[offsets[i]:offsets[i + 1]]))
        if i % 1000 == 0:
            PacketReader().feed(data[offsets[i]:offsets[i + 1]])  # fresh reader too
    assert r.stats.packets == n
    assert r.stats.rejected > 0
    assert time.perf_counter() - t < 30


def test_encode_errors():
    with pytest.raises(ValueError, match="device_id"):
        encode_packet(256, 1, b"")
    with pytest.raises(ValueError, match="packet_id"):
        encode_packet(1, -1, b"")
    with pytest.raises(ValueError, match="exceeds"):
        encode_packet(1, 1, bytes(252))
    assert PacketReader().feed(encode_packet(1, 1, bytes(251)))[0].data == bytes(251)


def test_float_helpers():
    assert decode_floats(encode_floats(1.0, -2.5)) == (1.0, -2.5)
    assert decode_float(encode_floats(0.5)) == 0.5
    with pytest.raises(ValueError, match="non-finite"):
        encode_floats(float("nan"))
    with pytest.raises(ValueError, match="whole number"):
        decode_floats(b"\x00\x00\x00")
    with pytest.raises(ValueError, match="one float32"):
        decode_float(b"\x00" * 8)
