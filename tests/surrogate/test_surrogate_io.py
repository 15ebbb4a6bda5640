"""Save/load of datasets and networks: reloaded networks predict identically."""

from __future__ import annotations

import json

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from uvms_jax.surrogate import (
    FFBN,
    RBFN,
    fit_rbfn,
    init_ffbn,
    load_dataset,
    load_network,
    save_dataset,
    save_network,
    train_ffbn_lm,
)

from _surrogate_helpers import synthetic_dataset


@pytest.fixture(scope="module")
def data():
    return synthetic_dataset(jax.random.key(0), 100)


@pytest.mark.parametrize("kind", ["ffbn", "rbfn"])
def test_reloaded_network_predicts_identically(tmp_path, data, kind):
    if kind == "ffbn":
        net, _, _ = train_ffbn_lm(init_ffbn(jax.random.key(1), 3, data), data, max_epochs=3)
    else:
        net, _ = fit_rbfn(data, spread=1.0, max_centres=7)
    npz, js = save_network(tmp_path / kind, net, note="test")
    loaded = load_network(tmp_path / kind)
    assert isinstance(loaded, FFBN if kind == "ffbn" else RBFN)
    assert (loaded.index, loaded.inputs, loaded.n_joints) == (net.index, net.inputs, net.n_joints)
    for q in (data.q, data.q.astype(jnp.float32)):
        np.testing.assert_array_equal(np.asarray(loaded.index_fn(q)), np.asarray(net.index_fn(q)))
    info = json.loads(js.read_text())
    assert info["kind"] == kind and info["note"] == "test" and info["operation_count"] == net.operation_count


def test_dataset_round_trip(tmp_path, data):
    save_dataset(tmp_path / "d2", data, seed=7)
    loaded = load_dataset(tmp_path / "d2.npz")
    for name in ("q", "x", "y"):
        np.testing.assert_array_equal(np.asarray(getattr(loaded, name)), np.asarray(getattr(data, name)))
    assert (loaded.index, loaded.inputs, loaded.sampling) == (data.index, data.inputs, data.sampling)
    assert json.loads((tmp_path / "d2.json").read_text())["seed"] == 7


def test_load_rejects_unknown_format(tmp_path, data):
    net = init_ffbn(jax.random.key(1), 2, data)
    _, js = save_network(tmp_path / "n", net)
    info = json.loads(js.read_text())
    js.write_text(json.dumps({**info, "format_version": 99}))
    with pytest.raises(ValueError, match="format version"):
        load_network(tmp_path / "n")
    with pytest.raises(TypeError):
        save_network(tmp_path / "x", object())
