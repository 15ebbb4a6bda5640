"""What a Reach arm's devices answer to a REQUEST, and how to read it (docs/hardware.md).

:data:`ANSWER_FORMATS` maps each answerable packet id to the ``struct`` layout of its data
(little-endian) and its units; :func:`decode_answer` turns an answer's bytes into numbers.
"""

from __future__ import annotations

import dataclasses
import struct

from ._ids import HardwareStatus, PacketID

__all__ = ["ANSWER_FORMATS", "AnswerFormat", "decode_answer"]


@dataclasses.dataclass(frozen=True)
class AnswerFormat:
    """Layout of one answer's data.

    Attributes:
      fmt: ``struct`` format, little-endian (``"<f"`` one float32, ``"<3B"`` three bytes …).
      units: what the values mean, in order.
    """

    fmt: str
    units: str

    @property
    def size(self) -> int:
        """Data length [bytes]."""
        return struct.calcsize(self.fmt)


ANSWER_FORMATS: dict[int, AnswerFormat] = {
    PacketID.MODE: AnswerFormat("<B", "mode (Mode)"),
    PacketID.VELOCITY: AnswerFormat("<f", "rad/s (jaws mm/s)"),
    PacketID.POSITION: AnswerFormat("<f", "rad (jaws mm)"),
    PacketID.CURRENT: AnswerFormat("<f", "mA"),
    PacketID.POSITION_LIMITS: AnswerFormat("<2f", "max, min: rad (jaws mm)"),
    PacketID.VELOCITY_LIMITS: AnswerFormat("<2f", "max, min: rad/s (jaws mm/s)"),
    PacketID.CURRENT_LIMITS: AnswerFormat("<2f", "max, min: mA"),
    PacketID.SERIAL_NUMBER: AnswerFormat("<f", "serial number"),
    PacketID.MODEL_NUMBER: AnswerFormat("<f", "model number"),
    PacketID.DEVICE_ID: AnswerFormat("<B", "device id"),
    PacketID.HUMIDITY: AnswerFormat("<f", "%"),
    PacketID.TEMPERATURE: AnswerFormat("<f", "°C"),
    PacketID.PRESSURE: AnswerFormat("<f", "bar"),
    PacketID.HARDWARE_STATUS: AnswerFormat("<4B", "status bytes A, B, C, D"),
    PacketID.SOFTWARE_VERSION: AnswerFormat("<3B", "major, sub-major, minor"),
    PacketID.VOLTAGE: AnswerFormat("<f", "V"),
    PacketID.HEARTBEAT_SET: AnswerFormat("<10B", "packet ids (0 = unused)"),
    PacketID.HEARTBEAT_FREQUENCY: AnswerFormat("<B", "Hz (0 = off)"),
    PacketID.KM_END_POS: AnswerFormat("<6f", "X, Y, Z [mm], yaw, pitch, roll [rad]"),
    PacketID.KM_END_VEL: AnswerFormat("<6f", "X, Y, Z [mm/s], yaw, pitch, roll rates [rad/s]"),
}


def decode_answer(packet_id: int, data: bytes) -> tuple:
    """The values of an answer to a REQUEST of ``packet_id`` (a tuple, even for one value).

    HARDWARE_STATUS gives one :class:`HardwareStatus` (bytes A–D read little-endian).

    Raises:
      ValueError: an id with no known answer, or data of the wrong size.
    """
    f = ANSWER_FORMATS.get(packet_id)
    if f is None:
        raise ValueError(f"packet id 0x{int(packet_id):02X} has no known answer format")
    if len(data) != f.size:
        name = PacketID(packet_id).name
        raise ValueError(f"{name} answer has {len(data)} bytes, expected {f.size}")
    values = struct.unpack(f.fmt, data)
    if packet_id == PacketID.HARDWARE_STATUS:
        return (HardwareStatus(int.from_bytes(data, "little")),)
    return values
