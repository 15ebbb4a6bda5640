"""Batch scoring of candidate schedules: cost and a reason code, in one jitted call."""

from __future__ import annotations

import enum
from typing import NamedTuple

import jax
import jax.numpy as jnp
from jax import Array

from uvms_jax.sched._problem import PickPlaceProblem
from uvms_jax.sched._rules import BASE, OBJECT, allowed_next, consumed


class Reason(enum.IntEnum):
    """Why a schedule is invalid (the first failing check, in this order); OK = valid."""

    OK = 0
    UNKNOWN_NODE = 1  #: a node index outside 0..n-1 (and not the padding -1)
    NOT_FROM_START = 2  #: the first node is not the start
    NO_GOAL = 3  #: the goal is missing or appears more than once
    OBJECT_NOT_PLACED_ONCE = 4  #: some object is missing or picked twice
    BASE_REUSED = 5  #: a base receives two objects
    MOVE_RULE = 6  #: a move the rules forbid (incl. an incompatible base, padding inside,
    #: the start once every object is placed)
    FORBIDDEN_EDGE = 7  #: a move whose cost is NaN


class Scores(NamedTuple):
    """Attributes: cost ``(...,)`` float32 (``inf`` unless valid); reason ``(...,)`` int32
    (``Reason`` codes)."""

    cost: Array
    reason: Array


@jax.jit
def score(problem: PickPlaceProblem, paths: Array) -> Scores:
    """Scores a batch of schedules in one jitted call.

    A schedule is valid when it starts at the start, every move is one that
    ``_rules.allowed_next`` allows at that point (replayed from the start: compatibility,
    free bases, goal only once all objects are placed, NaN costs) and it reaches the goal;
    padding may follow the goal. The reason of an invalid schedule is the first whole-path
    check it fails, in the order of ``Reason``.

    Args:
      problem: the instance.
      paths: ``(..., L)`` int node sequences padded with ``-1`` after the goal
        (see ``as_padded_paths``); any ``L >= 2``.

    Returns:
      ``Scores`` with ``(...,)`` cost (float32) and reason code.
    """
    paths = jnp.asarray(paths)
    n = problem.n_nodes
    unknown = jnp.any((paths < -1) | (paths >= n), axis=-1)
    p = jnp.where((paths < 0) | (paths >= n), n, paths)  # padding (and unknown) → node n
    W = jnp.asarray(problem.move_cost, jnp.float32)
    rule = jnp.asarray(problem.rule)
    a, b = p[..., :-1], p[..., 1:]
    moves = W[a, b]
    counts = jnp.sum(p[..., :, None] == jnp.arange(n)[None, :], axis=-2)  # (..., n)
    kind = jnp.asarray(problem.kind[:n])
    allowed = _moves_allowed(problem, p)
    flags = jnp.stack(
        [
            unknown,
            p[..., 0] != problem.start,
            counts[..., problem.goal] != 1,
            jnp.any((kind == OBJECT) & (counts != 1), axis=-1),
            jnp.any((kind == BASE) & (counts > 1), axis=-1),
            ~jnp.all(rule[a, b], axis=-1),
            ~jnp.all(jnp.isfinite(moves), axis=-1),
            ~allowed,  # implied by the checks above; named MOVE_RULE should one ever slip by
        ],
        axis=-1,
    )
    bad = jnp.any(flags, axis=-1)
    code = jnp.array([*range(Reason.UNKNOWN_NODE, Reason.FORBIDDEN_EDGE + 1), Reason.MOVE_RULE], jnp.int32)
    reason = jnp.where(bad, code[jnp.argmax(flags, axis=-1)], Reason.OK).astype(jnp.int32)
    cost = jnp.where(bad, jnp.inf, jnp.sum(moves, axis=-1))
    return Scores(cost, reason)


def _moves_allowed(problem: PickPlaceProblem, p: Array) -> Array:
    """``(...,)`` bool: every move of each path (``(..., L)``, padding = node ``n``) is one
    ``allowed_next`` allows in the state the path has reached. All moves at once: before move
    ``t`` the path has visited what nodes ``0..t`` entered and placed as many objects as it
    entered bases; only the entry of ``allowed_next`` for the node moved to is needed, so the
    rule is asked with the table and ``visited`` restricted to that node."""
    kind = jnp.asarray(problem.kind)
    table = jnp.asarray(problem.next_ok)
    src, dst = p[..., :-1], p[..., 1:]
    steps = jnp.arange(src.shape[-1])
    seen = jnp.any((src[..., None, :] == dst[..., :, None]) & (steps[None, :] <= steps[:, None]), axis=-1)
    visited = seen & consumed(kind)[dst]  # (..., L-1): the node moved to was entered before
    placed = jnp.cumsum(kind[src] == BASE, axis=-1)

    def one(a, b, v, k):
        return allowed_next(table[:, :, b], a, v, k, problem.n_objects)

    ok = jnp.vectorize(one)(src, dst, visited, placed)
    return jnp.all(ok, axis=-1)
