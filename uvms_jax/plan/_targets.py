"""Pick-and-place targets: the arm configurations of the eight steps at every object and base.

The thesis (4.4) splits one pick and place into eight steps: pre-grasp, open, grasp, close,
post-grasp (at the object), pre-final, final, post-final (at the base). Here the pre- and post-
poses coincide (``approach`` back along the approach axis from the grasp/final pose), so a
node has two arm configurations: ``q_pre`` (where the arm arrives and leaves) and ``q_at``
(grasp or final). Gripper steps (open, close, and the release at the final pose) do not move
the arm.

All tool poses of all nodes and of every symmetric yaw of the object go through one batched
numerical IK call (:func:`uvms_jax.kin.numeric_ik`, many seeds per target). For every yaw and
seed the grasp solution is paired with the nearest pre-pose solution (same IK branch), and the
pair is kept only if both are inside the limits and collision-free in the contexts of the
step (approach with the object ignored, lift with the object held, …) and the straight
joint-space segment between them is collision-free. Among those, the pair of highest
manipulability ``min(w(q_pre), w(q_at))`` wins.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping

import jax
import jax.numpy as jnp
import numpy as np

from uvms_jax import frames, indices, kin
from uvms_jax.plan._collision import CollisionChecker
from uvms_jax.plan._scene import Context, Scene
from uvms_jax.plan._settings import IkSettings

__all__ = ["NodeTarget", "STEPS", "node_contexts", "pick_place_targets", "tool_poses"]

#: The eight pick-and-place steps (thesis 4.4): object steps then base steps.
STEPS = ("pre-grasp", "open", "grasp", "close", "post-grasp", "pre-final", "final", "post-final")


@dataclasses.dataclass(frozen=True)
class NodeTarget:
    """Arm configurations of one object or base node.

    Attributes:
      node: node number.
      q_pre: (6,) pre-grasp = post-grasp (object) or pre-final = post-final (base) [rad].
      q_at: (6,) grasp or final configuration [rad].
      T_world_pre, T_world_at: (4, 4) the corresponding tool poses (world frame).
      yaw: object yaw of the chosen grasp about its axis [rad].
      manipulability: min(w(q_pre), w(q_at)).
      n_candidates: valid (yaw, seed) pairs found.
    """

    node: int
    q_pre: np.ndarray
    q_at: np.ndarray
    T_world_pre: np.ndarray
    T_world_at: np.ndarray
    yaw: float
    manipulability: float
    n_candidates: int


def _shift(z: float) -> np.ndarray:
    T = np.eye(4)
    T[2, 3] = z
    return T


def _yaws(period: float, n_continuous: int) -> np.ndarray:
    n = n_continuous if period == 0.0 else int(round(2 * np.pi / period))
    return np.arange(n) * 2 * np.pi / n


def tool_poses(scene: Scene, node: int, n_yaw_continuous: int = 8) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Candidate tool poses of a node, one per symmetric yaw of its object.

    Returns:
      yaws ``(k,)`` [rad], ``T_world_at (k, 4, 4)`` (grasp/final) and ``T_world_pre (k, 4, 4)``.
    """
    if node in scene.objects:
        obj, T_obj = node, scene.T_world_object(node)
    elif node in scene.bases:
        obj = scene.bases[node].fits[0]
        T_obj = scene.T_world_placed(node, obj)
    else:
        raise ValueError(f"node {node} is neither an object {sorted(scene.objects)} nor a base {sorted(scene.bases)}")
    yaws = _yaws(scene.objects[obj].symmetry, n_yaw_continuous)
    T_obj_tool = np.linalg.inv(scene.T_tool_obj_for(obj))
    at = np.stack([T_obj @ frames.pose(frames.rot_z(y)) @ T_obj_tool for y in yaws])
    pre = at @ _shift(-scene.spec.approach)
    return yaws, at, pre


def node_contexts(scene: Scene, node: int) -> dict[str, Context]:
    """Collision contexts of a node's moves.

    Keys: ``arrive`` and ``leave`` (at ``q_pre``), ``down`` (pre → at, before the gripper
    acts) and ``up`` (at → pre, after it). At an object the arm arrives empty, goes down with
    the object ignored, and lifts it (held; its table ignored while they touch). At a base it
    arrives holding the object, goes down with base and table ignored, and leaves empty.
    """
    if node in scene.objects:
        table = scene.objects[node].table
        return {"arrive": Context(), "down": Context(ignore=(node,)),
                "up": Context(held=node, ignore=(table,)), "leave": Context(held=node)}
    if node in scene.bases:
        obj, table = scene.bases[node].fits[0], scene.bases[node].table
        return {"arrive": Context(held=obj), "down": Context(held=obj, ignore=(node, table)),
                "up": Context(ignore=(node,)), "leave": Context()}
    raise ValueError(f"node {node} is neither an object nor a base")


def _valid(checker: CollisionChecker, ctx: Context, q: np.ndarray) -> bool:
    return checker.is_valid(q, ctx)


def _segment_valid(checker: CollisionChecker, ctx: Context, a, b, resolution: float) -> bool:
    return checker.path_is_valid(np.stack([a, b]), ctx, resolution)


def _node_name(scene: Scene, node: int) -> str:
    return scene.objects[node].name if node in scene.objects else scene.bases[node].name


def _first_contact(checker: CollisionChecker, ctx: Mapping[str, Context], pre, at) -> str:
    """The first contact of a rejected target pair, in words (at the pre or the grasp
    configuration, or on the segment between them)."""
    for key, q in (("arrive", pre), ("leave", pre), ("down", at), ("up", at)):
        found = checker.contacts(q, ctx[key])
        if found:
            a, b, dist = found[0]
            return f"{a} against {b} ({1e3 * -dist:.0f} mm deep) at the {'pre' if q is pre else 'grasp'} pose"
    return "the move between the pre and the grasp pose collides"


def _unreachable(scene: Scene, T_world_at: np.ndarray, n_solved: int, n_paired: int, collision: str | None,
                 n_tries: int, max_branch_jump: float) -> str:
    """Why no target pair of a node is valid: out of reach (by how much), no IK solution, a
    branch jump, or a collision (the first contact)."""
    distance = float(np.min(np.linalg.norm(T_world_at[:, :3, 3] - scene.T_world_base[:3, 3], axis=-1)))
    reach = scene.robot.max_reach
    if n_solved == 0:
        if distance > reach:
            return (f"out of reach: its grasp pose is {distance:.3f} m from the arm's base, {distance - reach:.3f} m "
                    f"beyond the arm's longest reach ({reach:.3f} m)")
        return (f"no IK solution within the joint limits for the grasp and its pre pose ({n_tries} tries; "
                f"{distance:.3f} m from the base, reach {reach:.3f} m)")
    if n_paired == 0:
        return f"every grasp solution is more than ik.max_branch_jump = {max_branch_jump} rad from its pre pose"
    return f"in collision: every IK solution collides, e.g. {collision}"


def _nearest_turn(q: np.ndarray, q_ref: np.ndarray, robot) -> np.ndarray:
    """Revolute angles ``q (..., n)`` moved by whole turns to the value nearest ``q_ref (n,)``
    within the limits: a joint whose range spans more than a turn reaches a pose at several
    angles, and the one nearest the start keeps the moves between targets short."""
    revolute = np.array([k == "revolute" for k in robot.chain.kinds])
    turns = np.round((q_ref - q) / (2 * np.pi))
    shifted = q + 2 * np.pi * turns
    for step in (-1.0, 1.0):  # back inside the limits where the nearest turn lies beyond one
        outside = (shifted < robot.lower) if step > 0 else (shifted > robot.upper)
        shifted = np.where(outside, shifted + step * 2 * np.pi, shifted)
    inside = (shifted >= robot.lower) & (shifted <= robot.upper)
    return np.where(revolute & inside & np.isfinite(q), shifted, q)


def pick_place_targets(
    key: jax.Array,
    scene: Scene,
    checker: CollisionChecker,
    ik: IkSettings = IkSettings(),
    resolution: float = 0.01,
) -> dict[int, NodeTarget]:
    """Solve the targets of every object and base node by batched numerical IK.

    Args:
      key: PRNG key for the IK seeds.
      scene, checker: the scene and its collision checker (each check names its context,
        :func:`node_contexts`).
      ik: seeds and iterations of the numerical IK, yaws of a symmetric object, the largest
        joint change between ``q_pre`` and ``q_at``, and which valid pair is kept.
      resolution: joint step [rad] of the segment check between ``q_pre`` and ``q_at``.

    Returns:
      node → :class:`NodeTarget`.

    Raises:
      ValueError: a node has no valid, collision-free target pair (names the node).
    """
    chain = scene.robot.chain
    nodes = sorted(scene.objects) + sorted(scene.bases)
    per_node = [tool_poses(scene, n, ik.n_yaw_continuous) for n in nodes]
    T_world = np.concatenate([np.stack([at, pre], axis=1) for _, at, pre in per_node])  # (K, 2, 4, 4)
    T_base = scene.T_base_world @ T_world
    sol = kin.numeric_ik(key, chain, jnp.asarray(T_base), n_seeds=ik.n_seeds, iterations=ik.iterations, all_seeds=True)
    q_all = _nearest_turn(np.asarray(sol.q), scene.start_q, scene.robot)  # (K, 2, S, n)
    ok_all = np.asarray(sol.valid)
    w_all = np.asarray(indices.manipulability(kin.jacobian(chain, jnp.nan_to_num(jnp.asarray(q_all)))))
    out: dict[int, NodeTarget] = {}
    row = 0
    for node, (yaws, at, pre) in zip(nodes, per_node):
        ctx = node_contexts(scene, node)
        best, n_ok, n_solved, n_paired, collision = None, 0, 0, 0, None
        for k in range(len(yaws)):
            q_at, q_pre = q_all[row + k, 0], q_all[row + k, 1]
            ok_at, ok_pre = ok_all[row + k, 0], ok_all[row + k, 1]
            n_solved += int(ok_at.any() and ok_pre.any())
            if not ok_pre.any():
                continue
            pre_idx = np.flatnonzero(ok_pre)
            tried: set[tuple[int, int]] = set()
            for s in np.flatnonzero(ok_at):
                jump = np.max(np.abs(q_pre[pre_idx] - q_at[s]), axis=1)
                j = pre_idx[int(np.argmin(jump))]
                if jump.min() > ik.max_branch_jump or (s, j) in tried:
                    continue
                tried.add((s, j))
                n_paired += 1
                w = float(min(w_all[row + k, 0, s], w_all[row + k, 1, j]))
                score = -float(np.max(np.abs(q_pre[j] - scene.start_q))) if ik.select == "nearest_start" else w
                a, p = q_at[s], q_pre[j]
                if not (_valid(checker, ctx["arrive"], p) and _valid(checker, ctx["leave"], p)
                        and _valid(checker, ctx["down"], a) and _valid(checker, ctx["up"], a)
                        and _segment_valid(checker, ctx["down"], p, a, resolution)
                        and _segment_valid(checker, ctx["up"], a, p, resolution)):
                    collision = collision or _first_contact(checker, ctx, p, a)
                    continue
                n_ok += 1
                if best is None or score > best[0]:
                    best = (score, k, a.copy(), p.copy(), w)
        row += len(yaws)
        if best is None:
            why = _unreachable(scene, at, n_solved, n_paired, collision, len(yaws) * ik.n_seeds, ik.max_branch_jump)
            raise ValueError(f"node {node} ({_node_name(scene, node)}): {why}; arm {scene.robot.name!r} with its "
                             f"base at {np.round(scene.T_world_base[:3, 3], 3).tolist()} m")
        _, k, a, p, w = best
        out[node] = NodeTarget(node, p, a, pre[k], at[k], float(yaws[k]), w, n_ok)
    return out
