"""Map of the best manipulability over the task area for one docking pose (paper eq. 16)."""

from __future__ import annotations

from typing import NamedTuple

import jax.numpy as jnp
import numpy as np

from uvms_jax import indices
from uvms_jax.evo._problem import DockingProblem, _area_inputs_jit


class WmaxMap(NamedTuple):
    """``w_max`` over a regular grid of the task area.

    Attributes:
      x, y: ``(n,)`` grid coordinates in G [m] (task-area edges included).
      w_max: ``(n, n)`` best manipulability over the valid IK branches at ``(x[i], y[j])``
        (eq. 16); 0 where no branch is valid.
      zero_fraction: share of grid points with ``w_max = 0`` (area with no valid branch).
    """

    x: np.ndarray
    y: np.ndarray
    w_max: np.ndarray
    zero_fraction: float


def wmax_map(problem: DockingProblem, pose, n_per_side: int = 41) -> WmaxMap:
    """``w_max`` (eq. 16) on an ``n_per_side × n_per_side`` grid of the task area for the arm
    base at ``pose (4,) = [x, y, z, ψ]``, with the problem's tool orientation at every point.

    The same computation as M_a (eq. 1) with the grid as control points, before the min.
    """
    pose = jnp.asarray(pose, dtype=problem.d.dtype)
    if pose.shape != (4,) or bool(jnp.isnan(pose).any()):
        raise ValueError(f"pose must be 4 finite numbers [x, y, z, psi], got {pose}")
    if n_per_side < 2:
        raise ValueError(f"n_per_side must be >= 2, got {n_per_side}")
    c, h = np.asarray(problem.task_center), float(problem.task_half)
    x = c[0] + np.linspace(-h, h, n_per_side)
    y = c[1] + np.linspace(-h, h, n_per_side)
    gx, gy = np.meshgrid(x, y, indexing="ij")
    points = np.stack([gx.ravel(), gy.ravel(), np.full(gx.size, c[2])], axis=-1)
    T_world_base, R_world_tool = _area_inputs_jit(problem, pose)
    T_base_tool = indices.tool_targets(T_world_base, jnp.asarray(points, dtype=pose.dtype), R_world_tool)
    w = np.asarray(indices.max_branch_manipulability(problem.chain, T_base_tool))
    w = w.reshape(n_per_side, n_per_side)
    return WmaxMap(x=x, y=y, w_max=w, zero_fraction=float(np.mean(w <= 0.0)))
