"""Poses at and near a chain's singularities: samples for checking indices where they are hardest."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

from uvms_jax.indices._indices import task_rows
from uvms_jax.kin import Chain, jacobian

#: Joint values a search starts from lie within ±this of zero where a joint's limits are wider [rad].
START_RANGE = 3.0


def near_singular_poses(chain: Chain, n: int, task="full", *, seed: int = 0, within: float = 1e-3,
                        steps: int = 12) -> tuple[np.ndarray, np.ndarray]:
    """``(on, near)``, each ``(n, dof)``: poses walked onto the singular set of ``chain``'s
    Jacobian in a task space, and one pose within ``within`` [rad] of each.

    The walk takes Newton steps on the smallest singular value ``σ_min`` of J (its gradient
    through JAX's SVD, in the dtype x64 allows): near a set where J loses rank, ``σ_min`` grows
    like the distance to it, so a step ``−σ_min ∇σ_min / |∇σ_min|²`` lands on it. Starts are
    uniform in the joint limits (within ±3 rad); poses are clipped to the limits, so where a
    limit stops a walk the pose lies only toward the set. A square J is rank-deficient on a
    set of codimension 1 and nearly every walk arrives; a redundant or tall J less often.

    Args:
      chain: any chain; task: rows of the geometric Jacobian (see :func:`task_rows`).
      n: poses of each kind; seed: of the starts and of the offsets.
      within: the largest offset [rad]; directions uniform, lengths uniform in [0, within].
      steps: Newton steps.
    """
    rows = jnp.asarray(task_rows(task))
    rng = np.random.default_rng(seed)
    lower, upper = np.asarray(chain.lower), np.asarray(chain.upper)
    lo, hi = np.maximum(lower, -START_RANGE), np.minimum(upper, START_RANGE)
    sigma_min = lambda q: jnp.linalg.svd(jacobian(chain, q)[rows], compute_uv=False)[-1]  # noqa: E731
    sigma, grad = jax.jit(jax.vmap(sigma_min)), jax.jit(jax.vmap(jax.grad(sigma_min)))
    q = jnp.asarray(lo + rng.random((n, chain.n_joints)) * (hi - lo))
    for _ in range(steps):
        g = grad(q)
        q = q - (sigma(q) / jnp.maximum(jnp.sum(g * g, -1), 1e-30))[:, None] * g
    on = np.clip(np.asarray(q, np.float64), lower, upper)
    step = rng.normal(size=on.shape)
    near = on + step / np.linalg.norm(step, axis=1, keepdims=True) * rng.random((n, 1)) * within
    return on, np.clip(near, lower, upper)
