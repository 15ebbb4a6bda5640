"""The simulated arm's links: faults between it and the client, and how the bytes travel.

* :class:`SimLink` — a :class:`~uvms_jax.hw.SimArm` plus faults (drop, corruption, latency), shared by
* :class:`SimServer` — a UDP server thread on 127.0.0.1 (ephemeral port by default), and
* :class:`LoopbackTransport` — an in-process :class:`~uvms_jax.hw.Transport` on a
  :class:`VirtualClock`, so tests run a whole plan in simulated time without sockets.
"""

from __future__ import annotations

import collections
import math
import random
import socket
import threading
import time
from typing import TYPE_CHECKING

from ._codec import PacketReader
from ._settings import SimSettings

if TYPE_CHECKING:
    from ._sim import SimArm

__all__ = ["QUEUE_LIMIT", "LoopbackTransport", "SimLink", "SimServer", "VirtualClock"]

# The most datagrams a simulated link queues each way (replies waiting for their latency, and
# a loopback client's unread ones). A run's traffic needs far less: 14 datagrams a tick, 420
# in flight with 0.6 s of latency on a 50 Hz stream.
QUEUE_LIMIT = 1024


class SimLink:
    """A :class:`SimArm` behind a faulty link: drops, corruption and latency (seeded).

    Each answer leaves as its own datagram, as each device of a Reach arm answers for itself
    over UDP; with ``config.coalesce`` the answers to one received datagram share one (a byte
    stream's view, as on serial). Drops, corruption and latency apply per datagram.

    The replies wait in a bounded queue (``queue_limit`` datagrams, in the order they were
    sent): when it is full the oldest is dropped and counted in :attr:`overflowed`, so a
    flood of requests costs bounded memory, as on a device with fixed buffers.
    """

    def __init__(self, arm: SimArm, config: SimSettings | None = None, *, queue_limit: int = QUEUE_LIMIT) -> None:
        if queue_limit < 1:
            raise ValueError(f"queue_limit must be at least 1, got {queue_limit}")
        self.queue_limit = queue_limit
        self.arm = arm
        self.config = arm.config if config is None else config
        self._rng = random.Random(self.config.seed)
        self._reader = PacketReader()
        self._outbox: collections.deque[tuple[float, bytes]] = collections.deque()
        self.dropped = self.corrupted = 0
        self.overflowed = 0  # datagrams dropped from full queues (the oldest first)

    @property
    def reader_stats(self):
        """Decoder statistics of what the device received."""
        return self._reader.stats

    def receive(self, datagram: bytes, now: float) -> None:
        """A datagram arrives from the client at simulated time ``now`` [s]."""
        if self._rng.random() < self.config.drop:
            self.dropped += 1
            return
        self.arm.step_to(now)
        self._emit([a for p in self._reader.feed(datagram) for a in self.arm.handle(p)], now)

    def tick(self, now: float) -> None:
        """Advance physics to ``now`` and emit due heartbeats."""
        self.arm.step_to(now)
        self._emit(self.arm.heartbeat(), now)

    def _emit(self, packets: list[bytes], now: float) -> None:
        if not packets:
            return
        for data in [b"".join(packets)] if self.config.coalesce else packets:
            if self._rng.random() < self.config.drop:
                self.dropped += 1
                continue
            if self._rng.random() < self.config.corrupt:
                self.corrupted += 1
                b = bytearray(data)
                b[self._rng.randrange(len(b))] ^= self._rng.randrange(1, 256)
                data = bytes(b)
            if len(self._outbox) >= self.queue_limit:
                self._outbox.popleft()
                self.overflowed += 1
            self._outbox.append((now + self.config.latency_s, data))

    @property
    def queued(self) -> int:
        """Replies waiting to be delivered."""
        return len(self._outbox)

    def next_due(self) -> float:
        """Time the next queued datagram is due [s] (inf if none)."""
        return self._outbox[0][0] if self._outbox else math.inf

    def pop_due(self, now: float) -> list[bytes]:
        """Every datagram due by ``now``, in order."""
        out = []
        while self._outbox and self._outbox[0][0] <= now:
            out.append(self._outbox.popleft()[1])
        return out


class VirtualClock:
    """Simulated time for in-process runs: ``now()`` and ``sleep(dt)`` that just advances."""

    def __init__(self, t0: float = 0.0) -> None:
        self.t = t0

    def now(self) -> float:
        """Current simulated time [s]."""
        return self.t

    def sleep(self, dt: float) -> None:
        """Advance simulated time by ``dt`` [s] (negative values are ignored)."""
        if dt > 0:
            self.t += dt


class LoopbackTransport:
    """In-process transport to a :class:`SimLink` on a :class:`VirtualClock` (no sockets).

    ``recv`` returns one datagram, as a UDP socket does, advancing the clock to the next one
    (or by the whole timeout), so a run costs only its computation time. ``sent`` keeps every
    datagram the client wrote. Datagrams delivered but not yet read wait in a queue filled only
    when empty, from the link's bounded one: it never holds more than ``link.queue_limit``.
    """

    datagrams = True  # each recv is one whole datagram

    def __init__(self, link: SimLink, clock: VirtualClock, *, tick: float = 0.01) -> None:
        self.link, self.clock = link, clock
        self.name = "loopback"
        self.sent: list[bytes] = []
        self._tick = tick
        self._inbox: collections.deque[bytes] = collections.deque()

    def send(self, data: bytes) -> None:
        self.sent.append(bytes(data))
        self.link.receive(data, self.clock.now())

    def recv(self, timeout: float) -> bytes:
        end = self.clock.now() + max(timeout, 0.0)
        while True:
            if self._inbox:
                return self._inbox.popleft()
            self.link.tick(self.clock.now())
            self._inbox.extend(self.link.pop_due(self.clock.now()))  # only when empty: bounded as the link's
            if self._inbox:
                return self._inbox.popleft()
            nxt = min(self.link.next_due(), end, self.clock.now() + self._tick)
            if self.clock.now() >= end:
                return b""
            self.clock.sleep(nxt - self.clock.now())

    def close(self) -> None:
        pass


class SimServer:
    """UDP server thread speaking BPL for a :class:`SimArm` (real time, 127.0.0.1).

    Replies go to the address of the last datagram received. Use as a context manager::

        with SimServer(SimArm(cfg, q0)) as server:
            transport = UdpTransport(*server.address)
    """

    def __init__(self, arm: SimArm, config: SimSettings | None = None, host: str = "127.0.0.1",
                 port: int = 0, poll_s: float = 0.002) -> None:
        self.link = SimLink(arm, config)
        self.arm = arm
        self._sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self._sock.bind((host, port))
        self.address: tuple[str, int] = self._sock.getsockname()
        self._poll = poll_s
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self.lock = threading.Lock()
        self.error: BaseException | None = None

    def start(self) -> SimServer:
        """Start the server thread (simulated time 0 = now)."""
        self._t0 = time.monotonic() - self.arm.time
        self._thread = threading.Thread(target=self._run, name="reach-sim", daemon=True)
        self._thread.start()
        return self

    def stop(self) -> None:
        """Stop the thread and close the socket."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=2.0)
        self._sock.close()

    def __enter__(self) -> SimServer:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()

    def _run(self) -> None:
        peer = None
        try:
            while not self._stop.is_set():
                now = time.monotonic() - self._t0
                wait = min(self._poll, max(self.link.next_due() - now, 0.0))
                self._sock.settimeout(max(wait, 1e-4))
                try:
                    data, peer_addr = self._sock.recvfrom(65536)
                except (TimeoutError, BlockingIOError):
                    data = None
                except OSError:
                    if self._stop.is_set():
                        return
                    raise
                now = time.monotonic() - self._t0
                with self.lock:
                    if data is not None:
                        peer = peer_addr
                        self.link.receive(data, now)
                    self.link.tick(now)
                    out = self.link.pop_due(now)
                if peer is not None:
                    for datagram in out:
                        self._sock.sendto(datagram, peer)
        except BaseException as e:  # surfaced to tests through .error
            self.error = e
