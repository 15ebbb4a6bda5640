"""``ReachArm``: a safe client of the BPL protocol over any :class:`Transport`, for any Reach
arm (its joint table: :func:`~uvms_jax.hw.joint_specs` of its robot).

Every outgoing packet goes through :meth:`ReachArm.send`, the lowest send layer, which refuses
(raises :class:`LimitError`, never clips) a POSITION demand outside the joint's limits, a
VELOCITY demand above its speed limit, a broadcast motion demand, and any packet id other than
the few the runner needs (no limit writes, no open-loop or current drive). It checks the
float32 that goes on the wire, exactly: a demand of 6.3 rad, which float32 rounds up past the
limit, is sent as the float32 just inside it (:meth:`ReachArm.set_positions`), and raw bytes
holding the float32 above it are refused.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Callable, Iterable, Sequence

from ._answers import decode_answer
from ._codec import Packet, PacketReader, decode_float, decode_floats, encode_floats, encode_packet
from ._ids import BROADCAST, HardwareStatus, Mode, PacketID
from ._joints import (JointSpec, LimitError, check_position, check_velocity, spec_for_device, wire_position,
                      wire_velocity)
from ._transport import ClosedOnExit, LinkError, Transport

__all__ = ["JointState", "ReachArm", "SENDABLE"]

# What the runner may send. Everything else (limit writes, SAVE, open-loop, current, relative
# and indexed position) could move the arm or change its limits behind the guard's back.
SENDABLE = frozenset(
    {PacketID.MODE, PacketID.POSITION, PacketID.VELOCITY, PacketID.REQUEST,
     PacketID.HEARTBEAT_SET, PacketID.HEARTBEAT_FREQUENCY}
)
_SAFE_MODES = frozenset({Mode.STANDBY, Mode.DISABLE, Mode.POSITION, Mode.VELOCITY, Mode.ZERO_VELOCITY})


@dataclasses.dataclass(frozen=True)
class JointState:
    """Measured state of some devices, in the order they were asked for.

    Attributes:
      devices: device ids.
      positions: (n,) positions [rad; mm for the jaws].
      velocities: (n,) velocities [rad/s; mm/s for the jaws].
      t: clock time at which the state was complete [s].
    """

    devices: tuple[int, ...]
    positions: tuple[float, ...]
    velocities: tuple[float, ...]
    t: float


def guard_packet(device_id: int, packet_id: int, data: bytes, joints: Sequence[JointSpec]) -> None:
    """Raise LimitError/ValueError unless the packet is safe to send (see module docstring)."""
    if packet_id not in SENDABLE:
        name = PacketID(packet_id).name if packet_id in PacketID._value2member_map_ else f"0x{packet_id:02X}"
        raise ValueError(f"packet id {name} is not allowed by the safe client")
    if packet_id in (PacketID.POSITION, PacketID.VELOCITY):
        if device_id == BROADCAST:
            raise LimitError("broadcast motion demands are refused: limits are per joint")
        spec = spec_for_device(device_id, tuple(joints))
        value = decode_float(data)
        if packet_id == PacketID.POSITION:
            check_position(spec, value)
        else:
            check_velocity(spec, value)
    elif packet_id == PacketID.MODE:
        if len(data) != 1 or data[0] not in _SAFE_MODES:
            raise ValueError(f"mode payload {data.hex()} is not one of {sorted(m.name for m in _SAFE_MODES)}")


class ReachArm(ClosedOnExit):
    """Client of one Reach arm (or its simulator) over ``transport``.

    Args:
      transport: byte link (UDP, serial, or the in-process simulator link).
      joints: ``(n + 1,)`` the joint table the guard enforces and the client reads: the arm's
        joints, then the jaws (``joint_specs(robot)``).
      request_timeout: default wait for the answers to one REQUEST [s].
      clock: monotonic clock [s] (injectable for simulated time).
    """

    def __init__(
        self,
        transport: Transport,
        joints: Sequence[JointSpec],
        *,
        request_timeout: float = 0.05,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        self.transport = transport
        self.joints = tuple(joints)
        if not self.joints or not all(isinstance(j, JointSpec) for j in self.joints):
            raise TypeError("joints must be a non-empty sequence of JointSpec (hw.joint_specs(robot))")
        self.request_timeout = request_timeout
        self.clock = clock
        self.reader = PacketReader()
        self.latest: dict[tuple[int, int], tuple[bytes, float]] = {}
        self.packets_sent = 0

    # -- sending ---------------------------------------------------------------------------
    def send(self, packets: Iterable[tuple[int, int, bytes]]) -> None:
        """Guard, encode and send packets as one write (one datagram on UDP).

        Raises:
          LimitError: a motion demand outside the limits (nothing of the batch is sent).
          ValueError: a packet id or mode the safe client does not send.
          LinkError: the transport failed.
        """
        frames = []
        for device_id, packet_id, data in packets:
            guard_packet(device_id, packet_id, data, self.joints)
            frames.append(encode_packet(device_id, packet_id, data))
        if frames:
            self.transport.send(b"".join(frames))
            self.packets_sent += len(frames)

    def set_mode(self, mode: Mode, devices: Iterable[int] = (BROADCAST,)) -> None:
        """Set the operating mode of ``devices`` (default: all, by broadcast)."""
        self.send((d, PacketID.MODE, bytes((Mode(mode),))) for d in devices)

    def set_positions(self, demands: Iterable[tuple[int, float]]) -> None:
        """Send POSITION demands ``(device_id, value [rad or mm])`` in one write, each as the
        nearest float32 inside the joint's limits (:func:`~uvms_jax.hw._joints.wire_position`).

        Raises:
          LimitError: a value outside the limits, or a device without limits (nothing sent).
        """
        self.send([(d, PacketID.POSITION, encode_floats(wire_position(self._spec(d), v))) for d, v in demands])

    def set_velocities(self, demands: Iterable[tuple[int, float]]) -> None:
        """Send VELOCITY demands ``(device_id, value [rad/s or mm/s])`` in one write (float32
        inside the speed limit, as for positions)."""
        self.send([(d, PacketID.VELOCITY, encode_floats(wire_velocity(self._spec(d), v))) for d, v in demands])

    def _spec(self, device_id: int) -> JointSpec:
        if device_id == BROADCAST:
            raise LimitError("broadcast motion demands are refused: limits are per joint")
        return spec_for_device(device_id, self.joints)

    def hold(self, repeats: int = 3) -> bool:
        """Zero velocity on every known device, sent ``repeats`` times for lossy links.

        Never raises (it is the last thing done after a failure); returns whether every
        write went out.
        """
        ok = True
        for _ in range(repeats):
            try:
                self.set_velocities((j.device_id, 0.0) for j in self.joints)
            except Exception:  # noqa: BLE001 - best effort by design
                ok = False
        return ok

    def set_heartbeat(self, packet_ids: Sequence[int], frequency_hz: int, device: int = BROADCAST) -> None:
        """Ask ``device`` to stream ``packet_ids`` at ``frequency_hz`` (0 stops it)."""
        if not 0 <= frequency_hz <= 255:
            raise ValueError(f"heartbeat frequency {frequency_hz} Hz outside 0..255")
        if len(packet_ids) > 10:
            raise ValueError("at most 10 packet ids per heartbeat")
        self.send([
            (device, PacketID.HEARTBEAT_SET, bytes(int(p) for p in packet_ids)),
            (device, PacketID.HEARTBEAT_FREQUENCY, bytes((frequency_hz,))),
        ])

    # -- receiving -------------------------------------------------------------------------
    def _feed(self, chunk: bytes) -> list[Packet]:
        """Packets of one read: a datagram transport's read is decoded on its own, any number
        of packets in it; a byte stream's reads are joined."""
        if getattr(self.transport, "datagrams", False):
            return self.reader.feed_datagram(chunk)
        return self.reader.feed(chunk)

    def poll(self, timeout: float = 0.0) -> int:
        """Read what arrives within ``timeout`` [s] (one transport read) into :attr:`latest`;
        returns the packet count."""
        return self._take(self.transport.recv(timeout))

    def _take(self, chunk: bytes) -> int:
        pkts = self._feed(chunk) if chunk else []
        now = self.clock()
        for p in pkts:
            self.latest[(p.device_id, p.packet_id)] = (p.data, now)
        return len(pkts)

    def _drain(self) -> None:
        """Read everything already received, without waiting."""
        while chunk := self.transport.recv(0.0):
            self._take(chunk)

    def request(
        self,
        packet_ids: Sequence[int],
        devices: Sequence[int],
        *,
        timeout: float | None = None,
        retries: int = 1,
    ) -> dict[tuple[int, int], bytes]:
        """Request ``packet_ids`` from ``devices`` and wait for every answer.

        One broadcast REQUEST is sent when several devices are asked, else one addressed to
        the device. Returns ``{(device_id, packet_id): data}``.

        Raises:
          LinkError: some answer missing after ``retries`` tries of ``timeout`` seconds each.
        """
        timeout = self.request_timeout if timeout is None else timeout
        target = devices[0] if len(devices) == 1 else BROADCAST
        wanted = {(int(d), int(p)) for d in devices for p in packet_ids}
        got: dict[tuple[int, int], bytes] = {}
        for _ in range(max(retries, 1)):
            self.send([(target, PacketID.REQUEST, bytes(int(p) for p in packet_ids))])
            deadline = self.clock() + timeout
            while True:
                remaining = deadline - self.clock()
                if remaining <= 0:
                    break
                chunk = self.transport.recv(remaining)
                if not chunk:
                    continue
                now = self.clock()
                for p in self._feed(chunk):
                    key = (p.device_id, p.packet_id)
                    self.latest[key] = (p.data, now)
                    if key in wanted:
                        got[key] = p.data
                if len(got) == len(wanted):
                    return got
        missing = sorted(wanted - got.keys())
        names = ", ".join(f"{PacketID(p).name}@0x{d:02X}" for d, p in missing[:6])
        raise LinkError(f"no answer within {timeout * 1e3:.0f} ms x{max(retries, 1)}: {names}"
                        + (" …" if len(missing) > 6 else ""))

    def read_state(self, devices: Sequence[int] | None = None, **kw) -> JointState:
        """Positions and velocities of ``devices`` (default: all joints) in one request."""
        devices = tuple(j.device_id for j in self.joints) if devices is None else tuple(devices)
        got = self.request((PacketID.POSITION, PacketID.VELOCITY), devices, **kw)
        try:
            pos = tuple(decode_float(got[(d, PacketID.POSITION)]) for d in devices)
            vel = tuple(decode_float(got[(d, PacketID.VELOCITY)]) for d in devices)
        except ValueError as e:
            raise LinkError(f"malformed state packet: {e}") from e
        return JointState(devices, pos, vel, self.clock())

    def read_hardware_status(self, devices: Sequence[int] | None = None, **kw) -> dict[int, HardwareStatus]:
        """Hardware-status flags per device (0 = healthy)."""
        devices = tuple(j.device_id for j in self.joints) if devices is None else tuple(devices)
        got = self.request((PacketID.HARDWARE_STATUS,), devices, **kw)
        # Bytes A–D little-endian; a shorter answer (older firmware) is read as far as it goes.
        return {d: HardwareStatus(int.from_bytes(got[(d, PacketID.HARDWARE_STATUS)][:4], "little"))
                for d in devices}

    def recent_hardware_status(self, devices: Sequence[int], *, since: float) -> dict[int, HardwareStatus]:
        """Hardware status of those ``devices`` whose last status answer arrived after ``since``
        [s] (sends nothing; devices without one are left out)."""
        out = {}
        for d in devices:
            data, t = self.latest.get((d, PacketID.HARDWARE_STATUS), (b"", -float("inf")))
            if t > since:
                out[d] = HardwareStatus(int.from_bytes(data[:4], "little"))
        return out

    def read(self, packet_ids: Sequence[int], devices: Sequence[int], **kw) -> dict[tuple[int, int], tuple]:
        """Request ``packet_ids`` from ``devices`` and decode the answers (:func:`decode_answer`).

        Returns:
          ``{(device_id, packet_id): values}``, e.g. ``{(0x0E, KM_END_POS): (x, y, z, yaw, pitch, roll)}``.

        Raises:
          LinkError: an answer missing, or of the wrong size for its id.
        """
        got = self.request(packet_ids, devices, **kw)
        try:
            return {k: decode_answer(k[1], v) for k, v in got.items()}
        except ValueError as e:
            raise LinkError(f"malformed answer: {e}") from e

    # -- streaming (heartbeat) -------------------------------------------------------------
    def start_stream(self, frequency_hz: int, packet_ids: Sequence[int] = (PacketID.POSITION, PacketID.VELOCITY),
                     device: int = BROADCAST) -> None:
        """Have ``device`` (default: every joint) stream ``packet_ids`` at ``frequency_hz``, so
        that :meth:`stream_state` reads the state without a request per tick."""
        if not 1 <= frequency_hz <= 255:
            raise ValueError(f"stream frequency {frequency_hz} Hz outside 1..255")
        self.set_heartbeat(packet_ids, frequency_hz, device)

    def stop_stream(self, device: int = BROADCAST) -> bool:
        """Stop the heartbeat of ``device``; best effort (never raises), returns whether it went out."""
        try:
            self.set_heartbeat((), 0, device)
        except Exception:  # noqa: BLE001 - called while stopping, like hold()
            return False
        return True

    def stream_state(self, devices: Sequence[int] | None = None, *, since: float,
                     timeout: float | None = None) -> JointState:
        """The state of ``devices`` from streamed packets that arrived after ``since`` [s].

        Reads everything already received, then waits up to ``timeout`` [s] for what is
        still missing; sends nothing.

        Raises:
          LinkError: some device's POSITION or VELOCITY did not arrive in time, or is malformed.
        """
        devices = tuple(j.device_id for j in self.joints) if devices is None else tuple(devices)
        timeout = self.request_timeout if timeout is None else timeout
        keys = [(d, p) for d in devices for p in (PacketID.POSITION, PacketID.VELOCITY)]
        deadline = self.clock() + timeout
        self._drain()
        while True:
            fresh = [k for k in keys if k in self.latest and self.latest[k][1] > since]
            if len(fresh) == len(keys):
                break
            remaining = deadline - self.clock()
            if remaining <= 0:
                missing = sorted(set(keys) - set(fresh))
                names = ", ".join(f"{PacketID(p).name}@0x{d:02X}" for d, p in missing[:6])
                raise LinkError(f"stream: nothing new within {timeout * 1e3:.0f} ms from {names}"
                                + (" …" if len(missing) > 6 else ""))
            self.poll(remaining)
        try:
            pos = tuple(decode_float(self.latest[(d, PacketID.POSITION)][0]) for d in devices)
            vel = tuple(decode_float(self.latest[(d, PacketID.VELOCITY)][0]) for d in devices)
        except ValueError as e:
            raise LinkError(f"malformed state packet: {e}") from e
        return JointState(devices, pos, vel, self.clock())

    def read_position_limits(self, devices: Sequence[int] | None = None, **kw) -> dict[int, tuple[float, float]]:
        """Position limits stored in each device, as (lower, upper) [rad or mm]."""
        devices = tuple(j.device_id for j in self.joints) if devices is None else tuple(devices)
        got = self.request((PacketID.POSITION_LIMITS,), devices, **kw)
        out = {}
        for d in devices:
            vals = decode_floats(got[(d, PacketID.POSITION_LIMITS)])
            if len(vals) != 2:
                raise LinkError(f"POSITION_LIMITS of device 0x{d:02X} has {len(vals)} values, expected 2")
            out[d] = (min(vals), max(vals))
        return out

    def close(self) -> None:
        """Close the transport."""
        self.transport.close()

