"""The scheduling stage end to end (small settings): package functions, its edges.csv input,
and the Hydra entry point as a subprocess."""

import csv
import dataclasses
import json
import os
import subprocess
import sys
from pathlib import Path

import jax
import numpy as np
import pytest
from hydra import compose, initialize_config_dir
from omegaconf import OmegaConf

from uvms_jax import sched
from uvms_jax.settings import from_mapping

ROOT = Path(__file__).resolve().parents[2]
SMALL = ["sched.timing_repeats=2", "sched.sweep_repeats=2", "sched.iterations_sweep=[1000]"]


def _settings(overrides) -> sched.SchedSettings:
    """The settings the experiment builds from configs/schedule.yaml with ``overrides``."""
    with initialize_config_dir(config_dir=str(ROOT / "configs"), version_base="1.3"):
        cfg = compose(config_name="schedule", overrides=overrides)
    return from_mapping(sched.SchedSettings, OmegaConf.to_container(cfg.sched, resolve=True))


def test_config_defaults_are_the_settings_defaults():
    assert _settings([]) == sched.SchedSettings()


def test_thesis_matrix_run(tmp_path):
    run = sched.run_schedule(jax.random.key(0), _settings(SMALL))
    res = sched.write_schedule(run, tmp_path)
    for f in ("table.md", "table.csv", "results.json", "grasp_sweep.csv", "grasp_iterations.png",
              "route.png", "schedule_edges.json"):
        assert (tmp_path / f).stat().st_size > 0, f
    assert res["solvers"]["greedy"]["path"] == "0-2-5-4-8-0-1-6-3-7-9"
    assert res["solvers"]["astar"]["cost"] == pytest.approx(res["optimal_cost"])
    assert not res["weights_used"] and not run.weights_used
    assert json.loads((tmp_path / "results.json").read_text())["optimal_cost"] == res["optimal_cost"]
    assert run.best.cost == pytest.approx(run.optimal_cost)


@pytest.mark.parametrize("weights", ["speed", "only_security"])
def test_weights_change_the_costs_of_metric_inputs(tmp_path, weights):
    s = _settings([*SMALL, "sched/source=synthetic", f"sched/weights={weights}", "sched.plots=false"])
    res = sched.write_schedule(sched.run_schedule(jax.random.key(0), s), tmp_path, plots=s.plots)
    assert res["weights_used"] and res["weights_name"] == weights
    assert not (tmp_path / "route.png").exists()
    exact = res["solvers"]["exact"]
    k = np.array([exact[f"K_{m}"] for m in sched.METRICS])
    n = np.array([exact[f"N_{m}"] for m in sched.METRICS])
    assert exact["cost"] == pytest.approx(float(k @ n))  # C_final = Σ K·N (eq. 4.16)


def _edges_csv(path: Path) -> np.ndarray:
    layout = sched.thesis_problem()
    raw = sched.random_metrics(jax.random.key(3), layout)
    raw[:, :, layout.goal] = np.nan  # the planner plans into the start only (mirror_goal)
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["planner", "src", "dst", "success", *sched.EDGE_CSV_COLUMNS])
        for i, j in zip(*np.nonzero(np.isfinite(raw[0]))):
            w.writerow(["RRTConnect", i, j, "true", *raw[:, i, j]])
            w.writerow(["PRM", i, j, "false", *raw[:, i, j]])
    return raw


def test_edges_csv_input(tmp_path):
    path = tmp_path / "edges.csv"
    raw = _edges_csv(path)
    s = _settings(["sched/source=edges_csv", f"sched.source.path={path}", "sched.source.n_nodes=10"])
    problem, nm, note = sched.load_source(s.source, [0.2] * 5)
    assert "RRTConnect" in note
    expect = sched.cost_matrix(sched.normalise_metrics(sched.mirror_goal(raw, 0, 9)), [0.2] * 5)
    np.testing.assert_allclose(problem.cost, expect, equal_nan=True)
    # the same metrics in memory give the same problem
    in_memory, nm2 = sched.problem_from_metrics(raw, None, 0, None, [0.2] * 5, True)
    np.testing.assert_array_equal(in_memory.cost, problem.cost)
    np.testing.assert_array_equal(nm2, nm)
    # relative paths start from root
    rel = dataclasses.replace(s.source, path="edges.csv")
    np.testing.assert_array_equal(sched.load_source(rel, [0.2] * 5, root=tmp_path).problem.cost, problem.cost)
    with pytest.raises(ValueError, match="no rows for planner 'BKPIECE'"):
        sched.load_source(dataclasses.replace(s.source, planner="BKPIECE"), [0.2] * 5)


def test_run_on_metrics_in_memory():
    raw = sched.random_metrics(jax.random.key(3), sched.thesis_problem())
    s = dataclasses.replace(_settings(SMALL), iterations_sweep=(), solvers=("greedy", "exact"), timing_repeats=1)
    run = sched.run_schedule(jax.random.key(0), s, raw, note="plan stage")
    assert run.weights_used and run.note == "plan stage" and run.sweep == ()
    assert set(run.solved) == {"greedy", "exact"} and run.best.cost == run.optimal_cost


def test_solve_by_name():
    p, key = sched.thesis_problem(), jax.random.key(0)
    assert sched.solve(key, p, "greedy").path == sched.THESIS_EQ41_GREEDY_PATH
    assert sched.solve(key, p, "grasp", sched.GraspSettings(iterations=50)).info["iterations"] == 50
    with pytest.raises(ValueError, match="unknown solver 'dijkstra'.*greedy"):
        sched.solve(key, p, "dijkstra")
    with pytest.raises(ValueError, match="unknown solver"):
        sched.solve_all(key, p, sched.SchedSettings(solvers=("greedy", "dijkstra")))


def test_hydra_entry_point(tmp_path):
    out = tmp_path / "run"
    env = {**os.environ, "JAX_PLATFORMS": "cpu"}
    cmd = [sys.executable, str(ROOT / "experiments" / "schedule.py"), f"hydra.run.dir={out}",
           "sched.solvers=[greedy,exact]", "sched.timing_repeats=1", "sched.iterations_sweep=[]",
           "sched.plots=false"]
    subprocess.run(cmd, check=True, cwd=tmp_path, env=env, capture_output=True)
    res = json.loads((out / "results.json").read_text())
    assert res["solvers"]["greedy"]["path"] == "0-2-5-4-8-0-1-6-3-7-9"
    assert sorted(p.name for p in out.iterdir() if p.suffix != ".log") == [
        ".hydra", "results.json", "schedule_edges.json", "table.csv", "table.md"]
