"""A run folder that holds an earlier run is refused (exit 2, one line naming the files and the
marker's run and when it started), before Hydra writes into it: a planted rerun keeps the first
results.json byte for byte; ``--overwrite`` (or ``overwrite=true``) lets the run go on."""

from __future__ import annotations

import json
import types

import pytest
from _battery import one_line, run_cases

from uvms_jax import files
from uvms_jax.pipeline import RUN_FILES, run_pipeline

FIRST = b'{"first run": 1.2345678901234567, "stages": ["plan"]}\n'
MARKER = {"pid": 4242, "started": "2031-05-06T07:08:09+0000", "argv": ["experiments/pipeline.py", "seed=3"]}


@pytest.fixture(scope="module")
def reruns(tmp_path_factory):
    """The folders planted, and the reruns' results (one child process)."""
    tmp = tmp_path_factory.mktemp("reruns")
    done, killed, stopped, done2, killed2 = (tmp / n for n in ("done", "killed", "stopped", "done2", "killed2"))
    for folder in (done, killed, stopped, done2, killed2):
        folder.mkdir()
    for folder in (done, done2):
        (folder / "results.json").write_bytes(FIRST)
    for folder in (killed, killed2):
        (folder / files.RUNNING).write_text(json.dumps(MARKER))
    (stopped / files.RUNNING).write_text(json.dumps({**MARKER, "status": "interrupted", "stage": "hw"}))
    cases = {"done": [f"hydra.run.dir={done}"], "killed": [f"hydra.run.dir={killed}"],
             "stopped": [f"hydra.run.dir={stopped}"],
             # Past the folder check, a bad value stops the run before any stage: exit 2 for it.
             "--overwrite": [f"hydra.run.dir={done2}", "--overwrite", "stages=[fly]"],
             "overwrite=true": [f"hydra.run.dir={killed2}", "overwrite=true", "stages=[fly]"],
             "overwrite=maybe": [f"hydra.run.dir={tmp / 'fresh'}", "overwrite=maybe"]}
    results = run_cases("pipeline.py", list(cases.values()))
    return dict(zip(cases, results)), tmp


def test_finished_run_is_refused_and_kept_byte_for_byte(reruns):
    results, tmp = reruns
    line = one_line(results["done"])
    assert line == f"error: {tmp / 'done'} already holds a run (results.json): choose another hydra.run.dir or " \
                   "pass --overwrite"
    assert (tmp / "done" / "results.json").read_bytes() == FIRST
    assert sorted(p.name for p in (tmp / "done").iterdir()) == ["results.json"]  # Hydra wrote nothing either


@pytest.mark.parametrize(("case", "status"), [("killed", "no status (killed?)"), ("stopped", "interrupted in stage hw")])
def test_stale_marker_is_refused_naming_its_run(reruns, case, status):
    results, tmp = reruns
    line = one_line(results[case])
    assert "already holds a run (RUNNING; the marker is the run of pid 4242 started 2031-05-06T07:08:09+0000 " \
           f"(`experiments/pipeline.py seed=3`), {status}): choose another hydra.run.dir or pass --overwrite" in line
    assert json.loads((tmp / case / files.RUNNING).read_text())["pid"] == 4242  # untouched


@pytest.mark.parametrize("case", ["--overwrite", "overwrite=true"])
def test_overwrite_passes_the_folder_check(reruns, case):
    line = one_line(reruns[0][case])
    assert "error: PipelineSettings: unknown stages ['fly']" in line


def test_overwrite_takes_true_or_false(reruns):
    assert one_line(reruns[0]["overwrite=maybe"]) == "error: overwrite: expected true/false, got 'maybe'"


def test_run_pipeline_refuses_a_used_folder_in_process(tmp_path):
    settings = types.SimpleNamespace(stages=(), scenario=None)
    for name in RUN_FILES:
        folder = tmp_path / name
        folder.mkdir()
        (folder / name).write_bytes(FIRST)
        with pytest.raises(files.UsedFolderError, match=f"already holds a run \\({name}"):
            run_pipeline(settings, folder)
        assert (folder / name).read_bytes() == FIRST
        assert sorted(p.name for p in folder.iterdir()) == [name]
