"""Byte transports to a Reach arm: UDP and serial (pyserial), both with timeouts.

A transport moves raw bytes; framing is the codec's job. ``recv(timeout)`` returns ``b""``
when nothing arrived in time — timeouts are normal events on a lossy link, and the client
decides when silence becomes a lost link.
"""

from __future__ import annotations

import socket
from typing import Protocol, Self

__all__ = ["ClosedOnExit", "LinkError", "SerialTransport", "Transport", "UdpTransport", "parse_host_port"]


class LinkError(RuntimeError):
    """The link to the arm failed: no answer in time, or the socket/port broke."""


class Transport(Protocol):
    """What the client needs from a link (the transports here also have a ``name`` for logs,
    and ``datagrams = True`` where each ``recv`` is one whole datagram, as on UDP)."""

    def send(self, data: bytes) -> None:
        """Send raw bytes (one datagram for UDP)."""

    def recv(self, timeout: float) -> bytes:
        """Bytes received within ``timeout`` seconds, or ``b""``."""

    def close(self) -> None:
        """Release the link."""


class ClosedOnExit:
    """``with`` support for anything with ``close()``: the link is released however the block ends."""

    def __enter__(self) -> Self:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def parse_host_port(text: str) -> tuple[str, int]:
    """Parse ``"HOST:PORT"``; raises ValueError with the offending text otherwise."""
    host, sep, port = text.rpartition(":")
    if not sep or not host or not port.isdigit() or not 0 < int(port) < 65536:
        raise ValueError(f"expected HOST:PORT, got {text!r}")
    return host, int(port)


class UdpTransport(ClosedOnExit):
    """UDP link to ``(host, port)`` (Reach factory default 192.168.2.3:6789).

    Only datagrams from the arm's address are accepted. Each ``recv`` returns one datagram,
    which may hold any number of packets.
    """

    datagrams = True  # each recv is one whole datagram: frames never span two
    def __init__(self, host: str, port: int, *, bind: tuple[str, int] = ("", 0)) -> None:
        self.address = (socket.gethostbyname(host), int(port))
        self.name = f"udp {self.address[0]}:{self.address[1]}"
        self._sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self._sock.bind(bind)

    def send(self, data: bytes) -> None:
        try:
            self._sock.sendto(data, self.address)
        except OSError as e:
            raise LinkError(f"UDP send to {self.address[0]}:{self.address[1]} failed: {e}") from e

    def recv(self, timeout: float) -> bytes:
        self._sock.settimeout(max(timeout, 1e-6))
        while True:
            try:
                data, addr = self._sock.recvfrom(65536)
            except TimeoutError:
                return b""
            except ConnectionRefusedError:
                # ICMP port unreachable from an earlier send: the arm is not listening.
                return b""
            except OSError as e:
                raise LinkError(f"UDP receive failed: {e}") from e
            if addr == self.address:
                return data
            self._sock.settimeout(1e-6)  # foreign datagram: drain without blocking again

    def close(self) -> None:
        self._sock.close()


class SerialTransport(ClosedOnExit):
    """Serial link (115200 8N1 by default). ``port`` may be a device or a pyserial URL
    such as ``loop://`` (used in tests)."""

    def __init__(self, port: str, baudrate: int = 115200) -> None:
        import serial  # pyserial; imported here so UDP-only users do not need a port layer

        self.name = f"serial {port}"

        try:
            self._serial = serial.serial_for_url(
                port, baudrate=baudrate, bytesize=8, parity="N", stopbits=1, timeout=0.0
            )
        except (serial.SerialException, ValueError) as e:
            raise LinkError(f"cannot open serial port {port!r}: {e}") from e
        self._exc = serial.SerialException

    def send(self, data: bytes) -> None:
        try:
            self._serial.write(data)
        except self._exc as e:
            raise LinkError(f"serial write failed: {e}") from e

    def recv(self, timeout: float) -> bytes:
        try:
            self._serial.timeout = max(timeout, 0.0)
            first = self._serial.read(1)  # blocks up to timeout
            if not first:
                return b""
            waiting = self._serial.in_waiting
            return first + (self._serial.read(waiting) if waiting else b"")
        except self._exc as e:
            raise LinkError(f"serial read failed: {e}") from e

    def close(self) -> None:
        self._serial.close()
