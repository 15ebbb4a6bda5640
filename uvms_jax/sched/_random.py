"""Random instances for tests, benchmarks and synthetic studies (explicit PRNG keys)."""

from __future__ import annotations

from typing import Mapping, Sequence

import jax
import numpy as np

from uvms_jax.sched._problem import PickPlaceProblem
from uvms_jax.sched._rules import static_rules


def _rng(key: jax.Array) -> np.random.Generator:
    """A NumPy generator seeded from a JAX key (instances are built on the host)."""
    return np.random.default_rng(int(jax.random.randint(key, (), 0, 2**31 - 1)))


def random_problem(
    key: jax.Array,
    n_objects: int,
    n_bases: int,
    *,
    compat: Mapping[int, Sequence[int]] | None = None,
    bases_per_object: tuple[int, int] = (1, 2),
    nan_fraction: float = 0.0,
    max_tries: int = 100,
) -> PickPlaceProblem:
    """A random instance in the generalised thesis layout.

    Nodes: 0 start, objects ``1..N``, bases ``N+1..N+M``, goal ``N+M+1``. Costs are uniform
    in ``[0, 1)``; a base → goal move costs the same as base → start (the goal is the start
    geometrically, as in the thesis).

    Args:
      key: JAX PRNG key.
      n_objects, n_bases: ``N`` and ``M`` (``M >= N``).
      compat: object → allowed bases; default random: each object gets a distinct base (so
        a full placement exists) plus up to ``bases_per_object[1] - 1`` random extra bases,
        at least ``bases_per_object[0]`` in all.
      nan_fraction: fraction of allowed moves made NaN (forbidden); instances without a
        feasible schedule are redrawn.
      max_tries: redraws before giving up.

    Raises:
      ValueError: ``n_bases < n_objects`` or no feasible instance within ``max_tries``.
    """
    if n_bases < n_objects:
        raise ValueError(f"need at least as many bases as objects; got {n_objects} objects, {n_bases} bases")
    rng = _rng(key)
    N, M = n_objects, n_bases
    n = N + M + 2
    objects = list(range(1, N + 1))
    bases = list(range(N + 1, N + M + 1))
    if compat is None:
        own = rng.permutation(bases)[:N]
        compat = {}
        for o, b in zip(objects, own):
            k = int(rng.integers(bases_per_object[0], bases_per_object[1] + 1))
            extra = [x for x in rng.permutation(bases) if x != b][: max(k - 1, 0)]
            compat[o] = tuple(sorted([int(b), *map(int, extra)]))
    objs = sorted(compat)
    mask = static_rules(n, 0, n - 1, objs, bases, [compat[o] for o in objs])[:n, :n]
    last = None
    for _ in range(max_tries):
        c = rng.random((n, n))
        c[:, n - 1] = c[:, 0]
        drop = rng.random((n, n)) < nan_fraction
        drop[:, n - 1] = drop[:, 0]
        cost = np.where(mask & ~drop, c, np.nan)
        try:
            return PickPlaceProblem.from_matrix(cost, compat, start=0, goal=n - 1)
        except ValueError as e:  # infeasible draw
            last = e
    raise ValueError(f"no feasible random instance in {max_tries} tries: {last}")


def random_metrics(key: jax.Array, problem: PickPlaceProblem, *, object_mass_kg: float = 0.5) -> np.ndarray:
    """Synthetic raw edge metrics ``(5, n, n)`` for the moves of ``problem`` (NaN elsewhere).

    Not from any planner: node positions are drawn in a 2 × 2 × 1 m cage (start/goal above,
    objects on two tables, bases on two others, thesis 5.1) and each metric is a noisy
    function of the move — end-effector distance ≈ straight line × (1–1.6), joint movement
    ∝ distance, planning time log-normal growing with distance, clearance 2–20 cm, max
    torque from the carried object's weight at the reach (moves that carry an object only).
    Enough to exercise the weights pipeline (thesis Tables 5.6–5.9) without a planner.

    Returns:
      ``(5, n, n)`` raw metrics in ``METRICS`` order.
    """
    rng = _rng(key)
    n = problem.n_nodes
    pos = np.zeros((n, 3))
    pos[problem.start] = pos[problem.goal] = (0.0, 0.0, 0.9)
    for k, o in enumerate(problem.objects):
        pos[o] = (-0.6 + 1.2 * (k % 2), -0.6 + 0.15 * k, 0.1) + rng.normal(0, 0.05, 3)
    for k, b in enumerate(problem.bases):
        pos[b] = (-0.5 + 1.0 * (k % 2), 0.6 - 0.15 * k, 0.25) + rng.normal(0, 0.05, 3)
    mc = np.asarray(problem.move_cost)[:n, :n]
    src, dst = np.nonzero(np.isfinite(mc))
    line = np.linalg.norm(pos[src] - pos[dst], axis=1)
    ee = line * rng.uniform(1.0, 1.6, line.size)
    joints = 2.5 * ee * rng.uniform(0.8, 1.3, line.size)
    t_plan = 0.02 * np.exp(rng.normal(0.0, 0.5, line.size)) * (1 + 3 * line)
    clearance = rng.uniform(0.02, 0.20, line.size)
    carrying = np.isin(dst, problem.bases)
    reach = np.linalg.norm(pos[dst, :2], axis=1) + 0.3
    torque = np.where(carrying, object_mass_kg * 9.81 * reach, 0.3) * rng.uniform(0.9, 1.1, line.size)
    out = np.full((5, n, n), np.nan)
    for k, v in enumerate((t_plan, joints, ee, clearance, torque)):
        out[k, src, dst] = v
    return out
