"""The experiments' command lines: a bad override (a wrong type, a value out of range, an unknown
key or name, a missing file) is one line and exit status 2 before any stage runs, an override
that changes nothing is an error, ``--help`` lists the experiment's own groups, and a good run
logs no backend probing.

Each refusal and ``--help`` is its own run of the script (its own arguments, exit status and
output), the runs of one script in one child process (its imports once, tests/_script_runs.py);
the good run, which must start JAX's backends itself, is a process of its own."""

import subprocess
import sys

import pytest
from _pipeline_helpers import ROOT
from _script_runs import run_script_cases

USAGE_EXIT = 2  # experiments/_cli.py: a configuration error
CHILD_TIMEOUT_S = 600  # one child runs all of a script's cases


def _run(script: str, *args: str, tmp_path=None) -> subprocess.CompletedProcess:
    run_dir = [f"hydra.run.dir={tmp_path}"] if tmp_path is not None else []
    return subprocess.run([sys.executable, f"experiments/{script}", *args, *run_dir],
                          cwd=ROOT, capture_output=True, text=True, timeout=300)


def _one_error_line(result: dict) -> str:
    """The single line that a configuration error prints (stdout and stderr together)."""
    lines = [line for line in result["output"].splitlines() if line.strip()]
    assert result["code"] == USAGE_EXIT, result["output"]
    assert "Traceback" not in result["output"]
    assert len(lines) == 1, lines
    assert lines[0].startswith("error: ")
    return lines[0]


BAD_OVERRIDES = [
    ("schedule.py", "sched.grasp.iterations=abc", "error: sched.grasp.iterations: expected an integer, got 'abc'"),
    ("schedule.py", "sched.nope=1", "error: sched.nope: unknown key"),
    ("schedule.py", "sched/source=nope", "Could not find 'sched/source/nope'; available: edges_csv, synthetic"),
    ("schedule.py", "sched/source=edges_csv", "error: sched.source.path: Missing mandatory value"),
    ("docking.py", "ga.population_size=abc", "error: ga.population_size: expected an integer, got 'abc'"),
    ("plan.py", "plan.budget_s=fast", "error: plan.budget_s: expected a number, got 'fast'"),
    ("surrogate.py", "sampling.nope=1", "error: sampling.nope: unknown key"),
    ("pipeline.py", "experiment=nope", "Could not find 'experiment/nope'; available: full, tiny"),
    ("pipeline.py", "stages=[schedule,fly]", "unknown stages ['fly']"),
    ("pipeline.py", "hw.plan=[1", "no viable alternative at input"),
]
BAD_VALUES = [
    ("docking.py", ["ga.mutation_rate=2.0", "ga.population_size=-8", "grid.counts=[0,0,0,0]", "n_runs=-1",
                    "dtype=float16"],
     ["ga.mutation_rate: expected a value in [0, 1], got 2.0", "ga.population_size: expected a value >= 1, got -8",
      "grid.counts: expected each a value >= 1, got [0, 0, 0, 0]", "n_runs: expected a value >= 1, got -1",
      "dtype: expected one of ['float32', 'float64'], got 'float16'"]),
    ("schedule.py", ["sched/source=edges_csv", "sched.source.path=no_such_edges.csv", "sched.solvers=[greedy,bogus]",
                     "sched.grasp.iterations=-5", "sched.timing_repeats=0"],
     ["sched.source.path: no such file 'no_such_edges.csv'",
      "sched.solvers[1]: expected one of ['greedy', 'grasp', 'astar', 'exact'], got 'bogus'",
      "sched.grasp.iterations: expected a value >= 1, got -5", "sched.timing_repeats: expected a value >= 1, got 0"]),
    # Every stage's settings are checked, also of stages that don't run.
    ("pipeline.py", ["stages=[hw]", "ga.mutation_rate=2.0", "ga.population_size=-8", "hw.plan=no_such_plan.json"],
     ["ga.mutation_rate: expected a value in [0, 1], got 2.0", "ga.population_size: expected a value >= 1, got -8",
      "hw.plan: no such file '", "no_such_plan.json'"]),
    ("pipeline.py", ["+foo=1"], ["error: foo: unknown key; known: ['baseline', 'docking',"]),
]
WEIGHTS_ON_A_MATRIX = [
    ("schedule.py", ["sched/weights=security"]),
    ("schedule.py", ["sched.weights.security=0.9"]),
    ("pipeline.py", ["stages=[schedule]", "sched/weights=speed"]),
]


def test_weights_on_metrics_run_and_log_no_backend_probing(tmp_path):
    # The same weights override on a metric source changes the costs: accepted.
    proc = _run("schedule.py", "sched/source=synthetic", "sched/weights=security", "sched.solvers=[greedy]",
                "sched.timing_repeats=1", "sched.iterations_sweep=[]", "sched.plots=false", tmp_path=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert (tmp_path / "results.json").exists()
    log = proc.stdout + proc.stderr
    assert "greedy" in log
    assert "Unable to initialize backend" not in log and "xla_bridge" not in log


def test_gather_usage_error_is_one_line():
    proc = subprocess.run([sys.executable, "experiments/gather.py"], cwd=ROOT, capture_output=True, text=True)
    lines = [line for line in proc.stderr.splitlines() if line.strip()]
    assert proc.returncode == USAGE_EXIT and len(lines) == 1 and "sweep_dir" in lines[0], proc.stderr


HELP = [
    ("docking.py", ["docking/preset: bravo7, bravo7_fast, bravo7_tables, demo, fast, full*", "ga: bravo7, paper*",
                    "scenario: cage_obstacles, thesis_cage, thesis_tables"], ["sched/weights", "surrogate:"]),
    ("schedule.py", ["sched/source: edges_csv, synthetic, thesis_matrix*", "sched/weights: equal*"],
     ["docking/preset", "ga:", "surrogate:"]),
    ("surrogate.py", ["surrogate: paper*, small"], ["sched/weights", "ga:", "docking/preset"]),
    ("plan.py", ["plan: default*", "scenario: cage_obstacles, thesis_cage*"], ["sched/weights", "ga:", "surrogate:"]),
    ("pipeline.py", ["experiment: full, tiny", "ga: bravo7*, paper", "sched/weights: equal*", "hw: default*",
                     "scenario: cage_obstacles, thesis_cage, thesis_tables*", "scenario@baseline: cage_obstacles, thesis_cage*"],
     ["docking/preset", "sched/source", "surrogate:"]),
]
# Every run of the script's command line in the child: (script, arguments) → the run's folder
# (None for --help, which writes none).
RUNS = ([(script, [override]) for script, override, _ in BAD_OVERRIDES] + [(s, o) for s, o, _ in BAD_VALUES]
        + WEIGHTS_ON_A_MATRIX + [(script, ["--help"]) for script, _, _ in HELP])


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    """``(script, *arguments) → (result, run folder)`` of every run in :data:`RUNS`, one child
    process per script."""
    out = {}
    for script in dict.fromkeys(script for script, _ in RUNS):
        keys = [(script, *args) for s, args in RUNS if s == script]
        folders = [None if args == ("--help",) else tmp_path_factory.mktemp("run") for _, *args in keys]
        cases = [[*args] + ([f"hydra.run.dir={f}"] if f else []) for (_, *args), f in zip(keys, folders)]
        report = run_script_cases(script, cases, timeout=CHILD_TIMEOUT_S)
        out.update(zip(keys, zip(report["cases"], folders)))
    return out


@pytest.mark.parametrize(("script", "override", "expected"), BAD_OVERRIDES)
def test_bad_override_is_one_line(runs, script, override, expected):
    assert expected in _one_error_line(runs[script, override][0])


# Values out of range, unknown keys, missing files, unknown names: refused with every bad key
# named in the one line, before any stage starts (no results). Several overrides per run.
@pytest.mark.parametrize(("script", "overrides", "expected"), BAD_VALUES)
def test_bad_values_are_refused_before_any_stage(runs, script, overrides, expected):
    result, folder = runs[(script, *overrides)]
    line = _one_error_line(result)
    for part in expected:
        assert part in line, line
    assert not (folder / "results.json").exists() and not (folder / "summary.md").exists()


@pytest.mark.parametrize(("script", "overrides"), WEIGHTS_ON_A_MATRIX)
def test_weights_on_a_ready_matrix_are_an_error(runs, script, overrides):
    result, folder = runs[(script, *overrides)]
    line = _one_error_line(result)
    assert f"error: {overrides[-1]}: the weights are unused with a ready cost matrix" in line
    assert not (folder / "results.json").exists()


@pytest.mark.parametrize(("script", "own", "foreign"), HELP)
def test_help_lists_own_groups_only(runs, script, own, foreign):
    result, _ = runs[script, "--help"]
    assert result["code"] == 0, result["output"]
    groups = result["output"].split("== Configuration groups ==")[1].split("== Config ==")[0]
    for line in own:
        assert line in groups, groups
    for name in foreign:
        assert name not in groups, groups
