"""Runs lose nothing: Ctrl-C (SIGINT) holds the arm and writes the partial results marked
``interrupted`` (exit 130, no traceback); a run folder carries ``RUNNING`` until its results are
written, so a killed run is recognisable; a folder that holds a run is not written over unless
``--overwrite``."""

from __future__ import annotations

import json
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

from _hw_helpers import BRAVO, BRAVO7, SimRun, short_plan
from uvms_jax.files import RUNNING
from uvms_jax.hw import PacketID, RunInterrupted, decode_float, plan_to_dict, run_plan, write_run
from uvms_jax.hw import cli

ROOT = Path(__file__).resolve().parents[2]
THESIS_PLAN = ROOT / "examples" / "thesis_plan.json"  # ~70 s of motion: still running when signalled


def _interrupt_at(segment: int):
    def progress(i, n, name):
        if i == segment:
            raise KeyboardInterrupt
    return progress


def test_interrupt_holds_the_arm_and_keeps_what_was_done():
    run = SimRun()
    run.executor.progress = _interrupt_at(1)
    with pytest.raises(RunInterrupted) as info:
        run.executor.run(short_plan())
    res = info.value.result
    assert isinstance(info.value, KeyboardInterrupt)  # callers that do not look for it still stop
    assert res.interrupted and not res.ok and "interrupted (SIGINT)" in res.reason
    assert len(res.gates) == 3 and res.ticks > 0  # segment 0 done before the interrupt
    motion = [p for p in run.sent_packets() if p.packet_id in (PacketID.POSITION, PacketID.VELOCITY)]
    tail = motion[-3 * len(BRAVO7):]
    assert all(p.packet_id == PacketID.VELOCITY and decode_float(p.data) == 0.0 for p in tail)  # hold
    assert {p.device_id for p in tail} == {j.device_id for j in BRAVO7}


def test_interrupted_run_plan_writes_its_partial_results(tmp_path):
    with pytest.raises(RunInterrupted) as info:
        run_plan(short_plan(), BRAVO, link="loopback", progress=_interrupt_at(1))
    run = info.value.run
    assert run.status == "interrupted" and run.sim is not None
    (tmp_path / RUNNING).write_text("{}")
    report = write_run(run, tmp_path, plot=False)
    on_disk = json.loads((tmp_path / "results.json").read_text())
    assert on_disk == report and on_disk["status"] == "interrupted" and on_disk["ok"] is False
    assert on_disk["gates"] == 3
    rows = (tmp_path / "run.csv").read_text().splitlines()
    assert len(rows) == 1 + run.result.ticks  # every tick up to the interrupt
    assert not (tmp_path / RUNNING).exists()


# SIGINT to the end of the process: the hold and the writes take well under a second on an idle
# machine; the margin is for a loaded CI machine (two test workers).
SIGINT_TO_EXIT_S = 5.0


# The CLI in a child Python whose SIGINT raises KeyboardInterrupt, as from a terminal: a test
# worker's process may have come to ignore SIGINT, an ignored signal stays ignored across exec,
# and Python installs its handler only where SIGINT is not ignored.
CLI = ("import signal, sys; signal.signal(signal.SIGINT, signal.default_int_handler); "
       "from uvms_jax.hw.cli import main; sys.exit(main())")


def _start(out: Path, *flags: str) -> tuple[subprocess.Popen, list[str]]:
    """``uvms-hw run`` of the thesis plan on the simulated arm (UDP) in its own process, once the
    executor is driving the arm (its progress line on stderr; the folder marked); returns the
    process and the stderr read so far (a thread keeps reading it)."""
    proc = subprocess.Popen([sys.executable, "-c", CLI, "run", str(THESIS_PLAN), "--sim",
                             "--out", str(out), *flags], cwd=ROOT, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    err: list[str] = []
    threading.Thread(target=lambda: err.extend(iter(lambda: proc.stderr.read(1), "")), daemon=True).start()
    deadline = time.monotonic() + 60  # imports, the robot, the simulator's start on a loaded machine
    while not ((out / RUNNING).exists() and "run: " in "".join(err)):
        assert proc.poll() is None, "".join(err)
        assert time.monotonic() < deadline, "".join(err)
        time.sleep(0.05)
    time.sleep(0.5)  # moving by now
    return proc, err


def test_sigint_ends_a_run_quickly_with_partial_results(tmp_path):
    out = tmp_path / "out"
    proc, err = _start(out)
    t = time.monotonic()
    proc.send_signal(signal.SIGINT)
    proc.wait(timeout=60)
    assert time.monotonic() - t < SIGINT_TO_EXIT_S, "SIGINT took too long to end the run"
    stdout = proc.stdout.read()
    time.sleep(0.1)  # the reader thread's last characters
    stderr = "".join(err)
    assert proc.returncode == cli.EXIT_INTERRUPTED == 130, stderr
    assert "Traceback" not in stderr and "KeyboardInterrupt" not in stderr
    assert "interrupted, arm told to hold" in stderr
    res = json.loads((out / "results.json").read_text())
    assert res == json.loads(stdout)
    assert res["status"] == "interrupted" and res["ok"] is False and "told to hold" in res["reason"]
    assert res["ticks"] > 10 and res["link"] == "udp"
    assert len((out / "run.csv").read_text().splitlines()) == 1 + res["ticks"]
    assert not (out / RUNNING).exists()
    assert not list(out.glob(".*.tmp"))


def test_killed_run_is_marked_and_its_folder_refused_without_overwrite(tmp_path, capsys, monkeypatch):
    out = tmp_path / "out"
    proc, _ = _start(out)
    proc.kill()  # SIGKILL: nothing of the run's own can run
    proc.wait(timeout=10)
    assert (out / RUNNING).exists() and not (out / "results.json").exists()
    marker = json.loads((out / RUNNING).read_text())
    assert marker["pid"] == proc.pid
    plan = tmp_path / "plan.json"
    plan.write_text(json.dumps(plan_to_dict(short_plan())))
    # Refused, one line, nothing touched:
    assert cli.main(["run", str(plan), "--sim", "--no-plot", "--out", str(out)]) == cli.EXIT_REFUSED
    err = capsys.readouterr().err.strip().splitlines()
    # The marker's run named: its process and when it started.
    assert len(err) == 1 and f"already holds a run (RUNNING; the marker is the run of pid {proc.pid} started " \
        in err[0] and "--overwrite" in err[0]
    assert json.loads((out / RUNNING).read_text()) == marker
    # With --overwrite the run goes ahead (here on the in-process link, as in the other CLI tests).
    real = cli.run_plan
    monkeypatch.setattr(cli, "run_plan", lambda plan, robot, *, link, **kw: real(plan, robot, link="loopback", **kw))
    assert cli.main(["run", str(plan), "--sim", "--no-plot", "--overwrite", "--out", str(out)]) == cli.EXIT_OK
    assert json.loads((out / "results.json").read_text())["status"] == "completed"
    assert not (out / RUNNING).exists()
    # A finished run's folder is refused as well.
    assert cli.main(["run", str(plan), "--sim", "--no-plot", "--out", str(out)]) == cli.EXIT_REFUSED
    assert "already holds a run (results.json, run.csv)" in capsys.readouterr().err
