"""Save and load surrogate networks: ``<path>.npz`` (arrays, exact dtype) + ``<path>.json`` (metadata).

A reloaded network holds bit-identical arrays, so it predicts identically.
"""

from __future__ import annotations

import json
from pathlib import Path

import jax.numpy as jnp
import numpy as np
from flax import traverse_util

from uvms_jax.files import atomic_path, write_json
from uvms_jax.surrogate._ffbn import FFBN
from uvms_jax.surrogate._rbfn import RBFN
from uvms_jax.surrogate._scaler import Scaler

FORMAT_VERSION = 1
_SEP = "/"


def _scaler_arrays(prefix: str, s: Scaler) -> dict:
    return {f"{prefix}/offset": np.asarray(s.offset), f"{prefix}/scale": np.asarray(s.scale)}


def _scaler(arrays: dict, prefix: str) -> Scaler:
    return Scaler(offset=arrays[f"{prefix}/offset"], scale=arrays[f"{prefix}/scale"])


def save_network(path, net: FFBN | RBFN, **meta) -> tuple[Path, Path]:
    """Write ``net`` to ``<path>.npz`` and ``<path>.json`` (``meta`` is added to the JSON)."""
    if not isinstance(net, (FFBN, RBFN)):
        raise TypeError(f"expected an FFBN or RBFN, got {type(net).__name__}")
    path = Path(path).with_suffix("")
    path.parent.mkdir(parents=True, exist_ok=True)
    arrays = {**_scaler_arrays("x_norm", net.x_norm), **_scaler_arrays("y_norm", net.y_norm)}
    if isinstance(net, FFBN):
        kind, size = "ffbn", {"hidden": net.hidden}
        flat = traverse_util.flatten_dict(net.params, sep=_SEP)
        arrays.update({f"params/{k}": np.asarray(v) for k, v in flat.items()})
    else:
        kind, size = "rbfn", {"n_centres": net.n_centres, "spread": float(net.spread)}
        arrays.update({k: np.asarray(getattr(net, k)) for k in ("centres", "weights", "bias", "spread")})
    with atomic_path(path.with_suffix(".npz")) as tmp, tmp.open("wb") as f:
        np.savez(f, **arrays)
    info = {"format_version": FORMAT_VERSION, "kind": kind, "index": net.index, "inputs": list(net.inputs),
            "n_joints": net.n_joints, "operation_count": net.operation_count, **size, **meta}
    write_json(path.with_suffix(".json"), info)
    return path.with_suffix(".npz"), path.with_suffix(".json")


def load_network(path) -> FFBN | RBFN:
    """Read a network written by :func:`save_network`."""
    path = Path(path).with_suffix("")
    info = json.loads(path.with_suffix(".json").read_text())
    if info.get("format_version") != FORMAT_VERSION:
        raise ValueError(f"{path}: unsupported format version {info.get('format_version')}")
    with np.load(path.with_suffix(".npz")) as data:
        arrays = {k: jnp.asarray(data[k]) for k in data.files}
    common = dict(x_norm=_scaler(arrays, "x_norm"), y_norm=_scaler(arrays, "y_norm"), index=info["index"],
                  inputs=tuple(info["inputs"]), n_joints=int(info["n_joints"]))
    if info["kind"] == "ffbn":
        flat = {k[len("params/"):]: v for k, v in arrays.items() if k.startswith("params/")}
        return FFBN(params=traverse_util.unflatten_dict(flat, sep=_SEP), **common)
    if info["kind"] == "rbfn":
        return RBFN(centres=arrays["centres"], weights=arrays["weights"], bias=arrays["bias"],
                    spread=arrays["spread"], **common)
    raise ValueError(f"{path}: unknown network kind {info['kind']!r}")
