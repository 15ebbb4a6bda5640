"""A pipeline run folder says when its run did not finish: the RUNNING marker while it runs (and
after a kill), rewritten with the status when a stage raises or Ctrl-C arrives, no results.json
then; results written atomically (uvms_jax.files)."""

from __future__ import annotations

import json
import types

import pytest

from uvms_jax import files
from uvms_jax.pipeline import _run
from uvms_jax.pipeline._report import StageReport


def _stage(name, seen, fail=None):
    def fn(settings, out, flow):
        seen.append((name, (out.parent / files.RUNNING).exists()))  # the marker while it runs
        if fail is not None:
            raise fail
        return StageReport(name, name.title(), results={"value": len(seen)})
    return fn


@pytest.fixture
def two_stages(monkeypatch):
    """Two cheap stages ``one``, ``two`` in place of the real ones; returns a function that sets
    what stage ``two`` raises (None: nothing) and the list of stage calls."""
    seen = []

    def setup(fail=None):
        monkeypatch.setattr(_run, "STAGES", ("one", "two"))
        monkeypatch.setattr(_run, "STAGE_FNS", {"one": _stage("one", seen), "two": _stage("two", seen, fail)})
        return types.SimpleNamespace(stages=("one", "two"), scenario=None), seen
    return setup


def test_finished_run_has_results_and_no_marker(tmp_path, two_stages):
    settings, seen = two_stages()
    (tmp_path / "results.json").write_text('{"stale": true}')  # an earlier run's, overwritten
    res = _run.run_pipeline(settings, tmp_path, overwrite=True)
    assert seen == [("one", True), ("two", True)]
    assert not (tmp_path / files.RUNNING).exists()
    assert json.loads((tmp_path / "results.json").read_text())["two"] == res["two"] == {"value": 2}
    assert (tmp_path / "summary.md").read_text().startswith("# uvms_jax pipeline run")
    assert not list(tmp_path.glob(".*.tmp"))  # no temporary files left


@pytest.mark.parametrize(("fail", "status"), [(KeyboardInterrupt(), "interrupted"),
                                              (RuntimeError("solver diverged"), "failed")])
def test_stopped_run_keeps_a_marker_with_its_status(tmp_path, two_stages, fail, status):
    settings, _ = two_stages(fail)
    (tmp_path / "results.json").write_text('{"stale": true}')  # must not stand for this run
    with pytest.raises(type(fail)):
        _run.run_pipeline(settings, tmp_path, overwrite=True)
    marker = json.loads((tmp_path / files.RUNNING).read_text())
    assert marker["status"] == status and marker["stage"] == "two"
    assert marker["finished"] == {"one": {"value": 1}}  # the finished stage's results kept
    assert type(fail).__name__ in marker["error"]
    assert not (tmp_path / "results.json").exists() and not (tmp_path / "summary.md").exists()


def test_write_atomic_leaves_the_old_file_when_writing_fails(tmp_path):
    path = files.write_atomic(tmp_path / "r.json", '{"a": 1}')
    assert path.read_text() == '{"a": 1}'
    with pytest.raises(RuntimeError), files.atomic_path(path) as tmp:
        tmp.write_text('{"a": 2, "trunc')
        raise RuntimeError("killed mid-write")
    assert path.read_text() == '{"a": 1}'  # the old file, whole
    assert [p.name for p in tmp_path.iterdir()] == ["r.json"]  # the temporary file removed
    files.write_atomic(path, b"\x00\x01")
    assert path.read_bytes() == b"\x00\x01" and oct(path.stat().st_mode & 0o777) == "0o644"
