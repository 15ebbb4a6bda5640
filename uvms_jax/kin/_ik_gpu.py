"""Damped least squares IK as one Pallas (Triton) program on a GPU.

XLA runs :func:`uvms_jax.kin.dls_ik`'s loop as a sequence of fused kernels per iteration, each
reading and writing its intermediates (the joint values, the pose, the Jacobian, the 6 × 6
system) through GPU memory. Here one thread runs one configuration's whole loop — forward
kinematics, Jacobian, pose error, ``(J Jᵀ + λ² I) y = e``, the step ``Jᵀ y`` — with every
intermediate in registers, and reads only the seed, the target and the chain, and writes the
result.

The arithmetic is the XLA path's, written on scalars (:mod:`uvms_jax.kin._scalar`): the same
POE pass, the same error-scaled damping, Cholesky and limit handling. The chain is an input of
the kernel (one row per number, the same in every column), so a traced chain (docking's
problem is an argument of its ``jit``) uses the kernel too. Derivatives go through the XLA
path (a custom JVP): the kernel changes speed, never results beyond round-off.
"""

from __future__ import annotations

import functools

import jax
import jax.numpy as jnp
from jax import Array

from uvms_jax.kin._chain import Chain
from uvms_jax.kin._lie import rotation_log_scalars
from uvms_jax.kin._scalar import _IDENTITY, Pass, _joint_step, compose, geometric_rows, spd_solve_scalars, wrap_angle

#: Configurations per program instance, and warps per instance: one configuration per thread
#: (the dexterity kernels' choice, ``uvms_jax.indices._gpu``).
BLOCK = 128
NUM_WARPS = 4


def applies(q: Array) -> bool:
    """Whether the kernel serves seeds ``q``: a GPU backend and float32 joint values."""
    return jax.default_backend() == "gpu" and q.dtype == jnp.float32


def dls_step_scalars(twists: list, tool0: tuple[list, list], lower: list, upper: list, revolute: tuple[bool, ...],
                     target: tuple[list, list], q: list, damping, limits: str) -> list:
    """One :func:`uvms_jax.kin.dls_step` on scalars.

    Args:
      twists: per joint 6 scalars ``[v, ω]``; tool0: ``(R, p)`` of ``T_base_tool0``.
      lower, upper: per joint limits; revolute: per joint, static.
      target: ``(R, p)`` of the target tool pose in the base frame.
      q: per joint values; damping: λ's factor; limits: ``"clip"`` or ``"wrap"``.

    Returns the next joint values, one scalar per joint.
    """
    n = len(q)
    carry, columns = (_IDENTITY, [0.0, 0.0, 0.0]), []
    for i in range(n):
        carry, column = _joint_step(carry, (twists[i], q[i]))
        columns.append(column)
    R, p = compose(*carry, *tool0)
    J = geometric_rows(Pass(columns, []), p)  # 6 rows × n
    R_t, p_t = target
    dR = [[sum(R_t[i][k] * R[j][k] for k in range(3)) for j in range(3)] for i in range(3)]  # R_t Rᵀ
    e = [p_t[i] - p[i] for i in range(3)] + rotation_log_scalars(dR)
    lam2 = damping * damping * (sum(x * x for x in e) + 1e-6)
    A = [[sum(J[a][i] * J[b][i] for i in range(n)) + (lam2 if a == b else 0.0) for b in range(a + 1)] for a in range(6)]
    y = spd_solve_scalars(A, e)
    q = [q[i] + sum(J[a][i] * y[a] for a in range(6)) for i in range(n)]
    if limits == "clip":
        return [jnp.clip(q[i], lower[i], upper[i]) for i in range(n)]
    return [wrap_angle(q[i], lower[i]) if revolute[i] else q[i] for i in range(n)]


def _geometry(chain: Chain, damping, dtype) -> Array:
    """``(G,)`` the kernel's numbers: twists (6 per joint), ``T_base_tool0``'s top 12 entries
    (row by row), the lower and upper limits, the damping factor."""
    parts = [jnp.ravel(chain.twists), jnp.ravel(chain.T_base_tool0[:3]), chain.lower, chain.upper,
             jnp.reshape(damping, (1,))]
    return jnp.concatenate([jnp.asarray(x, dtype) for x in parts])


@functools.lru_cache(maxsize=32)
def _build(n: int, revolute: tuple[bool, ...], iterations: int, limits: str, interpret: bool):
    """``(geometry (G,), targets (12, B), seeds (n, B)) → (n, B)``: one Pallas program per block
    of configurations, padded to whole blocks and power-of-two row counts."""
    from jax.experimental import pallas as pl
    from jax.experimental.pallas import triton as plt

    n_geom = 6 * n + 12 + 2 * n + 1
    g_pad, n_pad = 1 << (n_geom - 1).bit_length(), 1 << (n - 1).bit_length()

    def kernel(geom_ref, target_ref, q_ref, out_ref):
        g = [geom_ref[i, :] for i in range(n_geom)]
        twists = [g[6 * j:6 * j + 6] for j in range(n)]
        top = g[6 * n:6 * n + 12]
        tool0 = ([top[4 * i:4 * i + 3] for i in range(3)], [top[4 * i + 3] for i in range(3)])
        lower, upper, damping = g[6 * n + 12:7 * n + 12], g[7 * n + 12:8 * n + 12], g[8 * n + 12]
        t = [target_ref[i, :] for i in range(12)]
        target = ([t[4 * i:4 * i + 3] for i in range(3)], [t[4 * i + 3] for i in range(3)])
        step = lambda _, q: tuple(dls_step_scalars(twists, tool0, lower, upper, revolute, target, list(q),  # noqa: E731
                                                   damping, limits))
        q = jax.lax.fori_loop(0, iterations, step, tuple(q_ref[i, :] for i in range(n)))
        for i in range(n):
            out_ref[i, :] = q[i]

    def run(geometry, targets, seeds):
        batch = seeds.shape[1]
        padded = -(-batch // BLOCK) * BLOCK
        geom = jnp.broadcast_to(jnp.pad(geometry, (0, g_pad - n_geom))[:, None], (g_pad, BLOCK))
        targets = jnp.pad(targets, ((0, 4), (0, padded - batch)), mode="edge")
        seeds = jnp.pad(seeds, ((0, n_pad - n), (0, padded - batch)), mode="edge")
        out = pl.pallas_call(
            kernel,
            out_shape=jax.ShapeDtypeStruct((n_pad, padded), seeds.dtype),
            grid=(padded // BLOCK,),
            in_specs=[pl.BlockSpec((g_pad, BLOCK), lambda i: (0, 0)), pl.BlockSpec((16, BLOCK), lambda i: (0, i)),
                      pl.BlockSpec((n_pad, BLOCK), lambda i: (0, i))],
            out_specs=pl.BlockSpec((n_pad, BLOCK), lambda i: (0, i)),
            compiler_params=plt.CompilerParams(num_warps=NUM_WARPS, num_stages=1),
            interpret=interpret,
        )(geom, targets, seeds)
        return out[:n, :batch]

    return run


def dls_ik_kernel(chain: Chain, T_base_tool: Array, q0: Array, iterations: int, damping, limits: str,
                  xla_path, interpret: bool = False) -> Array:
    """:func:`uvms_jax.kin.dls_ik` through the kernel: ``q (..., n)`` for targets
    ``(..., 4, 4)`` and seeds ``q0 (..., n)`` (leading axes broadcast together).

    ``xla_path(T_base_tool, q0)`` is the same solve through XLA: the kernel's derivatives.
    ``interpret`` runs the same program emulated (tests on a CPU).
    """
    shape = jnp.broadcast_shapes(T_base_tool.shape[:-2], q0.shape[:-1])
    n = chain.n_joints
    run = _build(n, tuple(k == "revolute" for k in chain.kinds), int(iterations), limits, interpret)
    geometry = _geometry(chain, damping, q0.dtype)

    @jax.custom_jvp
    def solve(T, q0):
        targets = jnp.broadcast_to(T[..., :3, :], shape + (3, 4)).reshape(-1, 12).T
        seeds = jnp.broadcast_to(q0, shape + (n,)).reshape(-1, n).T
        return run(geometry, targets.astype(q0.dtype), seeds).T.reshape(shape + (n,))

    @solve.defjvp
    def _jvp(primals, tangents):
        return jax.jvp(xla_path, primals, tangents)

    return solve(T_base_tool, q0)
