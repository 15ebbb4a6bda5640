"""The fused index kernels as one Pallas (Triton) program on a GPU.

On a GPU, XLA splits the few thousand scalar operations of w or KCI of a 12-joint chain into
several fusions and passes the intermediates through GPU memory (eight kernels for the 12-DOF
UVMS). Written as one Pallas kernel, every intermediate of a configuration stays in
registers: the same expression (``uvms_jax.kin.jacobian_rows`` → ``*_from_rows``) runs as one
thread per configuration, reading n joint values and writing one number. docs/benchmarks/kinematics.md
has the figures and the roofline.

The chain's numbers are constants of the kernel (they fold into the arithmetic), so one
compiled kernel serves one geometry; a chain whose geometry is traced (``jax.grad`` with
respect to a design parameter) takes the XLA path. Derivatives with respect to ``q`` go
through the XLA path too (a custom JVP), so the kernel changes speed, never results.
"""

from __future__ import annotations

from collections.abc import Callable

import jax
import jax.numpy as jnp
import numpy as np
from jax import Array

from uvms_jax.kin import Chain, jacobian_rows

#: Configurations per program instance, and warps per instance: one configuration per thread
#: (measured on an H100 for the 12-DOF UVMS: 128 × 4 warps beat 64–512 with 1–8 warps).
BLOCK = 128
NUM_WARPS = 4

_MAX_KERNELS = 32  # compiled kernels kept (one per geometry, task, index and dtype)
_kernels: dict[tuple, Callable] = {}


def applies(chain: Chain, q: Array) -> bool:
    """Whether the GPU kernel serves ``q``: a GPU backend, a chain with known numbers, a
    floating-point batch."""
    leaves = jax.tree_util.tree_leaves(chain)
    return (jax.default_backend() == "gpu" and q.ndim >= 1
            and jnp.issubdtype(q.dtype, jnp.floating)
            and not any(isinstance(leaf, jax.core.Tracer) for leaf in leaves))


def _geometry_key(chain: Chain) -> tuple:
    """A hashable copy of the numbers the kernel bakes in (twists, tool pose) and the topology."""
    return (chain.n_joints, tuple(np.asarray(chain.twists, np.float64).ravel().tolist()),
            tuple(np.asarray(chain.T_base_tool0, np.float64).ravel().tolist()))


def _kernel(index_from_rows: Callable, chain: Chain, rows: tuple[int, ...], dtype) -> Callable:
    """The compiled kernel for this index, geometry, task and dtype (built once, then reused)."""
    key = (index_from_rows, _geometry_key(chain), rows, jnp.dtype(dtype))
    if key not in _kernels:
        if len(_kernels) >= _MAX_KERNELS:
            _kernels.pop(next(iter(_kernels)))  # the oldest
        _kernels[key] = _build(index_from_rows, jax.tree_util.tree_map(np.asarray, chain), rows, dtype)
    return _kernels[key]


def _build(index_from_rows: Callable, chain: Chain, rows: tuple[int, ...], dtype) -> Callable:
    """``q: (B, n) → (B,)``, jitted: pad to whole blocks, joints to the leading axis, one
    Pallas program per block of configurations."""
    from jax.experimental import pallas as pl
    from jax.experimental.pallas import triton as plt

    n = chain.n_joints
    n_pad = 1 << (n - 1).bit_length()  # Triton blocks have power-of-two sides

    def kernel(q_ref, out_ref):
        J = jacobian_rows(chain, [q_ref[i, :] for i in range(n)])
        out_ref[...] = index_from_rows([J[r] for r in rows])

    def run(q):
        batch = q.shape[0]
        padded = -(-batch // BLOCK) * BLOCK
        qT = jnp.pad(q, ((0, padded - batch), (0, n_pad - n))).T
        out = pl.pallas_call(
            kernel,
            out_shape=jax.ShapeDtypeStruct((padded,), dtype),
            grid=(padded // BLOCK,),
            in_specs=[pl.BlockSpec((n_pad, BLOCK), lambda i: (0, i))],
            out_specs=pl.BlockSpec((BLOCK,), lambda i: (i,)),
            compiler_params=plt.CompilerParams(num_warps=NUM_WARPS, num_stages=1),
            interpret=jax.default_backend() != "gpu",  # the same program, emulated (tests on a CPU)
        )(qT)
        return out[:batch]

    return jax.jit(run)


def index_on_gpu(index_from_rows: Callable, xla_path: Callable, chain: Chain, q: Array,
                 rows: tuple[int, ...]) -> Array:
    """``index_from_rows`` of ``chain`` at ``q: (..., n)`` through the GPU kernel, shape ``(...)``.

    Args:
      index_from_rows: the index of a Jacobian given as rows of scalars (w or KCI).
      xla_path: ``(chain, q, rows) → (...)``, the same index through XLA: its derivatives are
        the kernel's.
      chain: a chain with known numbers (see :func:`applies`).
      q: ``(..., n)`` joint values.
      rows: task rows of the geometric Jacobian.
    """
    run = _kernel(index_from_rows, chain, rows, q.dtype)

    @jax.custom_jvp
    def index(q):
        return run(q.reshape(-1, q.shape[-1])).reshape(q.shape[:-1])

    @index.defjvp
    def _jvp(primals, tangents):
        return jax.jvp(lambda q: xla_path(chain, q, rows), primals, tangents)

    return index(q)
