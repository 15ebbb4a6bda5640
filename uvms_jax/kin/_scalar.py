"""The POE Jacobian written on scalars, for throughput over huge batches.

Every quantity is a nested list of "scalars": Python floats for the chain geometry (so the
compiler folds the zeros and ones of the axes) and arrays of the batch shape for anything
that depends on ``q``. Every batched operation is then elementwise and fuses into one kernel
on CPU and GPU — no tiny batched matrix products, no strided gathers. Measured on a 2-core
CPU for the 12-DOF UVMS, this is ~20× faster than the same maths on ``(..., 3, 3)`` arrays.
"""

from __future__ import annotations

import functools
from typing import Callable, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from uvms_jax.kin._chain import Chain

Rows = list  # nested list of scalars (floats or batch-shaped arrays)


class Geometry(NamedTuple):
    """Chain geometry as nested lists: ``twists[i][k]`` and ``tool[i][j]`` (4×4)."""

    twists: Rows
    tool: Rows


def _cross(a, b):
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def _rotate(R, x):
    return [R[i][0] * x[0] + R[i][1] * x[1] + R[i][2] * x[2] for i in range(3)]


def _exp(twist, theta):
    """``exp(ξ̂θ)`` with ``W² = ωωᵀ − |ω|²I`` (Murray eq. 2.14, 2.36); prismatic when ω = 0:
    ``R = I + sW + (1 − c)W²``, ``p = θv + (1 − c)(ω × v) + (θ − s)(ω(ω·v) − |ω|²v)``."""
    v, w = twist[:3], twist[3:]
    s, c = jnp.sin(theta), jnp.cos(theta)
    C = 1.0 - c
    ww = w[0] * w[0] + w[1] * w[1] + w[2] * w[2]
    W = [[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]]
    R = [[(1.0 - C * ww if i == j else 0.0) + s * W[i][j] + C * w[i] * w[j] for j in range(3)] for i in range(3)]
    wv = w[0] * v[0] + w[1] * v[1] + w[2] * v[2]
    wxv = _cross(w, v)
    p = [theta * v[i] + C * wxv[i] + (theta - s) * (w[i] * wv - ww * v[i]) for i in range(3)]
    return R, p


def jacobian_rows(geometry: Geometry, q_cols: list) -> Rows:
    """Geometric Jacobian as 6 rows × n scalars, from joint values ``q_cols[i]`` (batch arrays).

    Columns: spatial twist ``ξ'_i = Ad(g_{i−1}) ξ_i``; the linear rows then move the
    reference point to the tool point, ``v_p = v' + ω' × p_tool``.
    """
    R = [[1.0 if i == j else 0.0 for j in range(3)] for i in range(3)]
    p = [0.0, 0.0, 0.0]
    columns = []
    for twist, theta in zip(geometry.twists, q_cols):
        w_s = _rotate(R, twist[3:])
        v_s = [a + b for a, b in zip(_rotate(R, twist[:3]), _cross(p, w_s))]
        columns.append((v_s, w_s))
        Ri, pi = _exp(twist, theta)
        Rp = _rotate(R, pi)
        R = [[R[i][0] * Ri[0][j] + R[i][1] * Ri[1][j] + R[i][2] * Ri[2][j] for j in range(3)] for i in range(3)]
        p = [Rp[i] + p[i] for i in range(3)]
    tool = geometry.tool
    p_tool = [_rotate(R, [tool[0][3], tool[1][3], tool[2][3]])[i] + p[i] for i in range(3)]
    linear = [[a + b for a, b in zip(v, _cross(w, p_tool))] for v, w in columns]
    return [[col[r] for col in linear] for r in range(3)] + [[w[r] for _, w in columns] for r in range(3)]


def stack_rows(rows: Rows, batch_shape: tuple, dtype) -> jax.Array:
    """Nested scalar lists → array ``(*batch_shape, len(rows), len(rows[0]))``."""
    full = lambda x: jnp.broadcast_to(jnp.asarray(x, dtype), batch_shape)
    # Stack along new leading axes (contiguous copies of whole batch arrays), then move
    # them last: far cheaper to compile and run than interleaving scalars along a minor axis.
    stacked = jnp.stack([jnp.stack([full(x) for x in row]) for row in rows])
    return jnp.moveaxis(stacked, (0, 1), (-2, -1))


def _is_concrete(chain: Chain) -> bool:
    return not any(isinstance(x, jax.core.Tracer) for x in jax.tree_util.tree_leaves(chain))


def geometry(chain: Chain) -> Geometry:
    """Geometry of a chain as Python floats when concrete (folded by the compiler), else as
    traced scalars (so kernels stay differentiable/vmappable in the design parameters)."""
    if _is_concrete(chain):
        tw, tool = np.asarray(chain.twists, np.float64), np.asarray(chain.T_base_tool0, np.float64)
        return Geometry([[float(x) for x in row] for row in tw], [[float(x) for x in row] for row in tool])
    return Geometry(
        [[chain.twists[i, k] for k in range(6)] for i in range(chain.n_joints)],
        [[chain.T_base_tool0[i, j] for j in range(4)] for i in range(4)],
    )


_COMPILED: dict = {}


def compiled_for(chain: Chain, kernel: Callable) -> Callable:
    """``kernel(geometry, q)`` specialised to a concrete chain and jitted, cached per chain
    geometry; for a traced chain, the kernel itself (it is already inside a trace)."""
    if not _is_concrete(chain):
        return functools.partial(kernel, geometry(chain))
    key = (kernel, chain.kinds, chain.name) + tuple(np.asarray(x).tobytes() for x in jax.tree_util.tree_leaves(chain))
    if key not in _COMPILED:
        _COMPILED[key] = jax.jit(functools.partial(kernel, geometry(chain)))
    return _COMPILED[key]
