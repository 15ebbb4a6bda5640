"""A solver added from outside the package runs through the stage, its settings, its tables
and its plots: the registry is the one place a solver is named."""

import time

import jax
import numpy as np
import pytest

from tests.sched._sched_bruteforce import brute_force_optimum
from uvms_jax import sched
from uvms_jax.settings import from_mapping


def _brute(key, problem, grasp_kwargs) -> sched.Schedule:
    """Enumerates every feasible schedule (the tests' oracle) and returns the cheapest."""
    t0 = time.perf_counter()
    cost = np.asarray(problem.cost, dtype=np.float64).tolist()
    best, paths, _ = brute_force_optimum(cost, problem.compat, problem.start, problem.goal)
    return sched.Schedule(tuple(paths[0]), float(best), time.perf_counter() - t0, "brute")


@pytest.fixture
def brute():
    solver = sched.register_solver("brute", _brute, label="brute force", line="m-.")
    yield solver
    sched.SOLVERS.pop("brute")


def test_registered_solver_runs_in_the_stage(brute, tmp_path):
    settings = from_mapping(sched.SchedSettings, {"solvers": ["greedy", "exact", "brute"], "timing_repeats": 1,
                                                  "iterations_sweep": [5], "sweep_repeats": 1})
    run = sched.run_schedule(jax.random.key(0), settings)
    assert set(run.solved) == {"greedy", "exact", "brute"}
    assert run.solved["brute"].cost == pytest.approx(run.optimal_cost, rel=1e-12)  # both optimal
    sched.write_schedule(run, tmp_path)
    assert "brute" in (tmp_path / "table.md").read_text()
    assert (tmp_path / "grasp_iterations.png").stat().st_size > 0


def test_registry_refuses_clashes_and_unknown_names(brute):
    with pytest.raises(ValueError, match="already registered"):
        sched.register_solver("brute", _brute)
    with pytest.raises(ValueError, match="identifier"):
        sched.register_solver("not a name", _brute)
    with pytest.raises(ValueError, match="solvers.*'brute'"):
        from_mapping(sched.SchedSettings, {"solvers": ["bruteforce"]})
