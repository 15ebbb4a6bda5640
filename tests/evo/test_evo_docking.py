"""The docking stage: settings from the composed config, and a tiny end-to-end run (slow)."""

import json
from pathlib import Path

import pytest
from hydra import compose, initialize_config_dir
from omegaconf import OmegaConf

from uvms_jax import evo
from uvms_jax.settings import SettingsError, from_mapping

CONFIGS = str(Path(__file__).resolve().parents[2] / "configs")


def _composed(*overrides) -> dict:
    with initialize_config_dir(config_dir=CONFIGS, version_base="1.3"):
        return OmegaConf.to_container(compose(config_name="docking", overrides=list(overrides)), resolve=True)


def test_settings_defaults_equal_the_full_config():
    assert from_mapping(evo.DockingSettings, _composed()) == evo.DockingSettings()


def test_settings_reject_unknown_keys():
    with pytest.raises(SettingsError, match="unknown keys"):
        from_mapping(evo.DockingSettings, {"ga": {"population": 10}})


@pytest.mark.slow
def test_tiny_run_writes_every_file(tmp_path):
    s = from_mapping(evo.DockingSettings, _composed(
        "docking/preset=fast", "n_runs=2", "grid.counts=[5,5,2,4]", "grid.refine_stages=1",
        "wmax.n_per_side=5", "ga.population_size=12", "ga.max_generations=5", "cmaes.n_runs=2",
        "cmaes.generations=3"))
    run = evo.run_docking(s)
    assert run.poses.shape == (2, 4) and run.fitness.shape == (2,) and len(run.histories) == 2
    assert run.refined_grid.fitness >= run.grid.fitness
    summary = evo.write_docking(run, tmp_path)
    names = {"runs.csv", "grid_optimum.json", "cmaes.json", "wmax.json", "wmax_best.png", "convergence.png",
             "results.json"}
    assert names <= {p.name for p in tmp_path.iterdir()}
    assert json.loads((tmp_path / "results.json").read_text())["ga_fitness"] == summary["ga_fitness"]
    # A dense grid (one polish start) is a reference: the GA's best against it certifies.
    c = summary["certificate"]
    assert c["reference"]["fitness"] == run.refined_grid.fitness and c["reference"]["search"] == "dense grid + zoom"
    assert c["ga_best_ratio"] == pytest.approx(float(run.fitness.max()) / run.refined_grid.fitness)
    assert c["ga_certified"] == (c["ga_best_ratio"] >= s.accept_ratio)


def test_multistart_search_and_the_runs_best_pose():
    """A shifted lattice polished from 3 distinct starts: never below its lattice, and the run's
    best pose is the better of the GA runs' and the search's, scored again by the problem."""
    # Chunks of 81 points: the lattice's 128 and each zoom stage's 81 per start are evaluated
    # by one compiled fitness (a chunk shape of their own each otherwise).
    s = from_mapping(evo.DockingSettings, _composed(
        "docking/preset=fast", "n_runs=2", "grid.counts=[4,4,2,4]", "grid.shift=true", "grid.refine_starts=3",
        "grid.refine_stages=2", "grid.refine_counts=[3,3,3,3]", "grid.chunk_size=81", "wmax.n_per_side=3",
        "ga.population_size=8", "ga.max_generations=3", "cmaes.enabled=false", "time_single_runs=false"))
    run = evo.run_docking(s)
    assert run.refined_grid.fitness >= run.grid.fitness
    assert run.refined_grid.candidates in (2 * 81, 2 * 2 * 81, 2 * 3 * 81)  # stages × starts found × 3^4
    best = run.best
    assert best.fitness == pytest.approx(max(run.refined_grid.fitness, float(run.fitness.max())))
    assert best.source == ("grid search" if run.refined_grid.fitness > run.fitness.max() else "analytic GA")
    # Scored again in a batch of one: measured bit-identical to a batch of 64 (float64) under
    # XLA's default, AVX and SSE4.2 ISAs; 1e-5 allows a float32 problem's reassociated sums.
    assert float(evo.evaluate(run.problem, best.pose[None]).fitness[0]) == pytest.approx(best.fitness, rel=1e-5)
    assert evo.docking_summary(run)["certificate"]["ga_certified"] is None  # a multistart search is no reference
