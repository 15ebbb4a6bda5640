"""Typed identifiers of the Reach/Blueprint Lab "BPL" protocol (docs/theory.md §6).

Packet ids, device modes and hardware-status bits, as integer enums so that they print by name
and compare equal to the bytes on the wire, and the protocol's fixed device ids (broadcast, the
base's router and computer). An arm's joint device ids are the arm's: its robot's hardware
profile (:func:`uvms_jax.hw.device_ids`).
"""

from __future__ import annotations

import enum

__all__ = ["BASE_COMPUTER", "BASE_ROUTER", "BROADCAST", "HardwareStatus", "Mode", "PacketID"]


class PacketID(enum.IntEnum):
    """BPL packet ids (one byte on the wire)."""

    MODE = 0x01
    VELOCITY = 0x02
    POSITION = 0x03
    OPENLOOP = 0x04
    CURRENT = 0x05
    INDEXED_POSITION = 0x0D
    RELATIVE_POSITION = 0x0E
    POSITION_LIMITS = 0x10
    VELOCITY_LIMITS = 0x11
    CURRENT_LIMITS = 0x12
    SAVE = 0x50
    REQUEST = 0x60
    SERIAL_NUMBER = 0x61
    MODEL_NUMBER = 0x62
    DEVICE_ID = 0x64
    HUMIDITY = 0x65
    TEMPERATURE = 0x66
    PRESSURE = 0x67  # the older SDK calls 0x67 DEVICE_TYPE; the protocol listing says pressure
    HARDWARE_STATUS = 0x68
    SOFTWARE_VERSION = 0x6C
    VOLTAGE = 0x90
    HEARTBEAT_SET = 0x91
    HEARTBEAT_FREQUENCY = 0x92
    KM_END_POS = 0xA1
    KM_END_VEL = 0xA2


class Mode(enum.IntEnum):
    """Device operating modes (data byte of a MODE packet)."""

    STANDBY = 0x00
    DISABLE = 0x01
    POSITION = 0x02
    VELOCITY = 0x03
    CURRENT = 0x04
    OPENLOOP = 0x05
    ZERO_VELOCITY = 0x15


# 0xFF addresses every device.
BROADCAST = 0xFF

# The base's two devices; the base computer answers the end-effector pose and velocity.
BASE_ROUTER = 0x0D
BASE_COMPUTER = 0x0E


class HardwareStatus(enum.IntFlag):
    """Hardware-status bits; any set bit is a fault the executor aborts on.

    On the wire the status is 4 bytes A, B, C, D; read little-endian as one integer, byte A is
    bits 0–7, byte B bits 8–15 and byte C bits 16–23 (byte D carries no flag).
    """

    OK = 0
    # byte A
    ENCODER_NOT_DETECTED = 1 << 0
    ENCODER_POSITION_ERROR = 1 << 1
    MOTOR_DRIVER_FAULT = 1 << 2
    COMMS_CRC_ERROR = 1 << 3
    COMMS_SERIAL_ERROR = 1 << 4
    OVER_TEMPERATURE = 1 << 5
    OVER_HUMIDITY = 1 << 6
    FLASH_READ_FAILED = 1 << 7
    # byte B
    DRIVER_OVER_TEMPERATURE = 1 << 8
    DRIVER_OVER_CURRENT_UNDER_VOLTAGE = 1 << 9
    OVER_PRESSURE = 1 << 10
    DEVICE_ID_CONFLICT = 1 << 11
    INPUT_ENCODER_POSITION_ERROR = 1 << 12
    MOTOR_OVER_CURRENT = 1 << 13
    MOTOR_NOT_CONNECTED = 1 << 14
    DEVICE_AXIS_CONFLICT = 1 << 15
    # byte C
    ENCODER_FAULT = 1 << 17
    JOINT_SERVICE_DUE = 1 << 19
