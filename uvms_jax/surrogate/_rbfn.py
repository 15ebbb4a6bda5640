"""Radial basis function network (RBFN; dexterity paper §3.2 eqs. 16–18, §3.4; Matlab ``newrb``).

Hidden unit j: ``φ_j(x) = exp(−(‖x̃ − c_j‖ b)²)`` with ``b = 0.8326 / spread`` (so φ = 0.5 at
distance ``spread``); linear output ``S = y⁻¹(Σ_j a_j φ_j(x) + a_0)``. Inputs are min–max
normalised to [−1, 1] first, so centres and spread are in normalised input units.

Design (greedy, newrb-like): start with the bias alone; repeatedly add a unit centred on the
training input with the largest absolute error, then refit all output weights by linear least
squares; stop when the training mse ≤ target or ``max_centres`` is reached. The least-squares
fit is kept incremental by Gram–Schmidt orthogonalisation of the design-matrix columns
(re-orthogonalised once, "twice is enough"): adding a unit costs O(N·M), the whole fit one
jitted ``lax.while_loop``.
"""

from __future__ import annotations

import math
from functools import partial
from typing import NamedTuple

import jax
import jax.numpy as jnp
from flax import struct
from jax import Array

from uvms_jax.surrogate._dataset import Dataset
from uvms_jax.surrogate._inputs import JointInputs
from uvms_jax.surrogate._scaler import fit_scaler

SPREAD_CONSTANT = math.sqrt(math.log(2.0))  # 0.8326: φ(spread) = 0.5
# Operations per RBF unit in the dexterity paper's count (12 additions + 16 multiplications; see
# RBFN.operation_count).
RBFN_OPS_PER_UNIT = 28
# A candidate column whose part orthogonal to the current basis is below this fraction of its
# norm adds nothing the basis cannot already fit (numerically dependent); it is skipped.
DEPENDENT_COLUMN_RTOL = 1e-7


@struct.dataclass
class RBFN(JointInputs):
    """A Gaussian RBF network of one index.

    Attributes:
      centres: ``(M, d)`` unit centres in normalised input space.
      weights: ``(M,)`` output weights (normalised output units).
      bias: ``()`` output bias.
      spread: ``()`` spread in normalised input units; ``b = 0.8326 / spread``.
      x_norm, y_norm, index, inputs, n_joints: see :class:`JointInputs`.
    """

    centres: Array
    weights: Array
    bias: Array
    spread: Array

    @property
    def n_centres(self) -> int:
        """Number of hidden units M."""
        return int(self.centres.shape[0])

    @property
    def operation_count(self) -> int:
        """Additions + multiplications per evaluation in the dexterity paper's convention.

        The paper counts 12 additions and 16 multiplications per unit, whatever the number of
        inputs: RBFN-w, 149 units of 7 inputs, 1788 + 2384 = 4172; RBFN-KCI, 3976 = 1704 + 2272,
        i.e. 142 units of 11 inputs (§4.3–4.4, Table 4). So ``28 M``. (Counting the formula
        instead, ``exp(−(‖x − c‖ b)²)`` costs d subtractions, d squares, d − 1 additions, a
        multiplication by b², an exp, a weight multiplication and an addition: ``M (3d + 3)``.)
        """
        return RBFN_OPS_PER_UNIT * self.n_centres

    def predict(self, x: Array) -> Array:
        """Index estimate for network inputs ``x: (..., d)`` → ``(...)``, in the dtype of ``x``.

        Raises:
          ValueError: ``x``'s last axis is not ``d`` long.
        """
        return _predict(self, self._checked_inputs(x))


@jax.jit
def _predict(net: RBFN, x: Array) -> Array:
    dt = x.dtype
    phi = _design(net.x_norm(x), net.centres.astype(dt), net.spread.astype(dt))
    return net.y_norm.inverse(phi @ net.weights.astype(dt) + net.bias.astype(dt))


def _sq_dist(x: Array, c: Array) -> Array:
    """``‖x_i − c_j‖²`` for ``x: (..., d)``, ``c: (M, d)`` → ``(..., M)`` (expanded form, one matmul)."""
    d2 = jnp.sum(x * x, -1)[..., None] - 2.0 * x @ c.T + jnp.sum(c * c, -1)
    return jnp.maximum(d2, 0.0)


def _design(x: Array, c: Array, spread: Array) -> Array:
    b = SPREAD_CONSTANT / spread
    return jnp.exp(-(b * b) * _sq_dist(x, c))


class RBFNFit(NamedTuple):
    """Raw result of :func:`fit_rbfn_arrays` (padded to ``max_centres``).

    Attributes:
      centre_index: ``(max_centres,)`` training-sample index of each unit (−1 = unused).
      weights: ``(max_centres,)`` output weights (0 for unused units); bias: ``()``.
      count: ``()`` number of units used.
      mse: ``()`` training mse (normalised output units).
      history: ``(max_centres + 1,)`` training mse after each added unit (NaN afterwards).
    """

    centre_index: Array
    weights: Array
    bias: Array
    count: Array
    mse: Array
    history: Array


@partial(jax.jit, static_argnames=("max_centres",))
def fit_rbfn_arrays(x: Array, y: Array, spread: Array, target_mse: Array, max_centres: int) -> RBFNFit:
    """Greedy RBF design on normalised data, ``x: (N, d)``, ``y: (N,)``; one ``while_loop``.

    The spread and target are traced (a spread search compiles once).
    """
    n, dt = x.shape[0], x.dtype
    k_max = max_centres + 1  # column 0 is the bias
    Q = jnp.zeros((n, k_max), dt).at[:, 0].set(1.0 / jnp.sqrt(jnp.asarray(n, dt)))
    R = jnp.zeros((k_max, k_max), dt).at[0, 0].set(jnp.sqrt(jnp.asarray(n, dt)))
    r = y - jnp.mean(y)  # residual of the bias-only fit
    b2 = (SPREAD_CONSTANT / spread) ** 2
    state = dict(
        Q=Q, R=R, r=r, used=jnp.zeros(n, bool), centre=jnp.full((max_centres,), -1, jnp.int32),
        count=jnp.array(0, jnp.int32), history=jnp.full((k_max,), jnp.nan, dt).at[0].set(jnp.mean(r * r)),
    )

    def cond(s):
        return (s["count"] < max_centres) & (jnp.mean(s["r"] ** 2) > target_mse) & ~jnp.all(s["used"])

    def body(s):
        i = jnp.argmax(jnp.where(s["used"], -1.0, jnp.abs(s["r"])))  # worst-fit unused input
        phi = jnp.exp(-b2 * jnp.maximum(jnp.sum((x - x[i]) ** 2, -1), 0.0))
        c1 = s["Q"].T @ phi
        v = phi - s["Q"] @ c1
        c2 = s["Q"].T @ v
        v = v - s["Q"] @ c2
        norm = jnp.linalg.norm(v)
        add = norm > DEPENDENT_COLUMN_RTOL * jnp.linalg.norm(phi)
        q_new = v / jnp.where(add, norm, 1.0)
        k = s["count"] + 1
        coeff = (c1 + c2).at[k].set(norm)
        r_new = s["r"] - q_new * (q_new @ s["r"])
        count = s["count"] + add.astype(jnp.int32)
        return dict(
            Q=jnp.where(add, s["Q"].at[:, k].set(q_new), s["Q"]),
            R=jnp.where(add, s["R"].at[:, k].set(coeff), s["R"]),
            r=jnp.where(add, r_new, s["r"]),
            used=s["used"].at[i].set(True),
            centre=jnp.where(add, s["centre"].at[s["count"]].set(i.astype(jnp.int32)), s["centre"]),
            count=count,
            history=jnp.where(add, s["history"].at[k].set(jnp.mean(r_new**2)), s["history"]),
        )

    s = jax.lax.while_loop(cond, body, state)
    # Output weights: R a = Qᵀ y on the active columns; unused columns get R_kk = 1, rhs 0 → a_k = 0.
    active = jnp.arange(k_max) <= s["count"]
    R = jnp.where(active[None, :] & active[:, None], s["R"], 0.0) + jnp.diag(jnp.where(active, 0.0, 1.0))
    rhs = jnp.where(active, s["Q"].T @ y, 0.0)
    a = jax.scipy.linalg.solve_triangular(R, rhs, lower=False)
    return RBFNFit(centre_index=s["centre"], weights=a[1:], bias=a[0], count=s["count"],
                   mse=jnp.mean(s["r"] ** 2), history=s["history"])


def fit_rbfn(data: Dataset, *, spread: float, target_mse: float = 0.0, max_centres: int = 200) -> tuple[RBFN, Array]:
    """Design an RBFN on ``data`` for one ``spread`` (paper §3.4, inner loop).

    Args:
      data: training set (inputs are normalised to [−1, 1] by the network's scaler).
      spread: Gaussian spread in normalised input units (> 0).
      target_mse: stop adding units when the training mse ≤ this (E_th), in squared index units.
      max_centres: unit limit (also stops when every training input is a centre).

    Returns:
      (network trimmed to its units, training-mse history in index units, one entry per unit
      count starting from the bias-only network).
    """
    if not spread > 0:
        raise ValueError(f"spread must be positive, got {spread}")
    if max_centres < 1:
        raise ValueError(f"max_centres must be >= 1, got {max_centres}")
    x_norm, y_norm = fit_scaler(data.x, axis=0), fit_scaler(data.y, axis=None)
    x = x_norm(jnp.asarray(data.x))
    y = y_norm(jnp.asarray(data.y, x.dtype))
    s2 = jnp.asarray(y_norm.scale, x.dtype) ** 2
    max_centres = min(int(max_centres), x.shape[0])
    fit = fit_rbfn_arrays(x, y, jnp.asarray(spread, x.dtype), jnp.asarray(target_mse, x.dtype) * s2, max_centres)
    m = int(fit.count)
    net = RBFN(
        centres=x[fit.centre_index[:m]], weights=fit.weights[:m], bias=fit.bias, spread=jnp.asarray(spread, x.dtype),
        x_norm=x_norm, y_norm=y_norm, index=data.index, inputs=data.inputs, n_joints=data.q.shape[-1],
    )
    return net, fit.history[: m + 1] / s2
