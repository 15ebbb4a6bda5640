"""The Hydra scheduling experiment end to end (small settings), and its edges.csv input."""

import csv
import importlib.util
import json
from pathlib import Path

import jax
import numpy as np
import pytest
from hydra import compose, initialize_config_dir

from uvms_jax import sched

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def experiment():
    spec = importlib.util.spec_from_file_location("schedule_experiment", ROOT / "experiments" / "schedule.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def _cfg(overrides):
    with initialize_config_dir(config_dir=str(ROOT / "configs"), version_base="1.3"):
        return compose(config_name="schedule", overrides=overrides)


SMALL = ["sched.timing_repeats=2", "sched.sweep_repeats=2", "sched.iterations_sweep=[1000]"]


def test_thesis_matrix_run(experiment, tmp_path):
    res = experiment.run(_cfg(SMALL), tmp_path)
    for f in ("table.md", "table.csv", "results.json", "grasp_sweep.csv", "grasp_iterations.png",
              "route.png", "schedule_edges.json"):
        assert (tmp_path / f).stat().st_size > 0, f
    assert res["solvers"]["greedy"]["path"] == "0-2-5-4-8-0-1-6-3-7-9"
    assert res["solvers"]["astar"]["cost"] == pytest.approx(res["optimal_cost"])
    assert not res["weights_used"]
    assert json.loads((tmp_path / "results.json").read_text())["optimal_cost"] == res["optimal_cost"]


@pytest.mark.parametrize("weights", ["speed", "only_security"])
def test_weights_change_the_costs_of_metric_inputs(experiment, tmp_path, weights):
    res = experiment.run(_cfg([*SMALL, "sched/source=synthetic", f"sched/weights={weights}",
                               "sched.plots=false"]), tmp_path)
    assert res["weights_used"] and res["weights_name"] == weights
    exact = res["solvers"]["exact"]
    k = np.array([exact[f"K_{m}"] for m in sched.METRICS])
    n = np.array([exact[f"N_{m}"] for m in sched.METRICS])
    assert exact["cost"] == pytest.approx(float(k @ n))  # C_final = Σ K·N (eq. 4.16)


def test_edges_csv_input(experiment, tmp_path):
    layout = sched.thesis_problem()
    raw = sched.random_metrics(jax.random.key(3), layout)
    raw[:, :, layout.goal] = np.nan  # the planner plans into the start only (mirror_goal)
    path = tmp_path / "edges.csv"
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["planner", "src", "dst", "success", *experiment.CSV_METRICS])
        for i, j in zip(*np.nonzero(np.isfinite(raw[0]))):
            w.writerow(["RRTConnect", i, j, "true", *raw[:, i, j]])
            w.writerow(["PRM", i, j, "false", *raw[:, i, j]])
    cfg = _cfg(["sched/source=edges_csv", f"sched.source.path={path}", "sched.source.n_nodes=10"])
    problem, nm, note = experiment.load_source(cfg, [0.2] * 5)
    assert "RRTConnect" in note
    expect = sched.cost_matrix(sched.normalise_metrics(sched.mirror_goal(raw, 0, 9)), [0.2] * 5)
    np.testing.assert_allclose(problem.cost, expect, equal_nan=True)
    with pytest.raises(ValueError, match="no rows for planner 'BKPIECE'"):
        experiment.load_source(_cfg(["sched/source=edges_csv", f"sched.source.path={path}",
                                     "sched.source.planner=BKPIECE"]), [0.2] * 5)
