"""Forward kinematics and Jacobians of a POE chain (Murray, Li & Sastry, ch. 3)."""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp
from jax import Array

from uvms_jax.kin._chain import Chain, check_joint_array, with_dtype
from uvms_jax.kin._scalar import Geometry, compiled_for, jacobian_rows, stack_rows
from uvms_jax.kin._lie import adjoint_twist, exp_twist, homogeneous, matmul, matvec


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


def _kinematics_one(chain: Chain, q: Array) -> Kinematics:
    """Single-configuration kernel, ``q: (n,)``; the joint loop is unrolled (n is static)."""
    R = jnp.eye(3, dtype=q.dtype)
    p = jnp.zeros(3, dtype=q.dtype)
    frames, twists = [], []
    for i in range(chain.n_joints):
        twists.append(adjoint_twist(R, p, chain.twists[i]))
        Ri, pi = exp_twist(chain.twists[i], q[i])
        R, p = matmul(R, Ri), matvec(R, pi) + p
        frames.append(matmul(homogeneous(R, p), chain.T_base_joint0[i]))
    return Kinematics(
        T_base_tool=matmul(homogeneous(R, p), chain.T_base_tool0),
        T_base_joint=jnp.stack(frames),
        twists=jnp.stack(twists),
    )


def _batched(kernel):
    """Apply a one-configuration kernel to ``q`` of any leading shape, in the dtype of ``q``."""

    def run(chain: Chain, q: Array):
        chain = with_dtype(chain, q.dtype)
        flat = q.reshape((-1, q.shape[-1]))
        out = jax.vmap(kernel, in_axes=(None, 0))(chain, flat)
        return jax.tree_util.tree_map(lambda x: x.reshape(q.shape[:-1] + x.shape[1:]), out)

    return jax.jit(run)


def _jacobian_kernel(geom: Geometry, q: Array) -> Array:
    rows = jacobian_rows(geom, [q[..., i] for i in range(q.shape[-1])])
    return stack_rows(rows, q.shape[:-1], q.dtype)


_kinematics = _batched(_kinematics_one)


def kinematics(chain: Chain, q) -> Kinematics:
    """Tool pose, joint-frame poses and spatial joint twists for ``q: (..., n)``.

    Works for any leading batch shape, under ``jit``/``vmap``, in float32 or float64
    (the dtype of ``q``).
    """
    return _kinematics(chain, check_joint_array(chain, q))


def fk(chain: Chain, q) -> Array:
    """Tool pose ``T_base_tool: (..., 4, 4)`` [m] for joint values ``q: (..., n)`` [rad | m]."""
    return kinematics(chain, q).T_base_tool


def jacobian(chain: Chain, q) -> Array:
    """Geometric Jacobian ``(..., 6, n)`` in the base frame.

    Rows 0–2: linear velocity of the tool point [m/s per unit joint rate]; rows 3–5: angular
    velocity [rad/s per unit joint rate]; both expressed in the base frame.
    """
    q = check_joint_array(chain, q)
    return compiled_for(chain, _jacobian_kernel)(q)


def spatial_jacobian(chain: Chain, q) -> Array:
    """Spatial-twist Jacobian ``(..., 6, n)``: columns ``ξ'_i = [v'_i, ω'_i]`` (Murray eq. 3.54).

    The linear rows are the velocity of the body point momentarily at the base origin.
    """
    return jnp.swapaxes(kinematics(chain, q).twists, -1, -2)
