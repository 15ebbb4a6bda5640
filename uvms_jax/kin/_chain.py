"""The immutable serial-chain model: POE twists, zero pose, joint frames, limits, names."""

from __future__ import annotations

from typing import Sequence

import jax
import jax.numpy as jnp
import numpy as np
from flax import struct
from jax import Array

from uvms_jax.kin._lie import rpy_matrix
from uvms_jax.urdf import PRISMATIC, REVOLUTE, UrdfJoint


@struct.dataclass
class Chain:
    """A serial chain in product-of-exponentials form (Murray, Li & Sastry, ch. 3).

    Geometry fields are traced pytree leaves (so design parameters can be vmapped or
    differentiated); topology and names are static.

    Attributes:
      twists: ``(n, 6)`` unit joint twists ``[v, ω]`` in the base frame at ``q = 0``.
      T_base_tool0: ``(4, 4)`` tool pose in the base frame at ``q = 0`` [m].
      T_base_joint0: ``(n, 4, 4)`` pose of each joint frame at ``q = 0`` (joint i's frame
        moves with link i, i.e. after joint i's own motion).
      lower, upper: ``(n,)`` joint limits [rad or m].
      velocity_limits: ``(n,)`` joint speed limits [rad/s or m/s].
      kinds: per joint, ``"revolute"`` or ``"prismatic"`` (static).
      joint_names: per joint (static).
      name: model name (static).
    """

    twists: Array
    T_base_tool0: Array
    T_base_joint0: Array
    lower: Array
    upper: Array
    velocity_limits: Array
    kinds: tuple[str, ...] = struct.field(pytree_node=False)
    joint_names: tuple[str, ...] = struct.field(pytree_node=False)
    name: str = struct.field(pytree_node=False, default="chain")

    @property
    def n_joints(self) -> int:
        return len(self.kinds)


def _check_twists(twists: np.ndarray, kinds: Sequence[str]) -> None:
    """A ValueError for a joint of unknown kind or whose twist ``(6,)`` is not a unit
    revolute axis (``|ω| = 1``) or a unit prismatic direction (``ω = 0, |v| = 1``)."""
    for i, kind in enumerate(kinds):
        v, w = twists[i, :3], twists[i, 3:]
        if kind == REVOLUTE and not np.isclose(np.linalg.norm(w), 1.0, atol=1e-9):
            raise ValueError(f"joint {i}: revolute axis must be a unit vector, |ω| = {np.linalg.norm(w)}")
        elif kind == PRISMATIC and not (np.allclose(w, 0.0) and np.isclose(np.linalg.norm(v), 1.0, atol=1e-9)):
            raise ValueError(f"joint {i}: prismatic twist must have ω = 0 and |v| = 1")
        elif kind not in (REVOLUTE, PRISMATIC):
            raise ValueError(f"joint {i}: unknown joint kind {kind!r} (expected 'revolute' or 'prismatic')")


def _default_joint_frames(twists: np.ndarray, kinds: Sequence[str]) -> np.ndarray:
    """``(n, 4, 4)`` joint frames aligned with the base at a point of each joint's axis: ``ω × v``
    for a revolute joint, the previous frame's origin for a prismatic one."""
    T_base_joint0 = np.tile(np.eye(4), (len(kinds), 1, 1))
    previous = np.zeros(3)
    for i, kind in enumerate(kinds):
        v, w = twists[i, :3], twists[i, 3:]
        # For ξ = [−ω × q, ω], ω × v is the point of the axis closest to the origin.
        point = np.cross(w, v) if kind == REVOLUTE else previous
        T_base_joint0[i, :3, 3] = point
        previous = point
    return T_base_joint0


def make_chain(
    twists,
    T_base_tool0,
    lower,
    upper,
    kinds: Sequence[str],
    joint_names: Sequence[str] | None = None,
    T_base_joint0=None,
    velocity_limits=None,
    name: str = "chain",
) -> Chain:
    """Build and validate a :class:`Chain`.

    Args:
      twists: ``(n, 6)`` ``[v, ω]``; revolute: ``|ω| = 1``; prismatic: ``ω = 0, |v| = 1``.
      T_base_tool0: ``(4, 4)`` tool pose at ``q = 0``.
      lower, upper: ``(n,)`` joint limits, ``lower < upper``.
      kinds: ``"revolute"`` / ``"prismatic"`` per joint.
      joint_names: defaults to ``q1 … qn``.
      T_base_joint0: ``(n, 4, 4)``; defaults to a frame aligned with the base at a point of
        the joint axis (``ω × v`` for revolute joints, the previous frame's origin otherwise).
      velocity_limits: ``(n,)`` [rad/s or m/s]; defaults to 1.

    Raises:
      ValueError: on wrong shapes, non-finite numbers, non-unit axes or inverted limits.
    """
    twists = np.asarray(twists, dtype=np.float64)
    n = len(kinds)
    if twists.shape != (n, 6):
        raise ValueError(f"twists must have shape ({n}, 6) for {n} joints, got {twists.shape}")
    T_base_tool0 = np.asarray(T_base_tool0, dtype=np.float64)
    if T_base_tool0.shape != (4, 4):
        raise ValueError(f"T_base_tool0 must have shape (4, 4), got {T_base_tool0.shape}")
    lower = np.asarray(lower, dtype=np.float64)
    upper = np.asarray(upper, dtype=np.float64)
    if lower.shape != (n,) or upper.shape != (n,):
        raise ValueError(f"joint limits must have shape ({n},), got {lower.shape} and {upper.shape}")
    for label, arr in (("twists", twists), ("T_base_tool0", T_base_tool0), ("lower", lower), ("upper", upper)):
        if not np.all(np.isfinite(arr)):
            raise ValueError(f"{label} contains NaN or infinite values")
    bad = np.nonzero(lower >= upper)[0]
    if bad.size:
        names = joint_names or [f"q{i + 1}" for i in range(n)]
        raise ValueError(
            "joint limits inverted or empty (lower >= upper) for joints "
            + ", ".join(f"{names[i]} [{lower[i]}, {upper[i]}]" for i in bad)
        )
    _check_twists(twists, kinds)
    if joint_names is None:
        joint_names = [f"q{i + 1}" for i in range(n)]
    if len(joint_names) != n:
        raise ValueError(f"expected {n} joint names, got {len(joint_names)}")
    T_base_joint0 = np.asarray(_default_joint_frames(twists, kinds) if T_base_joint0 is None else T_base_joint0,
                               dtype=np.float64)
    if T_base_joint0.shape != (n, 4, 4):
        raise ValueError(f"T_base_joint0 must have shape ({n}, 4, 4), got {T_base_joint0.shape}")
    velocity_limits = np.ones(n) if velocity_limits is None else np.asarray(velocity_limits, dtype=np.float64)
    if velocity_limits.shape != (n,) or np.any(velocity_limits <= 0):
        raise ValueError(f"velocity_limits must be ({n},) and positive, got {velocity_limits}")
    # Geometry is stored in JAX's default float dtype (float64 when x64 is enabled); kernels
    # cast it to the dtype of q.
    return Chain(
        twists=jnp.asarray(twists),
        T_base_tool0=jnp.asarray(T_base_tool0),
        T_base_joint0=jnp.asarray(T_base_joint0),
        lower=jnp.asarray(lower),
        upper=jnp.asarray(upper),
        velocity_limits=jnp.asarray(velocity_limits),
        kinds=tuple(kinds),
        joint_names=tuple(joint_names),
        name=name,
    )


def revolute_twist(axis, point) -> np.ndarray:
    """``ξ = [−ω × q, ω]`` for a revolute joint with unit axis ω through point q (base frame)."""
    w = np.asarray(axis, dtype=np.float64)
    return np.concatenate([-np.cross(w, np.asarray(point, dtype=np.float64)), w])


def prismatic_twist(direction) -> np.ndarray:
    """``ξ = [k, 0]`` for a prismatic joint along unit direction k (base frame)."""
    return np.concatenate([np.asarray(direction, dtype=np.float64), np.zeros(3)])


def chain_from_urdf_joints(
    joints: Sequence[UrdfJoint], tool_xyz, tool_rpy=(0.0, 0.0, 0.0), name: str = "chain"
) -> Chain:
    """POE chain of a URDF-style serial chain (all joints in sequence, then a fixed tool joint).

    The joint frames at ``q = 0`` are the URDF joint frames composed from the base link;
    twists are their axes expressed in the base frame.
    """
    T = np.eye(4)
    twists, frames = [], []
    for joint in joints:
        local = np.eye(4)
        local[:3, :3] = np.asarray(rpy_matrix(np.asarray(joint.rpy, dtype=np.float64)))
        local[:3, 3] = joint.xyz
        T = T @ local
        axis = T[:3, :3] @ np.asarray(joint.axis, dtype=np.float64)
        axis /= np.linalg.norm(axis)
        twists.append(revolute_twist(axis, T[:3, 3]) if joint.kind == REVOLUTE else prismatic_twist(axis))
        frames.append(T.copy())
    tool = np.eye(4)
    tool[:3, :3] = np.asarray(rpy_matrix(np.asarray(tool_rpy, dtype=np.float64)))
    tool[:3, 3] = tool_xyz
    return make_chain(
        twists=np.stack(twists),
        T_base_tool0=T @ tool,
        lower=[j.lower for j in joints],
        upper=[j.upper for j in joints],
        kinds=[j.kind for j in joints],
        joint_names=[j.name for j in joints],
        T_base_joint0=np.stack(frames),
        velocity_limits=[j.velocity for j in joints],
        name=name,
    )


def with_dtype(chain: Chain, dtype) -> Chain:
    """The same chain with its geometry cast to ``dtype`` (float32 or float64)."""
    return jax.tree_util.tree_map(lambda x: jnp.asarray(x, dtype=dtype), chain)


def check_joint_array(chain: Chain, q, label: str = "q") -> Array:
    """Validate a joint array ``(..., n)``: last axis = number of joints; no NaN when concrete.

    The NaN check runs only on concrete (non-traced) input, so it costs nothing inside a
    user's ``jit`` and one reduction when called eagerly.
    """
    q = jnp.asarray(q)
    if q.ndim == 0 or q.shape[-1] != chain.n_joints:
        raise ValueError(
            f"{label} must have shape (..., {chain.n_joints}) for chain {chain.name!r}, got {q.shape}"
        )
    if not jnp.issubdtype(q.dtype, jnp.floating):
        q = q.astype(jnp.float32)
    if not isinstance(q, jax.core.Tracer) and bool(jnp.isnan(q).any()):
        raise ValueError(f"{label} contains NaN")
    return q
