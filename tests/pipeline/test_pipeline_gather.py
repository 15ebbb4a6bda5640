"""experiments/gather.py over a fake multirun folder, and over a real (small) schedule sweep."""

from __future__ import annotations

import csv
import json
import subprocess
import sys

from _pipeline_helpers import ROOT

WEIGHTS = ["equal", "speed", "security", "planning_time", "only_max_torque"]


def _fake_sweep(root, n=3, missing=()):
    for i in range(n):
        job = root / str(i)
        (job / ".hydra").mkdir(parents=True)
        (job / ".hydra" / "overrides.yaml").write_text(
            f"- sched/weights={WEIGHTS[i]}\n- seed={i}\n- hydra.job.chdir=false\n")
        if i in missing:
            continue
        (job / "results.json").write_text(json.dumps({
            "weights_name": WEIGHTS[i], "jax": "0.10.2",
            "solvers": {"exact": {"cost": 1.0 + i, "path": "0-1-9"}, "greedy": {"cost": 2.0 + i, "path": "0-1-9"}},
            "grasp_sweep": [{"iterations": 1, "cost": 3.0}], "ga_fitness": [1.5, 2.5]}))
    (root / "multirun.yaml").write_text("hydra: {}\n")


def test_flatten(gather):
    assert gather.flatten({"a": {"b": 1, "c": [1, 2.5]}, "d": [{"x": 1}], "e": None}) == {"a.b": 1, "a.c": "1;2.5", "e": None}


def test_gather_fake_sweep(gather, tmp_path):
    _fake_sweep(tmp_path, n=3, missing=(1,))
    rows, keys = gather.gather(tmp_path)
    assert keys == ["sched/weights", "seed"]  # hydra.* overrides left out
    assert [r["job"] for r in rows] == ["0", "1", "2"]
    assert [r["status"] for r in rows] == ["ok", "missing", "ok"]
    assert rows[2]["solvers.exact.cost"] == 3.0 and rows[0]["ga_fitness"] == "1.5;2.5"
    assert "grasp_sweep" not in rows[0]
    rc = gather.main([str(tmp_path), "--columns", "solvers.*.cost"])
    assert rc == 1  # a job without results is reported, not dropped
    md = (tmp_path / "gathered.md").read_text().splitlines()
    assert md[0] == "| job | status | sched/weights | seed | solvers.exact.cost | solvers.greedy.cost |"
    assert len(md) == 2 + 3
    (tmp_path / "3" / ".hydra").mkdir(parents=True)  # a fourth job with the same seed as job 0 ...
    (tmp_path / "3" / ".hydra" / "overrides.yaml").write_text("- sched/weights=speed\n- seed=0\n")
    _, md_path = gather.write(*gather.gather(tmp_path), tmp_path / "again")
    assert md_path.read_text().splitlines()[0].startswith("| job | status | sched/weights | seed |")
    with open(tmp_path / "gathered.csv") as f:
        table = list(csv.DictReader(f))
    assert len(table) == 3 and table[0]["solvers.greedy.path"] == "0-1-9" and table[1]["status"] == "missing"


def test_gather_default_columns_are_the_varying_ones(gather, tmp_path):
    _fake_sweep(tmp_path, n=3)
    assert gather.main([str(tmp_path), "--out", str(tmp_path / "g")]) == 0
    head = (tmp_path / "g" / "gathered.md").read_text().splitlines()[0]
    assert "solvers.exact.cost" in head and "weights_name" in head
    assert "jax" not in head and "solvers.exact.path" not in head  # constant across jobs


def test_gather_reports_a_broken_job_in_one_line_and_gathers_the_rest(gather, tmp_path, capsys):
    _fake_sweep(tmp_path, n=3)
    broken = tmp_path / "1" / "results.json"
    broken.write_text(broken.read_text()[:40])  # a job killed while writing (before atomic writes)
    (tmp_path / "2" / ".hydra" / "overrides.yaml").write_text("- a: &a [*a]\n")  # garbled
    assert gather.main([str(tmp_path), "--out", str(tmp_path / "g")]) == 1
    err = capsys.readouterr().err.splitlines()
    assert err[0].startswith(f"gather: {broken}: unreadable (") and err[0].endswith("; gathered as broken")
    assert err[1].startswith(f"gather: {tmp_path / '2' / '.hydra' / 'overrides.yaml'}: unreadable (")
    assert err[2].startswith("3 jobs (0 missing results, 2 broken)")
    with open(tmp_path / "g" / "gathered.csv") as f:
        rows = list(csv.DictReader(f))
    assert [r["status"] for r in rows] == ["ok", "broken", "broken"]
    assert rows[0]["solvers.exact.cost"] == "1" and rows[1]["solvers.exact.cost"] == ""


def test_gather_refuses_a_folder_without_jobs(gather, tmp_path):
    assert gather.main([str(tmp_path)]) == 2


def test_weight_sweep_multirun_and_gather(tmp_path):
    """Acceptance: a multirun of 5 weight sets → 5 result folders → one combined table (~10 s)."""
    sweep = tmp_path / "weights"
    cmd = [sys.executable, "experiments/schedule.py", "--multirun", "sched/source=synthetic",
           f"sched/weights={','.join(WEIGHTS)}", "sched.iterations_sweep=[]", "sched.timing_repeats=1",
           "sched.grasp.iterations=100", "sched.plots=false", f"hydra.sweep.dir={sweep}"]
    subprocess.run(cmd, cwd=ROOT, check=True, capture_output=True, timeout=600)
    assert sorted(p.name for p in sweep.iterdir() if p.is_dir()) == [str(i) for i in range(5)]
    out = subprocess.run([sys.executable, "experiments/gather.py", str(sweep), "--columns", "solvers.*.cost",
                          "solvers.exact.path"], cwd=ROOT, check=True, capture_output=True, text=True)
    lines = out.stdout.splitlines()
    assert lines[0].startswith("Common overrides: `sched/source=synthetic`")
    table = lines[2:]
    assert table[0] == ("| job | status | sched/weights | solvers.greedy.cost | solvers.grasp.cost | "
                        "solvers.astar.cost | solvers.exact.cost | solvers.exact.path |")
    assert len(table) == 2 + 5 and all(w in out.stdout for w in WEIGHTS)
    assert (sweep / "gathered.csv").exists()


def test_gather_reads_a_hardware_run_and_older_result_names(gather, tmp_path):
    """A job's summary is results.json whatever its stage (a hardware run's here); a folder
    written before that name was shared keeps its older one (``result.json``, hw's)."""
    for i, name in enumerate(("results.json", "result.json")):
        job = tmp_path / ("new" if i == 0 else "old") / "0"
        (job / ".hydra").mkdir(parents=True)
        (job / ".hydra" / "overrides.yaml").write_text(f"- speed_scale={0.5 + i}\n")
        (job / name).write_text(json.dumps({"status": "completed", "ok": True, "duration_s": 4.0 + i}))
        rows, keys = gather.gather(job.parent)
        assert keys == ["speed_scale"] and rows[0]["status"] == "ok" and rows[0]["duration_s"] == 4.0 + i
