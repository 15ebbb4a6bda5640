"""Forward kinematics and Jacobians of a POE chain (Murray, Li & Sastry, ch. 3).

Every function here is the one kernel of ``_scalar`` (:func:`~uvms_jax.kin._scalar.forward`)
under ``jax.jit`` with the chain as a traced argument: one compiled program per topology,
batch shape and dtype serves every geometry (a sweep over link lengths does not recompile),
and gradients flow to the geometry as well as to ``q``.
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp
from jax import Array

from uvms_jax.kin import _scalar
from uvms_jax.kin._chain import Chain, check_joint_array
from uvms_jax.kin._lie import cross3, stack_scalars


class Kinematics(NamedTuple):
    """Everything one FK pass yields for a configuration (leading axes = batch axes).

    Attributes:
      T_base_tool: ``(..., 4, 4)`` tool pose in the base frame.
      T_base_joint: ``(..., n, 4, 4)`` pose of every joint frame in the base frame.
      twists: ``(..., n, 6)`` spatial joint twists ``ξ'_i = Ad(e^{ξ1θ1}…e^{ξ(i-1)θ(i-1)}) ξ_i``.
    """

    T_base_tool: Array
    T_base_joint: Array
    twists: Array


def _last(R: list, p: list) -> tuple[list, list]:
    return [[x[-1] for x in row] for row in R], [x[-1] for x in p]


def _per_joint(T0: Array, batch_ndim: int) -> tuple[list, list]:
    """``(n, 4, 4)`` → rotation rows and translation of ``(n, 1, …, 1)`` scalars."""
    T0 = T0.reshape(T0.shape[:1] + (1,) * batch_ndim + T0.shape[1:])
    return [[T0[..., i, j] for j in range(3)] for i in range(3)], [T0[..., i, 3] for i in range(3)]


def kinematics_of(chain: Chain, q: Array) -> Kinematics:
    """:func:`kinematics` without input checks or ``jit``, for use inside other kernels."""
    batch, dtype = q.shape[:-1], q.dtype
    kpass = _scalar.forward_scanned(chain, q)
    (R, p), (v, w) = kpass.products[0], kpass.columns[0]  # scalars (n, *batch)
    T_tool = _scalar.pose_array(*_scalar.compose_pose(*_last(R, p), chain.T_base_tool0), batch, dtype)
    T0 = jnp.asarray(chain.T_base_joint0, dtype)
    frames = _scalar.pose_array(*_scalar.compose(R, p, *_per_joint(T0, len(batch))), (chain.n_joints,) + batch, dtype)
    twists = stack_scalars([v + w], (chain.n_joints,) + batch, dtype)[..., 0, :]
    return Kinematics(
        T_base_tool=T_tool, T_base_joint=jnp.moveaxis(frames, 0, -3), twists=jnp.moveaxis(twists, 0, -2)
    )


def fk_of(chain: Chain, q: Array) -> Array:
    """:func:`fk` without input checks or ``jit``, for use inside other kernels."""
    R, p = _scalar.forward_scanned(chain, q).products[0]
    return _scalar.pose_array(*_scalar.compose_pose(*_last(R, p), chain.T_base_tool0), q.shape[:-1], q.dtype)


def pose_and_jacobian_of(chain: Chain, q: Array) -> tuple[Array, Array]:
    """``(T_base_tool (..., 4, 4), J (..., 6, n))`` from one pass; no checks, no ``jit``."""
    batch, dtype = q.shape[:-1], q.dtype
    kpass = _scalar.forward_scanned(chain, q)
    (R, p), (v, w) = kpass.products[0], kpass.columns[0]
    R_tool, p_tool = _scalar.compose_pose(*_last(R, p), chain.T_base_tool0)
    linear = [a + b for a, b in zip(v, cross3(w, p_tool))]  # (n, *batch) each
    J = jnp.moveaxis(jnp.stack(linear + w), (0, 1), (-2, -1))
    return _scalar.pose_array(R_tool, p_tool, batch, dtype), J


_kinematics = jax.jit(kinematics_of)
_fk = jax.jit(fk_of)
_jacobian = jax.jit(lambda chain, q: pose_and_jacobian_of(chain, q)[1])


def kinematics(chain: Chain, q) -> Kinematics:
    """Tool pose, joint-frame poses and spatial joint twists for ``q: (..., n)``.

    Works for any leading batch shape, under ``jit``/``vmap``/``grad`` (in ``q`` and in the
    chain's geometry), in float32 or float64 (the dtype of ``q``).
    """
    return _kinematics(chain, check_joint_array(chain, q))


def fk(chain: Chain, q) -> Array:
    """Tool pose ``T_base_tool: (..., 4, 4)`` [m] for joint values ``q: (..., n)`` [rad | m]."""
    return _fk(chain, check_joint_array(chain, q))


def jacobian(chain: Chain, q) -> Array:
    """Geometric Jacobian ``(..., 6, n)`` in the base frame.

    Rows 0–2: linear velocity of the tool point [m/s per unit joint rate]; rows 3–5: angular
    velocity [rad/s per unit joint rate]; both expressed in the base frame.
    """
    return _jacobian(chain, check_joint_array(chain, q))


def spatial_jacobian(chain: Chain, q) -> Array:
    """Spatial-twist Jacobian ``(..., 6, n)``: columns ``ξ'_i = [v'_i, ω'_i]`` (Murray eq. 3.54).

    The linear rows are the velocity of the body point momentarily at the base origin.
    """
    return jnp.swapaxes(kinematics(chain, q).twists, -1, -2)


def spatial_jacobian_rows(chain: Chain, q: Array) -> list:
    """Spatial-twist Jacobian at ``q: (..., n)`` as 6 rows × n arrays of shape ``(...)``: the
    rows of :func:`spatial_jacobian`, for fused kernels as :func:`jacobian_rows`."""
    return _scalar.spatial_rows(chain, q)


def jacobian_rows(chain: Chain, q: Array) -> list:
    """Geometric Jacobian at ``q: (..., n)`` as 6 rows × n arrays of shape ``(...)``.

    For kernels that consume J entry by entry (e.g. the dexterity indices): call it inside
    your own ``jax.jit`` with the chain as an argument; the entries fuse with whatever uses
    them, and J is never stored. No input checks (see :func:`check_joint_array`).
    """
    return _scalar.jacobian_rows(chain, q)


def pose_and_jacobian_rows(chain: Chain, q) -> tuple[list, list, list]:
    """Tool pose (rotation rows, translation) and geometric Jacobian rows at ``q`` (an array
    ``(..., n)`` or n arrays of one batch shape), as scalars of the batch shape, for fused
    kernels as :func:`jacobian_rows`."""
    return _scalar.pose_and_jacobian_rows(chain, q)
