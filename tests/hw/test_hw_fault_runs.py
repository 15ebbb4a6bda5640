"""Fault runs through ``uvms-hw run``: each completes or stops into hold with the reason in
``result.json``, and none hangs (real time, simulated arm over UDP)."""

from __future__ import annotations

import json
import socket
import subprocess
import sys
import threading
import time

import pytest

from _hw_helpers import BRAVO7, short_plan
from uvms_jax.hw import encode_packet, PacketID, plan_to_dict
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
    return json.loads((out / "result.json").read_text())


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
