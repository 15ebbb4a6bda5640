"""BPL packet codec: CRC-8, COBS framing, a streaming reader and float helpers (docs/theory.md §6).

A packet on the wire is ``COBS(data ‖ packet_id ‖ device_id ‖ length ‖ crc8) ‖ 0x00`` with
``length = len(data) + 4`` and ``crc8`` computed over everything before it. Floats are
little-endian float32.

The CRC is the catalogue CRC-8 with width 8, poly 0x4D, init 0x00, reflected input and
output, final XOR 0xFF (check value 0x7B), configured with the ``crc`` library. The library's
own byte loop costs ~50 µs per packet, so the 256-entry table is taken from the library once
at import and the per-packet loop is a table lookup (~0.5 µs); a test checks both agree.
"""

from __future__ import annotations

import dataclasses
import struct
from typing import NamedTuple

from cobs import cobs
from crc import Calculator, Configuration

__all__ = [
    "CRC8_CONFIG",
    "MAX_PACKET_LEN",
    "Packet",
    "PacketReader",
    "ReaderStats",
    "crc8",
    "decode_float",
    "decode_floats",
    "decode_frame",
    "encode_floats",
    "encode_packet",
]

CRC8_CONFIG = Configuration(
    width=8,
    polynomial=0x4D,
    init_value=0x00,
    final_xor_value=0xFF,
    reverse_input=True,
    reverse_output=True,
)
_CRC8 = Calculator(CRC8_CONFIG, optimized=True)
# Reflected width-8 CRC: one table step is r = T[r ^ byte]; T[i] is the register after
# feeding byte i from 0, i.e. the library's checksum of that byte with the final XOR undone.
_CRC8_TABLE = bytes(_CRC8.checksum(bytes([i])) ^ CRC8_CONFIG.final_xor_value for i in range(256))

MAX_PACKET_LEN = 255  # the length field is one byte: data ‖ pid ‖ did ‖ len ‖ crc ≤ 255
_MAX_FRAME = MAX_PACKET_LEN + 2  # COBS adds at most one byte per 254, plus the lead code


def crc8(payload: bytes) -> int:
    """CRC-8 of ``payload`` as used by BPL (docs/theory.md §6); ``crc8(b"123456789") == 0x7B``."""
    r = 0
    table = _CRC8_TABLE
    for b in payload:
        r = table[r ^ b]
    return r ^ 0xFF


class Packet(NamedTuple):
    """One decoded packet: ``device_id`` and ``packet_id`` are ints (compare with the enums)."""

    device_id: int
    packet_id: int
    data: bytes


def encode_packet(device_id: int, packet_id: int, data: bytes = b"") -> bytes:
    """Encode one packet for the wire (COBS frame including its terminating ``0x00``).

    Args:
      device_id: destination/source device, 0..255 (0xFF = broadcast).
      packet_id: BPL packet id, 0..255.
      data: payload bytes (at most 251).

    Raises:
      ValueError: an id outside 0..255 or a payload too long for the one-byte length field.
    """
    if not 0 <= int(device_id) <= 0xFF:
        raise ValueError(f"device_id {device_id!r} outside 0..255")
    if not 0 <= int(packet_id) <= 0xFF:
        raise ValueError(f"packet_id {packet_id!r} outside 0..255")
    data = bytes(data)
    length = len(data) + 4
    if length > MAX_PACKET_LEN:
        raise ValueError(f"payload of {len(data)} bytes exceeds {MAX_PACKET_LEN - 4}")
    body = data + bytes((int(packet_id), int(device_id), length))
    return cobs.encode(body + bytes((crc8(body),))) + b"\x00"


@dataclasses.dataclass
class ReaderStats:
    """Counts of what a :class:`PacketReader` has seen (mutable: the reader is I/O state)."""

    packets: int = 0
    cobs_errors: int = 0
    length_errors: int = 0
    crc_errors: int = 0
    overflows: int = 0
    unterminated: int = 0

    @property
    def rejected(self) -> int:
        """All frames skipped for any reason."""
        return self.cobs_errors + self.length_errors + self.crc_errors + self.overflows + self.unterminated


def decode_frame(frame: bytes) -> Packet:
    """Decode one COBS frame (without the trailing ``0x00``).

    Raises:
      ValueError: bad COBS, bad length field or CRC mismatch (message says which).
    """
    try:
        raw = cobs.decode(frame)
    except cobs.DecodeError as e:
        raise ValueError(f"bad COBS frame: {e}") from None
    if len(raw) < 4 or raw[-2] != len(raw):
        raise ValueError(f"bad length field in {len(raw)}-byte packet")
    if crc8(raw[:-1]) != raw[-1]:
        raise ValueError("CRC mismatch")
    return Packet(raw[-3], raw[-4], raw[:-4])


class PacketReader:
    """Streaming decoder: ``feed(chunk)`` returns complete packets, keeps the partial tail.

    Garbage, COBS errors, bad lengths and CRC errors are counted in :attr:`stats` and skipped;
    ``feed`` never raises on any input bytes.
    """

    def __init__(self) -> None:
        self._buf = b""
        self.stats = ReaderStats()

    def feed(self, chunk: bytes) -> list[Packet]:
        """Consume ``chunk`` and return the packets it completes, in order."""
        frames = (self._buf + bytes(chunk)).split(b"\x00")
        tail = frames.pop()
        if len(tail) > _MAX_FRAME:  # no terminator in sight: cannot be a packet
            self.stats.overflows += 1
            tail = b""
        self._buf = tail
        out: list[Packet] = []
        stats = self.stats
        for frame in frames:
            if not frame:  # empty frames (repeated 0x00) are idle bytes, not errors
                continue
            if len(frame) > _MAX_FRAME:
                stats.overflows += 1
                continue
            try:
                raw = cobs.decode(frame)
            except cobs.DecodeError:
                stats.cobs_errors += 1
                continue
            if len(raw) < 4 or raw[-2] != len(raw):
                stats.length_errors += 1
                continue
            if crc8(raw[:-1]) != raw[-1]:
                stats.crc_errors += 1
                continue
            stats.packets += 1
            out.append(Packet(raw[-3], raw[-4], raw[:-4]))
        return out

    def feed_datagram(self, datagram: bytes) -> list[Packet]:
        """Decode one whole datagram: any number of packets, and no frame runs on into the next
        datagram (an unterminated tail is counted in ``stats.unterminated`` and dropped)."""
        self._buf = b""
        out = self.feed(datagram)
        if self._buf:
            self.stats.unterminated += 1
            self._buf = b""
        return out

    def reset(self) -> None:
        """Drop any partial frame (e.g. after reopening a port)."""
        self._buf = b""


def encode_floats(*values: float) -> bytes:
    """Little-endian float32 payload of ``values``; raises ValueError on NaN or inf."""
    for v in values:
        if v != v or v in (float("inf"), float("-inf")):
            raise ValueError(f"non-finite value {v!r} cannot be sent")
    return struct.pack(f"<{len(values)}f", *values)


def decode_floats(data: bytes) -> tuple[float, ...]:
    """Float32 values of a payload; raises ValueError if its length is not a multiple of 4."""
    if len(data) % 4:
        raise ValueError(f"{len(data)}-byte payload is not a whole number of float32")
    return struct.unpack(f"<{len(data) // 4}f", data)


def decode_float(data: bytes) -> float:
    """The single float32 of a 4-byte payload; raises ValueError otherwise."""
    if len(data) != 4:
        raise ValueError(f"expected one float32 (4 bytes), got {len(data)} bytes")
    return struct.unpack("<f", data)[0]
