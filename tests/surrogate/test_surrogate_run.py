"""The surrogate stage: settings mirror the config, run_surrogates + write_surrogates, acceptance."""

from __future__ import annotations

import json
import math
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from omegaconf import OmegaConf

from uvms_jax import kin, surrogate
from uvms_jax.settings import SettingsError, from_mapping

CONFIGS = Path(__file__).resolve().parents[2] / "configs"
# Degrees → radians through math.radians vs a product with π/180: rounding only.
ANGLE_ATOL = 1e-15


def _config(*groups: str) -> dict:
    """configs/surrogate.yaml merged with ``configs/surrogate/<group>.yaml`` (as Hydra composes them)."""
    cfg = OmegaConf.load(CONFIGS / "surrogate.yaml")
    for g in groups:
        cfg = OmegaConf.merge(cfg, OmegaConf.load(CONFIGS / "surrogate" / f"{g}.yaml"))
    cfg.pop("hydra")  # Hydra's own node (run folders), not the experiment's
    d = OmegaConf.to_container(cfg, resolve=True)
    d.pop("defaults")
    return d


def test_settings_defaults_equal_the_paper_config():
    assert from_mapping(surrogate.SurrogateSettings, _config("paper")) == surrogate.SurrogateSettings()


def test_settings_of_the_small_config_and_their_dict_mirror_the_yaml():
    d = _config("small")
    s = from_mapping(surrogate.SurrogateSettings, d)
    assert s.data.n_train["kci"] == 1500 and s.rbfn.max_centres["w"] == 150 and s.timing.batches == (1000, 100000)
    assert json.loads(json.dumps(s.to_dict())) == d  # the report's "config" is the config


def test_sampling_settings_convert_degrees_to_the_default_sampling():
    got, want = surrogate.SamplingSettings().to_sampling(), surrogate.Sampling()
    assert (got.mode, got.continuous) == (want.mode, want.continuous)
    for name in ("task_point", "r_min", "r_max", "phi", "heading", "nominal_arm", "half_range", "step"):
        np.testing.assert_allclose(getattr(got, name), getattr(want, name), atol=ANGLE_ATOL, err_msg=name)


@pytest.mark.parametrize(
    "mapping, match",
    [
        ({"networks": ["ffbn_x"]}, "unknown network"),
        ({"networks": ["ffbn_w", "ffbn_w"]}, "twice"),
        ({"networks": []}, "at least one"),
        ({"train_dtype": "float16"}, "train_dtype"),
        ({"ffbn": {"trainer": "sgd"}}, "trainer"),
        ({"data": {"n_train": {"w": 0, "kci": 10}}}, "w: expected a value >= 1"),
        ({"data": {"n_train": {"w": 10}}}, "kci"),
        ({"rbfn": {"target_mse": {"w": -1.0, "kci": 1e-6}}}, r"w: expected a value in \(0, inf\)"),
        ({"sampling": {"r_min": 2.0}}, "r_min"),
        ({"timing": {"batches": []}}, "batches"),
        ({"timing": {"spare": 1}}, "unknown keys"),
    ],
)
def test_bad_settings_raise_naming_the_problem(mapping, match):
    with pytest.raises((ValueError, SettingsError), match=match):
        from_mapping(surrogate.SurrogateSettings, mapping)


def test_index_values_reject_unknown_indices():
    with pytest.raises(KeyError, match="unknown index"):
        surrogate.IndexInts(w=1, kci=2)["theta"]


def test_tile_batch_and_chunk_for():
    q = jnp.arange(6.0, dtype=jnp.float64).reshape(3, 2)
    b = surrogate.tile_batch(q, 7)
    assert b.shape == (7, 2) and b.dtype == jnp.float32
    np.testing.assert_array_equal(np.asarray(b[3:6]), np.asarray(q, np.float32))
    assert surrogate.chunk_for(200, 100) == 100
    assert surrogate.chunk_for(100, 100) is None and surrogate.chunk_for(150, 100) is None
    with pytest.raises(ValueError, match="positive"):
        surrogate.tile_batch(q, 0)


def test_time_index_fn_times_calls_back_to_back():
    """A call much shorter than a timed run (about a millisecond against 0.2 s) is repeated in each
    run and the time divided by the calls: the function runs more than once per run, besides
    the compile and the probe."""
    calls = []
    fn = lambda q: (jax.debug.callback(lambda: calls.append(1)), q.sum(-1))[1]
    t = surrogate.time_index_fn(fn, jnp.ones((100, 3)), repeats=2, min_run_seconds=0.2)
    assert len(calls) > 2 + 2 * 1
    assert t["per_second"] == pytest.approx(100 / t["seconds"])
    assert 0 < t["min_seconds"] <= t["seconds"]
    with pytest.raises(ValueError, match="multiple"):
        surrogate.time_index_fn(fn, jnp.ones((100, 3)), chunk=30)


def _timing(speedup: float) -> dict:
    return {"100000": {"speedup": speedup}}


def test_acceptance_figures():
    s = surrogate.SurrogateSettings()
    nets = {
        "ffbn_w": {"max_rel_test_error": 0.01, "hidden_units": 8, "design_seconds": 10.0, "timing": _timing(6.0)},
        "ffbn_kci": {"max_rel_test_error": 0.03, "hidden_units": 25, "design_seconds": 1.0, "timing": _timing(10.0)},
        "rbfn_w": {"max_rel_test_error": 0.019},
    }
    acc = surrogate.acceptance_figures(nets, s)
    assert acc == {"ffbn_w_error_ok": True, "ffbn_w_design_seconds": 10.0, "ffbn_w_design_time_ok": True,
                   "ffbn_kci_error_ok": False, "rbfn_w_error_ok": True,
                   "ffbn_w_speedup_at_1e5": 6.0, "ffbn_w_speedup_ok": True,
                   "ffbn_kci_speedup_at_1e5": 10.0, "ffbn_kci_speedup_ok": False}
    assert surrogate.acceptance_figures({}, s) == {}


def test_float64_training_without_x64_is_refused():
    s = surrogate.SurrogateSettings(networks=("ffbn_w",))
    with jax.enable_x64(False), pytest.raises(ValueError, match="jax_enable_x64"):
        surrogate.run_surrogates(jax.random.key(0), kin.uvms12(), s)


TINY = {
    "networks": ["ffbn_w", "rbfn_w"],
    "data": {"n_train": {"w": 60, "kci": 60}, "n_test": 20},
    "ffbn": {"max_hidden": {"w": 2, "kci": 2}, "max_epochs": 5},
    "rbfn": {"spread_start": 4.0, "spread_step": 3.0, "spread_max": 7.0, "max_centres": {"w": 10, "kci": 10}},
    "timing": {"batches": [40, 80], "repeats": 1, "chunk": 40},
}


# The run compiles the UVMS kinematics (tens of seconds on a loaded 2-core CPU): slow tests.
@pytest.fixture(scope="module")
def tiny_run():
    settings = from_mapping(surrogate.SurrogateSettings, TINY)
    return surrogate.run_surrogates(jax.random.key(0), kin.uvms12(), settings)


@pytest.mark.slow
def test_run_surrogates_fills_the_report(tiny_run):
    run = tiny_run
    assert list(run.sets) == ["w"] and list(run.designs) == ["ffbn_w", "rbfn_w"]
    train, test = run.sets["w"]
    assert (len(train), len(test)) == (60, 20) and train.y.dtype == jnp.float64
    assert list(run.report) == ["device", "error_metric", "timing_note", "datasets", "analytic", "networks",
                                "config", "acceptance"]
    f, r = run.networks["ffbn_w"], run.networks["rbfn_w"]
    assert f["kind"] == "ffbn" and f["spread"] is None and f["hidden_units"] == run.designs["ffbn_w"].network.hidden
    assert r["kind"] == "rbfn" and r["spread"] in (4.0, 7.0) and r["hidden_units"] <= 10
    for n in (f, r):
        assert math.isfinite(n["max_rel_test_error"]) and n["operation_count"] > 0
        assert list(n["timing"]) == ["40", "80"]
        assert n["timing"]["40"]["chunk"] is None and n["timing"]["80"]["chunk"] == 40
        assert n["timing"]["80"]["analytic_s"] == run.analytic["w"]["timing"]["80"]["seconds"]
    assert set(run.acceptance) == {"ffbn_w_error_ok", "ffbn_w_design_seconds", "ffbn_w_design_time_ok",
                                   "rbfn_w_error_ok"}
    # The error in the report is the network's error on the test set (eq. 21).
    net = run.designs["ffbn_w"].network
    err = float(surrogate.max_relative_error(test.y, net.predict(test.x)))
    assert f["max_rel_test_error"] == pytest.approx(err, rel=1e-12)


@pytest.mark.slow
def test_write_surrogates_writes_the_files(tiny_run, tmp_path):
    report_path = surrogate.write_surrogates(tiny_run, tmp_path)
    files = sorted(str(p.relative_to(tmp_path)) for p in tmp_path.rglob("*") if p.is_file())
    assert files == sorted([
        "results.json", "training.png", "ffbn_w_design.png", "rbfn_w_design.png",
        "data/d2_train.npz", "data/d2_train.json", "data/d2_test.npz", "data/d2_test.json",
        "networks/ffbn_w.npz", "networks/ffbn_w.json", "networks/rbfn_w.npz", "networks/rbfn_w.json",
    ])
    report = json.loads(report_path.read_text())
    assert report["config"] == json.loads(json.dumps(tiny_run.settings.to_dict()))
    assert report["networks"]["rbfn_w"]["hidden_units"] == tiny_run.networks["rbfn_w"]["hidden_units"]
    meta = json.loads((tmp_path / "data" / "d2_train.json").read_text())
    assert meta["seed"] == 0 and meta["chain"] == kin.uvms12().name
    test = tiny_run.sets["w"][1]
    net = surrogate.load_network(tmp_path / "networks" / "ffbn_w")
    np.testing.assert_array_equal(np.asarray(net.index_fn(test.q)),
                                  np.asarray(tiny_run.designs["ffbn_w"].network.index_fn(test.q)))
