"""The docking problem of Sotiropoulos, Aspragathos & Andritsos (2011), docs/theory.md §3.

Frames and units (written once): the global frame G sits at the centre of the block's top
face (z = 0 on the face), metres and radians. A candidate docking pose is the arm base pose
``[x, y, z, ψ]`` (position of B in G, yaw ψ about z of G). Everything here works on a whole
population at once: ``(..., 4)`` poses → ``(...)`` results, one jitted call over
individuals × control points × IK branches.
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
from flax import struct
from jax import Array

from uvms_jax import indices, kin
from uvms_jax.evo._fitness import FitnessInputs, Objective, make_objective, paper_weights
from uvms_jax.kin import Chain, docking_arm, with_dtype

Pose = Array  # (..., 4) [x, y, z, ψ] of the arm base in G [m, rad]
Fitness = Array  # (...)

YAW_MODES = ("heading", "fixed")


def base_transform(pose: Pose) -> Array:
    """``T_G_B (..., 4, 4)`` of candidate poses ``[x, y, z, ψ]`` (paper eq. 7)."""
    R = kin.axis_rotation(2, pose[..., 3])  # R_z(ψ) about z of G (paper eq. 6–7)
    top = jnp.concatenate([R, pose[..., :3, None]], axis=-1)
    bottom = jnp.broadcast_to(jnp.array([0.0, 0.0, 0.0, 1.0], dtype=pose.dtype), pose.shape[:-1] + (1, 4))
    return jnp.concatenate([top, bottom], axis=-2)


def docking_point(pose: Pose, p_bp: Array) -> Array:
    """Docking (suction-cup) point ``p_d = T_G_B(pose) · p_bp`` (paper eq. 5), ``(..., 3)`` [m]."""
    R = kin.axis_rotation(2, pose[..., 3])  # R_z(ψ) about z of G (paper eq. 6–7)
    return jnp.sum(R * p_bp[..., None, :], axis=-1) + pose[..., :3]


@struct.dataclass
class DockingProblem:
    """Immutable docking scene and objective (paper eq. 1, 3–8, 14–15).

    Attributes:
      chain: the 6R docking arm (tool point = wrist centre).
      p_control: ``(k, 3)`` control points in G [m] (4 corners K, L, M, N or a grid).
      task_center: ``(3,)`` centre of the square task area in G [m].
      task_half: half side of the task area [m].
      face_half: ``(2,)`` half extents of the block's top face along x, y [m].
      z_face: z of the top face in G [m] (``z_A`` of eq. 11; 0 by the frame convention).
      d: height margin of eq. 11 [m].
      p_i: ``(3,)`` initial vehicle base (suction cup) point in G (eq. 4) [m].
      p_bp: ``(3,)`` vehicle base point in B [m].
      objective: the fitness terms and their weights (eq. 8: ``a`` on M_a in m³-like units of
        w, ``b`` on D in m; :mod:`uvms_jax.evo._fitness`).
      tool_yaw: demanded tool yaw in G [rad] when ``yaw_mode == "fixed"``.
      yaw_mode: ``"heading"`` (tool z along the candidate's ψ, the default of docs/theory.md §3) or ``"fixed"``
        (static).
    """

    chain: Chain
    p_control: Array
    task_center: Array
    task_half: Array
    face_half: Array
    z_face: Array
    d: Array
    p_i: Array
    p_bp: Array
    objective: Objective
    tool_yaw: Array
    yaw_mode: str = struct.field(pytree_node=False, default="heading")

    @property
    def pose_low(self) -> Array:
        """``(4,)`` lower corner of the box that holds Wd (eq. 9–11) and ψ = −π."""
        return jnp.array([-self.face_half[0], -self.face_half[1], self.z_face, -jnp.pi], dtype=self.d.dtype)

    @property
    def pose_high(self) -> Array:
        """``(4,)`` upper corner of the box that holds Wd (eq. 9–11) and ψ = π."""
        return jnp.array([self.face_half[0], self.face_half[1], self.z_face + self.d, jnp.pi], dtype=self.d.dtype)

    def fitness(self, pose: Pose) -> Fitness:
        """Fitness of eq. 15 for ``(..., 4)`` poses (traceable; see :func:`evaluate`)."""
        return evaluate_traced(self, pose).fitness


def make_docking_problem(
    *,
    block_size: tuple[float, float, float],
    task_center: tuple[float, float, float],
    task_size: float,
    control_points_per_side: int,
    p_init: tuple[float, float, float],
    psi_init: float,
    p_bp: tuple[float, float, float],
    a: float,
    b: float,
    d: float,
    yaw_mode: str,
    tool_yaw: float,
    arm_lengths: tuple[float, float, float],
    terms: dict[str, float] | None = None,
    dtype=None,
) -> DockingProblem:
    """Build the docking problem from plain values (docs/theory.md §3). The paper's scene is
    ``configs/docking/scene/paper.yaml`` (:class:`~uvms_jax.evo.SceneSettings` holds the
    same defaults): ``make_docking_problem(**scene)``.

    Args:
      block_size: block extents along x, y, z [m]; G is the centre of the top face.
      task_center, task_size: square task area on the top face [m].
      control_points_per_side: 2 = the four corners (paper), n > 2 = an n×n grid.
      p_init, psi_init: initial arm base position [m] and yaw [rad] (eq. 6).
      p_bp: vehicle base point (suction cup) in B [m].
      a, b: weights of eq. 8 (the fitness terms ``manipulability`` and ``distance``).
      d: margin above the face for z (eq. 11) [m].
      yaw_mode, tool_yaw: tool yaw at the control points: ``"heading"`` follows ψ,
        ``"fixed"`` uses ``tool_yaw`` [rad] in G.
      arm_lengths: ``(l0, l1, l2)`` of the docking arm [m].
      terms: further registered fitness terms, name → weight (:func:`~uvms_jax.evo.register_fitness_term`).
      dtype: float dtype of the arrays (default: JAX's default float).

    Raises:
      ValueError: on non-positive sizes, a task area that does not fit the face, an unknown
        yaw mode or an unknown fitness term.
    """
    if yaw_mode not in YAW_MODES:
        raise ValueError(f"yaw_mode must be one of {YAW_MODES}, got {yaw_mode!r}")
    block = np.asarray(block_size, dtype=np.float64)
    if block.shape != (3,) or np.any(block <= 0):
        raise ValueError(f"block_size must be 3 positive lengths, got {block_size}")
    if task_size <= 0 or d <= 0:
        raise ValueError(f"task_size and d must be positive, got {task_size} and {d}")
    center = np.asarray(task_center, dtype=np.float64)
    if np.any(np.abs(center[:2]) + task_size / 2 > block[:2] / 2):
        raise ValueError(f"task area (centre {task_center}, size {task_size}) does not fit the top face {block[:2]}")
    dtype = dtype or jnp.zeros(()).dtype
    arr = lambda x: jnp.asarray(x, dtype=dtype)
    # Eq. 4 and 6: initial vehicle base point from the initial manipulator base pose.
    p_i = docking_point(arr([*p_init, psi_init]), arr(p_bp))
    return DockingProblem(
        chain=with_dtype(docking_arm(*arm_lengths), dtype),
        p_control=arr(indices.control_points(center, task_size, control_points_per_side)),
        task_center=arr(center),
        task_half=arr(task_size / 2),
        face_half=arr(block[:2] / 2),
        z_face=arr(center[2]),
        d=arr(d),
        p_i=p_i,
        p_bp=arr(p_bp),
        objective=make_objective(paper_weights(a, b, terms), dtype),
        tool_yaw=arr(tool_yaw),
        yaw_mode=yaw_mode,
    )


def in_search_set(problem: DockingProblem, pose: Pose) -> Array:
    """Membership of Wd (eq. 14): on the top face, ``z_A ≤ z ≤ z_A + d``, outside the task area."""
    x, y, z = pose[..., 0], pose[..., 1], pose[..., 2]
    on_face = (jnp.abs(x) <= problem.face_half[0]) & (jnp.abs(y) <= problem.face_half[1])
    in_height = (z >= problem.z_face) & (z <= problem.z_face + problem.d)
    over_task = (jnp.abs(x - problem.task_center[0]) < problem.task_half) & (
        jnp.abs(y - problem.task_center[1]) < problem.task_half
    )
    return on_face & in_height & ~over_task


def tool_rotation(problem: DockingProblem, psi: Array) -> Array:
    """Demanded ``R_G_tool (..., 3, 3)`` at the control points: approach down, yaw per mode."""
    yaw = psi if problem.yaw_mode == "heading" else jnp.broadcast_to(problem.tool_yaw, psi.shape)
    return indices.approach_down(yaw)


class DockingEval(NamedTuple):
    """Per-candidate terms of the objective, each ``(...)``.

    Attributes:
      fitness: eq. 15 (the problem's objective, ``a·M_a − b·D`` by default, inside Wd; 0 outside).
      M_a: area manipulability, eq. 1.
      D: distance from the initial to the proposed vehicle base point, eq. 3 [m].
      feasible: membership of Wd, eq. 14.
    """

    fitness: Array
    M_a: Array
    D: Array
    feasible: Array


def _area_inputs(problem: DockingProblem, pose: Array) -> tuple[Array, Array]:
    """Arguments of :func:`uvms_jax.indices.area_manipulability` for base poses ``(..., 4)``:
    ``T_G_B (..., 4, 4)`` and the demanded tool orientation ``(..., 1, 3, 3)`` in G."""
    return base_transform(pose), tool_rotation(problem, pose[..., 3])[..., None, :, :]


def _terms(problem: DockingProblem, pose: Array, M_a: Array) -> DockingEval:
    """Objective terms of base poses ``(..., 4)`` from their area manipulability ``M_a (...)``."""
    D = jnp.linalg.norm(docking_point(pose, problem.p_bp) - problem.p_i, axis=-1)  # eq. 3
    feasible = in_search_set(problem, pose)  # eq. 14
    fitness = problem.objective(FitnessInputs(pose, M_a, D), feasible)  # eq. 15
    return DockingEval(fitness=fitness, M_a=M_a, D=D, feasible=feasible)


def evaluate_traced(problem: DockingProblem, pose: Array) -> DockingEval:
    """:func:`evaluate` for use inside ``jit``/``vmap``/loops (no input checks, no padding).

    One :func:`uvms_jax.indices.area_manipulability` call covers individuals × control
    points × IK branches.
    """
    T_world_base, R_world_tool = _area_inputs(problem, pose)
    M_a = indices.area_manipulability(problem.chain, T_world_base, problem.p_control, R_world_tool)
    return _terms(problem, pose, M_a)


_area_inputs_jit = jax.jit(_area_inputs)
_terms_jit = jax.jit(_terms)


def evaluate(problem: DockingProblem, pose) -> DockingEval:
    """Objective terms of candidate poses (paper eq. 1, 3, 8, 14, 15).

    Eager entry point with input checks; inside ``jit`` use :func:`evaluate_traced` or
    ``problem.fitness``.

    Args:
      problem: the scene.
      pose: ``(..., 4)`` candidate arm base poses ``[x, y, z, ψ]`` in G [m, rad].

    Returns:
      :class:`DockingEval` with fields of shape ``(...)``.
    """
    pose = jnp.asarray(pose, dtype=problem.d.dtype)
    if pose.ndim == 0 or pose.shape[-1] != 4:
        raise ValueError(f"pose must have shape (..., 4) = [x, y, z, psi], got {pose.shape}")
    if isinstance(pose, jax.core.Tracer):
        return evaluate_traced(problem, pose)
    if bool(jnp.isnan(pose).any()):
        raise ValueError("pose contains NaN")
    flat = pose.reshape((-1, 4))
    T_world_base, R_world_tool = _area_inputs_jit(problem, flat)
    M_a = indices.area_manipulability(problem.chain, T_world_base, problem.p_control, R_world_tool)
    out = _terms_jit(problem, flat, M_a)
    return jax.tree_util.tree_map(lambda x: x.reshape(pose.shape[:-1]), out)
