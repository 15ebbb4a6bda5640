"""Hardware-runner benchmark: prints one JSON object.

* codec throughput [packets/s]: ``encode_packet`` and ``PacketReader.feed`` on POSITION
  packets, next to the peer — the same codec computing the CRC with the ``crc`` library's
  own per-call ``Calculator.checksum`` (the straightforward use of the library);
* request→response round trip on loopback [ms]: a broadcast REQUEST of POSITION+VELOCITY to
  the simulated Bravo 7 (UDP 127.0.0.1) until all 14 answers (14 datagrams) are decoded — with the simulator
  in its own process (``uvms-hw sim``) and as a thread of the client's process (as
  ``uvms-hw run --sim`` does; shares the GIL, whose 5 ms switch interval shows in p99) — next
  to the peer: a bare UDP echo thread returning as many bytes (the floor of sockets alone);
* a 100 Hz state stream (heartbeat) from ``uvms-hw sim`` in its own process: complete states
  per second and datagrams the client sent per state, next to polling (one request per state).

Run: ``.venv/bin/python benchmarks/hw.py [--n 2000]``.
"""

from __future__ import annotations

import argparse
import platform
import socket
import statistics
import subprocess
import sys
import threading
import time

from cobs import cobs
from crc import Calculator

from uvms_jax.files import json_text
from uvms_jax.hw import (CRC8_CONFIG, PacketID, PacketReader, ReachArm, SimArm, SimSettings, SimServer, UdpTransport,
                         encode_floats, encode_packet, joint_specs)
from uvms_jax.robot import load_arm

ROBOT = load_arm("bravo7")  # the arm the benchmark's simulator and client speak for

_CRC8 = Calculator(CRC8_CONFIG, optimized=True)  # the peer: the crc library, as the codec configures it


def _rate(fn, n: int) -> float:
    t = time.perf_counter()
    fn(n)
    return n / (time.perf_counter() - t)


def codec(n: int) -> dict:
    data = encode_floats(1.2345)

    def enc(k):
        for i in range(k):
            encode_packet(1 + i % 7, PacketID.POSITION, data)

    def enc_peer(k):
        for i in range(k):
            body = data + bytes((PacketID.POSITION, 1 + i % 7, 8))
            cobs.encode(body + bytes((_CRC8.checksum(body),))) + b"\x00"

    stream = b"".join(encode_packet(1 + i % 7, PacketID.POSITION, data) for i in range(n))
    chunks = [stream[i:i + 1500] for i in range(0, len(stream), 1500)]  # MTU-sized reads

    def dec(_k):
        r = PacketReader()
        for c in chunks:
            r.feed(c)
        assert r.stats.packets == n

    def dec_peer(_k):
        for frame in stream.split(b"\x00")[:-1]:
            raw = cobs.decode(frame)
            assert _CRC8.checksum(raw[:-1]) == raw[-1]

    e, ep = _rate(enc, n), _rate(enc_peer, n)
    d, dp = _rate(dec, n), _rate(dec_peer, n)
    return {"encode_packets_per_s": round(e), "decode_packets_per_s": round(d),
            "peer_encode_packets_per_s": round(ep), "peer_decode_packets_per_s": round(dp),
            "encode_ratio": round(e / ep, 1), "decode_ratio": round(d / dp, 1)}


def _percentiles(xs: list[float]) -> dict:
    xs = sorted(xs)
    return {"p50_ms": round(statistics.median(xs) * 1e3, 3), "p99_ms": round(xs[int(0.99 * (len(xs) - 1))] * 1e3, 3)}


def _time_reads(address: tuple[str, int], n: int) -> list[float]:
    with ReachArm(UdpTransport(*address), joint_specs(ROBOT), request_timeout=0.5) as c:
        for _ in range(50):
            c.read_state(retries=20)
        ts = []
        for _ in range(n):
            t = time.perf_counter()
            c.read_state()
            ts.append(time.perf_counter() - t)
    return ts


def _sim_process() -> tuple[subprocess.Popen, tuple[str, int]]:
    """``uvms-hw sim`` in its own process (no GIL shared with the client) on a free port."""
    probe = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    probe.bind(("127.0.0.1", 0))
    port = probe.getsockname()[1]
    probe.close()
    proc = subprocess.Popen([sys.executable, "-m", "uvms_jax.hw.cli", "sim", "--port", str(port)],
                            stderr=subprocess.DEVNULL)
    return proc, ("127.0.0.1", port)


def stream(seconds: float = 3.0, hz: int = 100) -> dict:
    proc, address = _sim_process()
    try:
        with ReachArm(UdpTransport(*address), joint_specs(ROBOT), request_timeout=0.5) as c:
            c.read_state(retries=40)  # the process is up
            out = {}
            for name in ("polled", "streamed"):
                sent0, n, t0 = c.packets_sent, 0, time.perf_counter()
                if name == "streamed":
                    c.start_stream(hz)
                    sent0 = c.packets_sent
                since = c.clock()
                while time.perf_counter() - t0 < seconds:
                    if name == "polled":
                        c.read_state()
                    else:
                        since = c.stream_state(since=since, timeout=0.1).t
                    n += 1
                out[name] = {"states_per_s": round(n / (time.perf_counter() - t0), 1),
                             "packets_sent_per_state": round((c.packets_sent - sent0) / n, 3)}
            c.stop_stream()
            out["stream_hz"] = hz
    finally:
        proc.terminate()
        proc.wait(10)
    return out


def round_trip(n: int) -> dict:
    out = {}
    proc, address = _sim_process()
    try:
        out["bravo7_sim_process"] = _percentiles(_time_reads(address, n))
    finally:
        proc.terminate()
        proc.wait(10)
    # the simulator as a thread of this process (what `uvms-hw run --sim` does)
    with SimServer(SimArm(ROBOT, SimSettings())) as server:
        out["bravo7_sim_thread"] = _percentiles(_time_reads(server.address, n))

    srv = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    srv.bind(("127.0.0.1", 0))
    stop = threading.Event()

    def echo():
        srv.settimeout(0.05)
        while not stop.is_set():
            try:
                d, a = srv.recvfrom(65536)
            except TimeoutError:
                continue
            srv.sendto(d * 14, a)

    th = threading.Thread(target=echo, daemon=True)
    th.start()
    cli = UdpTransport(*srv.getsockname())
    req = encode_packet(0xFF, PacketID.REQUEST, bytes((PacketID.POSITION, PacketID.VELOCITY)))
    ts = []
    for i in range(n + 50):
        t = time.perf_counter()
        cli.send(req)
        cli.recv(0.5)
        if i >= 50:
            ts.append(time.perf_counter() - t)
    stop.set()
    th.join()
    cli.close()
    srv.close()
    out["peer_udp_echo"] = _percentiles(ts)
    out["p50_ratio"] = round(out["bravo7_sim_process"]["p50_ms"] / out["peer_udp_echo"]["p50_ms"], 1)
    return out


def main() -> None:
    p = argparse.ArgumentParser()
    p.add_argument("--n", type=int, default=2000, help="round trips")
    p.add_argument("--packets", type=int, default=100_000, help="packets through the codec")
    a = p.parse_args()
    res = {
        "benchmark": "hw",
        "command": " ".join(["python benchmarks/hw.py", *sys.argv[1:]]),
        "device": f"{platform.machine()} CPU, Python {platform.python_version()}",
        "codec": codec(a.packets),
        "round_trip": round_trip(a.n),
        "stream": stream(),
    }
    print(json_text(res))


if __name__ == "__main__":
    main()
