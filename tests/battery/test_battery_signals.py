"""SIGTERM (what batch schedulers send before they kill a job) stops a run as Ctrl-C does: the
finished work on disk, the folder's RUNNING marker saying ``interrupted`` and where, no
results.json, one line and exit 143 (SIGINT: 130); the pipeline and ``uvms-hw run`` alike."""

from __future__ import annotations

import json
import signal
import subprocess
import sys
import time

import pytest
from _battery import ROOT

from uvms_jax.files import EXIT_INTERRUPTED, EXIT_TERMINATED, RUNNING

# The pipeline in a child Python whose SIGINT raises KeyboardInterrupt, as from a terminal (a
# test worker may ignore SIGINT, and an ignored signal stays ignored across exec).
PIPELINE = ("import runpy, signal, sys; signal.signal(signal.SIGINT, signal.default_int_handler); "
            "sys.path.insert(0, 'experiments'); "
            "sys.argv = ['experiments/pipeline.py', *sys.argv[1:]]; runpy.run_path(sys.argv[0], run_name='__main__')")
START_S = 120  # imports, the arm, the simulator's start on a loaded machine
SIGNAL_TO_EXIT_S = 10.0  # the hold and the marker take well under a second


@pytest.mark.parametrize(("signum", "code"), [(signal.SIGTERM, EXIT_TERMINATED), (signal.SIGINT, EXIT_INTERRUPTED)])
def test_signal_marks_the_pipeline_run_interrupted(tmp_path, signum, code):
    out = tmp_path / "run"
    proc = subprocess.Popen([sys.executable, "-c", PIPELINE, f"hydra.run.dir={out}", "stages=[hw]", "hw.link=udp",
                             "hw.plan=examples/thesis_plan.json", "hw.plot=false"],
                            cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    _wait_started(proc, out, RUNNING, "hw")  # the hw stage has started
    t = time.monotonic()
    proc.send_signal(signum)
    output = proc.communicate(timeout=60)[0]
    assert time.monotonic() - t < SIGNAL_TO_EXIT_S
    assert proc.returncode == code, output[-3000:]
    assert "Traceback" not in output
    name = signal.Signals(signum).name
    last = [line for line in output.splitlines() if line.strip()][-1]
    assert last.startswith(f"interrupted ({name}): the partial results and the run folder's RUNNING marker")
    marker = json.loads((out / RUNNING).read_text())
    assert marker["status"] == "interrupted" and marker["stage"] == "hw", marker
    assert not (out / "results.json").exists()


def _wait_started(proc: subprocess.Popen, out, *files: str) -> None:
    deadline = time.monotonic() + START_S
    while not all((out / f).exists() for f in files):
        assert proc.poll() is None and time.monotonic() < deadline, proc.stdout.read()[-3000:]
        time.sleep(0.05)
    time.sleep(1.0)  # the arm moving (a real-time run of minutes)


def test_sigterm_is_sigint_for_uvms_hw(tmp_path):
    """uvms-hw run: SIGTERM holds the arm and writes the partial results as SIGINT does."""
    out = tmp_path / "out"
    proc = subprocess.Popen([sys.executable, "-m", "uvms_jax.hw.cli", "run", "examples/thesis_plan.json", "--sim",
                             "--no-plot", "--out", str(out)], cwd=ROOT, stdout=subprocess.PIPE,
                            stderr=subprocess.STDOUT, text=True)
    _wait_started(proc, out, RUNNING)
    proc.send_signal(signal.SIGTERM)
    output = proc.communicate(timeout=60)[0]
    assert proc.returncode == EXIT_TERMINATED, output[-3000:]
    assert "Traceback" not in output and "interrupted, arm told to hold" in output
    result = json.loads((out / "results.json").read_text())
    assert result["status"] == "interrupted" and not (out / RUNNING).exists()


def test_sigterm_handler_is_restored_and_exit_status(tmp_path):
    from uvms_jax.files import sigterm_as_interrupt

    before = signal.getsignal(signal.SIGTERM)
    with pytest.raises(KeyboardInterrupt), sigterm_as_interrupt() as terminated:
        signal.raise_signal(signal.SIGTERM)
    assert terminated() and signal.getsignal(signal.SIGTERM) is before
    assert (EXIT_INTERRUPTED, EXIT_TERMINATED) == (130, 143)

