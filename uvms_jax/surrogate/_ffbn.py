"""Feed-forward back-propagation network (FFBN; dexterity paper §3.2, eqs. 13–16).

One hidden layer of ``tanh`` units and a linear output unit (a flax ``linen`` MLP), wrapped
with min–max normalisation of inputs and output to [−1, 1]:

    S = y⁻¹( W2ᵀ tanh(W1ᵀ x̃ + b1) + b2 ),   x̃ = (x − x_offset) · x_scale.

Training works on the normalised form; evaluation folds both scalers into the layers
(:func:`folded_layers`) and writes the network out as scalar multiply-adds, one per weight,
over whole columns of the batch: for a few units on a few inputs that is one elementwise loop
over the batch, which reads each configuration once, with no gathered copy of the inputs and
no small matrix products.
"""

from __future__ import annotations

from functools import partial
from typing import Any

import flax.linen as nn
import jax
import jax.numpy as jnp
from flax import struct
from jax import Array

from uvms_jax.surrogate._adam import fit_adam
from uvms_jax.surrogate._dataset import Dataset
from uvms_jax.surrogate._inputs import JointInputs
from uvms_jax.surrogate._lm import LMHyperParams, LMState, fit_lm
from uvms_jax.surrogate._scaler import fit_scaler

# Operation counts in the paper's convention (Table 4, Appendix A): additions and
# multiplications cost 1 each, exp costs one multiplication, tanh = (e^γ − e^−γ)/(e^γ + e^−γ)
# costs 7 (2 exp, 2 add, 1 div + 2 for the negated exponent). Reproduces the paper's 184
# (w: 8 hidden, 7 inputs) and 775 (KCI: 25 hidden, 11 inputs).
TANH_OPS = 7


class MLP(nn.Module):
    """``tanh`` hidden layer of ``hidden`` units, linear scalar output; ``(..., d) → (...)``."""

    hidden: int

    @nn.compact
    def __call__(self, x: Array) -> Array:
        h = jnp.tanh(nn.Dense(self.hidden, name="hidden", param_dtype=x.dtype)(x))
        return nn.Dense(1, name="output", param_dtype=x.dtype)(h)[..., 0]


def mlp_apply(params: Any, x: Array) -> Array:
    """Apply the MLP whose parameters are ``params`` (hidden size read from their shapes)."""
    return MLP(params["hidden"]["kernel"].shape[-1]).apply({"params": params}, x)


@struct.dataclass
class FFBN(JointInputs):
    """A trained (or initialised) FFBN surrogate of one index.

    Attributes:
      params: flax parameters ``{"hidden": {kernel (d, H), bias (H,)}, "output": {kernel (H, 1), bias (1,)}}``
        acting on normalised inputs/outputs.
      x_norm, y_norm, index, inputs, n_joints: see :class:`JointInputs`.
    """

    params: Any

    @property
    def hidden(self) -> int:
        """Number of hidden neurons H."""
        return int(self.params["hidden"]["kernel"].shape[-1])

    @property
    def operation_count(self) -> int:
        """Additions + multiplications per evaluation, paper convention: ``H (2d + 2 + 7)``."""
        return self.hidden * (2 * self.n_inputs + 2 + TANH_OPS)

    def predict(self, x: Array) -> Array:
        """Index estimate for network inputs ``x: (..., d)`` → ``(...)``, in the dtype of ``x``.

        Raises:
          ValueError: ``x``'s last axis is not ``d`` long.
        """
        return _evaluate(self, self._checked_inputs(x), tuple(range(self.n_inputs)))

    def _from_joints(self, q: Array) -> Array:
        return _evaluate(self, q, self.inputs)


def folded_layers(net: FFBN) -> tuple[Array, Array, Array, Array]:
    """The network on unscaled inputs and outputs, ``S(x) = v · tanh(Aᵀ x + c) + d``.

    The input scaler's affine map folds into the hidden layer and the output scaler's into the
    output layer (exact algebra; only round-off differs from the normalised form).

    Returns:
      ``A: (d, H)`` [1/joint unit], ``c: (H,)``, ``v: (H,)`` and ``d: ()`` [index units].
    """
    (W1, b1), (W2, b2) = ((net.params[k]["kernel"], net.params[k]["bias"]) for k in ("hidden", "output"))
    x_scale, x_offset = jnp.broadcast_to(net.x_norm.scale, W1.shape[:1]), jnp.broadcast_to(net.x_norm.offset, W1.shape[:1])
    A = x_scale[:, None] * W1
    c = b1 - (x_offset * x_scale) @ W1
    v = W2[:, 0] / net.y_norm.scale
    return A, c, v, b2[0] / net.y_norm.scale + net.y_norm.offset


@partial(jax.jit, static_argnames="columns")
def _evaluate(net: FFBN, x: Array, columns: tuple[int, ...]) -> Array:
    """``S`` at ``x: (..., m)`` whose entries ``columns`` (static) are the network's inputs, in order."""
    A, c, v, d = (t.astype(x.dtype) for t in folded_layers(net))
    xs = [x[..., i] for i in columns]
    out = d
    for j in range(A.shape[1]):
        z = c[j]
        for k, xk in enumerate(xs):
            z = z + A[k, j] * xk
        out = out + v[j] * jnp.tanh(z)
    return jnp.broadcast_to(out, x.shape[:-1])


@partial(jax.jit, static_argnums=2)
def _init_params(keys: list[Array], x: Array, sizes: tuple[int, ...]) -> tuple:
    # One compilation for a whole list of sizes (a design loop's group), not one per size.
    return tuple(MLP(h).init(k, x)["params"] for k, h in zip(keys, sizes))


def init_ffbns(keys: list[Array], sizes: list[int], data: Dataset) -> list[FFBN]:
    """Fresh FFBNs of ``sizes[i]`` neurons from ``keys[i]``, normalised to ``data``'s input and
    target ranges; each is :func:`init_ffbn` of its key and size.

    Weights use flax's defaults (LeCun-normal kernels, zero biases) in the dtype of ``data.x``.
    """
    sizes = tuple(int(h) for h in sizes)
    if not sizes or min(sizes) < 1 or len(keys) != len(sizes):
        raise ValueError(f"need one key per size and sizes >= 1, got {len(keys)} keys and sizes {list(sizes)}")
    x_norm, y_norm = fit_scaler(data.x, axis=0), fit_scaler(data.y, axis=None)
    x = jnp.asarray(data.x)
    return [FFBN(params=params, x_norm=x_norm, y_norm=y_norm, index=data.index, inputs=data.inputs,
                 n_joints=data.q.shape[-1]) for params in _init_params(keys, x_norm(x[:1]), sizes)]


def init_ffbn(key: Array, hidden: int, data: Dataset) -> FFBN:
    """A fresh FFBN of ``hidden`` neurons, normalised to ``data``'s input and target ranges
    (:func:`init_ffbns` of one size)."""
    if hidden < 1:
        raise ValueError(f"hidden must be >= 1, got {hidden}")
    return init_ffbns([key], [hidden], data)[0]


def padded_width(hidden: int, minimum: int = 8) -> int:
    """Trainer width for ``hidden`` neurons: the next power of two, at least ``minimum``.

    Networks are trained zero-padded to this width so that a design loop over H = 1, 2, …
    compiles one trainer per width, not per H (see :func:`pad_hidden`).
    """
    return max(minimum, 1 << (int(hidden) - 1).bit_length())


def pad_hidden(params: Any, width: int) -> Any:
    """Zero-pad the hidden layer of MLP ``params`` to ``width`` units.

    A unit whose input weights, bias and output weight are all 0 outputs 0 and has zero
    gradient with respect to each of its parameters (∂/∂w_out = tanh(0) = 0, ∂/∂w_in ∝ w_out = 0),
    so Levenberg–Marquardt (block-diagonal normal equations, zero right-hand side) and Adam
    leave it at exactly 0: training the padded network trains the unpadded one.
    """
    extra = width - params["hidden"]["kernel"].shape[-1]
    if extra < 0:
        raise ValueError(f"cannot pad {params['hidden']['kernel'].shape[-1]} hidden units to {width}")
    return {
        "hidden": {"kernel": jnp.pad(params["hidden"]["kernel"], ((0, 0), (0, extra))),
                   "bias": jnp.pad(params["hidden"]["bias"], (0, extra))},
        "output": {"kernel": jnp.pad(params["output"]["kernel"], ((0, extra), (0, 0))),
                   "bias": params["output"]["bias"]},
    }


def trim_hidden(params: Any, hidden: int) -> Any:
    """Inverse of :func:`pad_hidden`: keep the first ``hidden`` units."""
    return {
        "hidden": {"kernel": params["hidden"]["kernel"][:, :hidden], "bias": params["hidden"]["bias"][:hidden]},
        "output": {"kernel": params["output"]["kernel"][:hidden], "bias": params["output"]["bias"]},
    }


def _normalised(net: FFBN, data: Dataset) -> tuple[Array, Array]:
    if tuple(data.inputs) != tuple(net.inputs):
        raise ValueError(f"dataset inputs {data.inputs} differ from the network's {net.inputs}")
    x = jnp.asarray(data.x)
    return net.x_norm(x), net.y_norm(jnp.asarray(data.y, x.dtype))


@partial(jax.jit, static_argnums=(1, 2))
def _stacked(params: tuple, width: int, dtype) -> Any:
    # Pad and stack in one compiled call: eager pads of every size would compile per size.
    padded = [pad_hidden(jax.tree_util.tree_map(lambda p: p.astype(dtype), p), width) for p in params]
    return jax.tree_util.tree_map(lambda *p: jnp.stack(p), *padded)


def _side_by_side(nets: list[FFBN], data: Dataset, pad_to: int | None, fit) -> tuple:
    """Train FFBNs initialised on ``data`` side by side: each zero-padded to one width
    (:func:`pad_hidden`), stacked, and ``fit(params, x, y)`` on the normalised data run for
    all of them in one vmapped call; returns ``fit``'s output, stacked."""
    x, y = _normalised(nets[0], data)  # the scalers are data's: the same for every network
    stacked = _stacked(tuple(net.params for net in nets), pad_to or max(net.hidden for net in nets), x.dtype)
    return jax.vmap(lambda params: fit(params, x, y))(stacked)


def predict_side_by_side(nets: list[FFBN], x: Array) -> Array:
    """``(len(nets), ...)`` predictions at network inputs ``x: (..., d)`` of networks that share
    their scalers (initialised on one dataset), in one vmapped call at one padded width.

    This is the normalised form the trainers fit, which equals :meth:`FFBN.predict` up to
    round-off; it compiles once per width, where ``predict`` compiles once per size.
    """
    x = nets[0]._checked_inputs(x)
    stacked = _stacked(tuple(net.params for net in nets), padded_width(max(net.hidden for net in nets)), x.dtype)
    z = jax.vmap(mlp_apply, in_axes=(0, None))(stacked, nets[0].x_norm(x))
    return nets[0].y_norm.inverse(z)


def _output_scale2(nets: list[FFBN]) -> float:
    """Index units² per normalised unit² of the networks' (shared) output scaler."""
    if not nets:
        raise ValueError("no networks to train")
    return float(jnp.asarray(nets[0].y_norm.scale)) ** 2


def _unstacked(nets: list[FFBN], params: Any) -> list[FFBN]:
    # Sliced on the host: device slices of every size would compile per size.
    host = jax.device_get(params)
    return [net.replace(params=jax.tree_util.tree_map(jnp.asarray, trim_hidden(
        jax.tree_util.tree_map(lambda a: a[i], host), net.hidden))) for i, net in enumerate(nets)]


def train_ffbns_lm(
    nets: list[FFBN],
    data: Dataset,
    *,
    max_epochs: int = 100,
    target_mse: float = 0.0,
    hyper: LMHyperParams = LMHyperParams(),
    pad_to: int | None = None,
) -> list[tuple[FFBN, LMState, Array]]:
    """Levenberg–Marquardt training (paper §3.3) of networks initialised on ``data``, side by
    side in one vmapped call: each with its own μ, epochs and stop, as alone up to round-off.

    ``target_mse`` (E_mse) is in squared index units (eq. 19); internally the mse lives on the
    normalised output, so it is converted with the output scale. ``pad_to`` trains zero-padded
    to that many hidden units (same result, shared compilation; :func:`pad_hidden`; default:
    the largest network's). Returns per network (net, final LM state, history of the mse in
    index units, NaN after the last epoch).
    """
    s2 = _output_scale2(nets)
    fit = lambda p, x, y: fit_lm(mlp_apply, p, x, y, max_epochs=max_epochs, target_mse=float(target_mse) * s2,  # noqa: E731
                                 hyper=hyper)
    params, state, history = _side_by_side(nets, data, pad_to, fit)
    return [(net, jax.tree_util.tree_map(lambda a: a[i], state._replace(mse=state.mse / s2)), history[i] / s2)
            for i, net in enumerate(_unstacked(nets, params))]


def train_ffbn_lm(net: FFBN, data: Dataset, **kwargs) -> tuple[FFBN, LMState, Array]:
    """:func:`train_ffbns_lm` of one network: (net, final LM state, mse history in index units)."""
    return train_ffbns_lm([net], data, **kwargs)[0]


def train_ffbns_adam(nets: list[FFBN], data: Dataset, *, steps: int = 2000, learning_rate: float = 1e-2,
                     pad_to: int | None = None) -> list[tuple[FFBN, Array]]:
    """Full-batch Adam training of networks initialised on ``data``, side by side in one
    vmapped call; per network (net, mse history in index units). ``pad_to`` as in
    :func:`train_ffbns_lm`."""
    s2 = _output_scale2(nets)
    fit = lambda p, x, y: fit_adam(mlp_apply, p, x, y, steps=steps, learning_rate=learning_rate)  # noqa: E731
    params, history = _side_by_side(nets, data, pad_to, fit)
    return [(net, history[i] / s2) for i, net in enumerate(_unstacked(nets, params))]


def train_ffbn_adam(net: FFBN, data: Dataset, **kwargs) -> tuple[FFBN, Array]:
    """:func:`train_ffbns_adam` of one network: (net, mse history in index units)."""
    return train_ffbns_adam([net], data, **kwargs)[0]
