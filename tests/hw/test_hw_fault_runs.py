"""Fault runs: each completes or stops into hold with its reason, and none hangs — through
``uvms-hw run`` (real time, simulated arm over UDP, reason in ``results.json``) and, for the whole
matrix (drop, corruption, latency, stuck joint, hardware fault, link loss), on the in-process
link on a virtual clock."""

from __future__ import annotations

import dataclasses
import json
import socket
import subprocess
import sys
import threading
import time

import pytest

from _hw_helpers import BRAVO7, SimRun, short_plan
from uvms_jax.hw import ExecutorSettings, PacketID, SimSettings, decode_float, encode_packet, plan_to_dict
from uvms_jax.hw.cli import main

# The served simulator (``uvms-hw sim``) starts mid-range with the jaws at 0 mm.
MID = [0.5 * (j.lower + j.upper) for j in BRAVO7[:6]]
NEAR = [q + 0.2 for q in MID]


@pytest.fixture
def plan_file(tmp_path):
    p = tmp_path / "plan.json"
    p.write_text(json.dumps(plan_to_dict(short_plan())))
    return p


def _result(out):
    return json.loads((out / "results.json").read_text())


@pytest.mark.parametrize(("flags", "abort_reason"), [
    (["--drop", "0.3", "--corrupt", "0.05", "--seed", "2"], None),  # completes or holds
    (["--drop", "0.3", "--corrupt", "0.05", "--seed", "2", "--stream", "50"], None),  # streamed state
    (["--stuck-joint", "C", "--gate-timeout", "0.5"], "joint C"),
    (["--hw-fault", "E:0x2000@0.5"], "MOTOR_OVER_CURRENT"),  # status byte B 0x20
])
def test_fault_runs_complete_or_hold_with_a_reason(plan_file, tmp_path, flags, abort_reason):
    out = tmp_path / "out"
    t = time.monotonic()
    rc = main(["run", str(plan_file), "--sim", "--no-plot", "--out", str(out), *flags])
    assert time.monotonic() - t < 30
    res = _result(out)
    assert rc in (0, 1) and res["ok"] == (rc == 0)
    assert res["status"] == ("completed" if rc == 0 else "aborted")
    assert res["sim"]["limit_violations"] == 0
    if rc == 1:
        assert res["reason"] and res["abort_after_s"] is not None
    if abort_reason is not None:
        assert rc == 1 and abort_reason in res["reason"], res["reason"]


def test_killed_simulator_process_stops_the_run(tmp_path):
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as free:
        free.bind(("127.0.0.1", 0))
        port = free.getsockname()[1]
    probe = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    probe.bind(("127.0.0.1", 0))
    proc = subprocess.Popen([sys.executable, "-m", "uvms_jax.hw.cli", "sim", "--port", str(port)],
                            stderr=subprocess.DEVNULL)
    try:
        deadline = time.monotonic() + 60.0  # the process imports MuJoCo first
        probe.settimeout(0.2)
        while True:
            assert proc.poll() is None
            probe.sendto(encode_packet(0x07, PacketID.REQUEST, bytes([PacketID.POSITION])), ("127.0.0.1", port))
            try:
                probe.recvfrom(4096)
                break
            except TimeoutError:
                assert time.monotonic() < deadline
        probe.close()
        plan = tmp_path / "plan.json"
        plan.write_text(json.dumps(plan_to_dict(short_plan(MID, NEAR))))
        killer = threading.Timer(1.5, proc.kill)
        killer.start()
        out = tmp_path / "out"
        t = time.monotonic()
        rc = main(["run", str(plan), "--udp", f"127.0.0.1:{port}", "--no-plot", "--out", str(out)])
        killer.join()
        assert time.monotonic() - t < 10
    finally:
        proc.kill()
        proc.wait(10)
    res = _result(out)
    assert rc == 1 and not res["ok"] and "lost link" in res["reason"], res["reason"]
    assert 1.0 < res["duration_s"] < 1.5 + 1.0  # killed at 1.5 s; link_timeout_s 0.5 s later


# -- the fault matrix on the in-process link (virtual clock: each run costs well under a second) --

def _link_lost_at(run: SimRun, segment: int):
    """A progress callback that cuts the link (every datagram lost, both ways) as ``segment`` starts."""
    def cut(i, n, name):
        if i == segment:
            run.link.config = dataclasses.replace(run.link.config, drop=1.0)
    return cut


def _hold_sent_last(run: SimRun) -> bool:
    """The client's last motion packets are zero velocity to every joint, three times (hold)."""
    motion = [p for p in run.sent_packets() if p.packet_id in (PacketID.POSITION, PacketID.VELOCITY)]
    tail = motion[-3 * len(BRAVO7):]
    return (len(tail) == 3 * len(BRAVO7) and all(p.packet_id == PacketID.VELOCITY and decode_float(p.data) == 0.0
                                                 for p in tail)
            and sorted(p.device_id for p in tail) == sorted(3 * [j.device_id for j in BRAVO7]))


# (sim faults, executor settings, expected reason prefix (None: completes), counter that shows
# the fault was injected, bound on the (virtual) run time [s])
MATRIX = {
    "drop": (dict(drop=0.1, seed=1), {}, None, "dropped", 6.0),
    "drop, streamed state": (dict(drop=0.3, seed=1), dict(stream_hz=50), None, "dropped", 6.0),
    "corruption": (dict(corrupt=0.1, seed=1), {}, None, "corrupted", 6.0),
    "latency": (dict(latency_s=0.05), {}, None, None, 6.0),
    "latency beyond the link timeout": (dict(latency_s=0.8), {}, "LinkError: lost link", None, 3.0),
    "stuck joint": (dict(stuck_joint="C"), dict(gate_timeout_s=0.5), "AbortRun: segment 0 waypoint 1", None, 3.0),
    "hardware fault": (dict(fault_joint="E", fault_bits=0x2000, fault_after_s=0.5), {},
                       "AbortRun: hardware status fault: joint E", None, 1.5),
    "link down at connect": (dict(drop=1.0), {}, "LinkError: no answer", "dropped", 2.0),
}


@pytest.mark.parametrize("case", list(MATRIX))
def test_fault_matrix_ends_completed_or_held_with_its_reason(case):
    sim, hw, reason, counter, bound = MATRIX[case]
    run = SimRun(SimSettings(**sim), ExecutorSettings(**hw))
    t = time.monotonic()
    res = run.executor.run(short_plan())
    assert time.monotonic() - t < 20  # no hang (each takes well under a second alone)
    assert res.duration_s < bound
    assert run.arm.limit_violations == 0
    if counter is not None:
        assert getattr(run.link, counter) > 0  # the fault was there
    if reason is None:
        assert res.ok and res.reason == "completed", res.reason
        assert len(res.gates) == 4 and res.max_gate_error_rad <= ExecutorSettings().gate_threshold_rad
    else:
        assert not res.ok and res.reason.startswith(reason), res.reason
        assert res.abort_after_s <= res.duration_s
        assert _hold_sent_last(run)


def test_fault_matrix_link_lost_mid_run_holds_after_the_link_timeout():
    run = SimRun()
    run.executor.progress = _link_lost_at(run, 1)
    res = run.executor.run(short_plan())
    assert not res.ok and res.reason.startswith("LinkError: lost link"), res.reason
    assert len(res.gates) == 3  # segment 0 (its start, move and gripper step) passed before the cut
    timeout = ExecutorSettings().link_timeout_s
    assert timeout <= res.abort_after_s <= timeout + 0.2  # it stops link_timeout_s after the last state
    assert _hold_sent_last(run)
