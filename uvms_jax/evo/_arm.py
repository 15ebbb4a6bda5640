"""Docking for any arm: area manipulability by batched multi-seed numerical IK (docs/docking.md).

The docking paper's problem (docs/theory.md §3) generalised: the arm hangs from a vehicle
through a fixed mount ``T_vehicle_base``; the free vehicle DOFs are ``[x, y, z, ψ]`` (the
vehicle frame V in the world W, yaw ψ about z of W); the task is data, a set of demanded
tool poses ``T_world_tool (k, 4, 4)``, grouped into ``g`` targets (the poses of one group
are alternatives, e.g. the symmetric grasps of an object). For a vehicle pose:

- every pose of every target is solved by damped least squares from the same ``S`` fixed
  seeds (one jitted call over poses × targets × seeds, a fixed number of iterations);
- a seed's solution counts when FK reaches the demanded pose, every joint lies within its
  limits (revolute angles are only shifted by multiples of 2π, never clipped) and it is free
  in the collision world of its target (:mod:`uvms_jax.evo._world`: the planner's spheres,
  pairs and margin when the task brings them, else the link capsules as spheres against the
  vehicle's and the scene's boxes);
- ``w`` of a target is the best manipulability over its valid solutions (0 if none), and
  ``M_a = min over targets`` (the paper's eq. 1 aggregation);
- the fitness is the paper's eq. 15 (the problem's :class:`~uvms_jax.evo.Objective`), with
  ``D`` the distance of the vehicle's docking point from its initial position and the search
  set Wd = the pose box, minus poses where the vehicle body meets the scene.

The same seeds for every pose make the fitness a deterministic function of the pose (the
GA's fitness cache and the grid comparison rely on it).
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
from flax import struct
from jax import Array

from uvms_jax import indices, kin
from uvms_jax.evo._collide import boxes_overlap
from uvms_jax.evo._fitness import FitnessInputs, Objective, make_objective, paper_weights
from uvms_jax.evo._problem import DockingEval, base_transform
from uvms_jax.evo._geometry import SphereWorld
from uvms_jax.evo._world import capsule_world, world_collides
from uvms_jax.kin import Chain
from uvms_jax.robot import SPHERE_SPACING


@struct.dataclass
class ArmDockingProblem:
    """Immutable docking scene and objective for any serial arm (module docstring).

    Attributes:
      chain: the arm (tool frame = the frame the targets demand).
      T_vehicle_base: ``(4, 4)`` arm base in the vehicle frame V (the mount) [m].
      T_world_tool: ``(k, 4, 4)`` demanded tool poses in the world W [m].
      group: ``(k,)`` target index of each pose, ``0 … n_groups − 1``.
      seeds: ``(S, n)`` IK seeds inside the joint limits [rad or m].
      pose_low, pose_high: ``(4,)`` box of vehicle poses ``[x, y, z, ψ]`` [m, rad].
      p_dock: ``(3,)`` docking point of the vehicle in V [m] (D of eq. 3 is measured there).
      p_i: ``(3,)`` initial position of the docking point in W [m].
      objective: the fitness terms and their weights (eq. 8: ``a``, ``b``; :mod:`uvms_jax.evo._fitness`).
      world: the arm's collision world, one row per target (:class:`~uvms_jax.evo.SphereWorld`).
      T_vehicle_box, vehicle_half: ``(mv, 4, 4), (mv, 3)`` vehicle body boxes in V [m].
      T_world_box, scene_half: ``(ms, 4, 4), (ms, 3)`` scene boxes (panel, tables) in W [m]:
        the vehicle's body must not meet them (Wd).
      damping: DLS damping; λ² = damping² (‖e‖² + 10⁻⁶).
      n_groups: number of targets g (static).
      iterations: DLS iterations per seed (static).
    """

    chain: Chain
    T_vehicle_base: Array
    T_world_tool: Array
    group: Array
    seeds: Array
    pose_low: Array
    pose_high: Array
    p_dock: Array
    p_i: Array
    objective: Objective
    world: SphereWorld
    T_vehicle_box: Array
    vehicle_half: Array
    T_world_box: Array
    scene_half: Array
    damping: Array
    n_groups: int = struct.field(pytree_node=False)
    iterations: int = struct.field(pytree_node=False)

    def fitness(self, pose: Array) -> Array:
        """Fitness of eq. 15 for ``(..., 4)`` vehicle poses (traceable)."""
        return evaluate_arm_traced(self, pose).fitness


def make_arm_docking_problem(
    *,
    chain: Chain,
    T_vehicle_base,
    T_world_tool,
    group=None,
    low,
    high,
    p_dock,
    p_i,
    a: float,
    b: float,
    link_radius: float,
    terms: dict[str, float] | None = None,
    vehicle_boxes=((), ()),
    scene_boxes=((), ()),
    world: SphereWorld | None = None,
    n_seeds: int = 16,
    iterations: int = 40,
    damping: float = 1.0,
    seed: int = 0,
    dtype=None,
) -> ArmDockingProblem:
    """Build and check an :class:`ArmDockingProblem` from plain arrays.

    Args:
      chain: the arm.
      T_vehicle_base: ``(4, 4)`` mount: arm base in the vehicle frame [m].
      T_world_tool: ``(k, 4, 4)`` demanded tool poses in the world [m].
      group: ``(k,)`` target of each pose (default: each pose its own target).
      low, high: ``(4,)`` box of vehicle poses ``[x, y, z, ψ]`` [m, rad].
      p_dock: ``(3,)`` docking point in the vehicle frame [m]; p_i: its initial world position.
      a, b: weights of eq. 8 (the fitness terms ``manipulability`` and ``distance``).
      link_radius: capsule radius of the links [m] (the collision world without ``world``).
      terms: further registered fitness terms, name → weight (:func:`~uvms_jax.evo.register_fitness_term`).
      vehicle_boxes: ``(T_vehicle_box (mv, 4, 4), half (mv, 3))`` in the vehicle frame.
      scene_boxes: ``(T_world_box (ms, 4, 4), half (ms, 3))`` in the world.
      world: the collision world, one row per target (e.g. the planner's,
        :func:`uvms_jax.plan.docking_world`); None: :func:`~uvms_jax.evo.capsule_world` of
        the chain, ``link_radius`` and the boxes.
      n_seeds, iterations, damping: numerical IK (seeds uniform in the limits, from ``seed``).
      dtype: float dtype (default: JAX's default float).

    Raises:
      ValueError: on wrong shapes, an empty box, a bad grouping, non-positive sizes, a
        world whose rows are not the targets or an unknown fitness term.
    """
    dtype = dtype or jnp.zeros(()).dtype
    arr = lambda x: _on_device(np.asarray(x, dtype=np.float64), dtype)
    T_tool, group = _checked_targets(T_world_tool, group)
    mount = np.asarray(T_vehicle_base, dtype=np.float64)
    if mount.shape != (4, 4):
        raise ValueError(f"T_vehicle_base must have shape (4, 4), got {mount.shape}")
    low, high = np.asarray(low, dtype=np.float64), np.asarray(high, dtype=np.float64)
    if low.shape != (4,) or high.shape != (4,) or np.any(low > high):
        raise ValueError(f"pose box must be two (4,) corners with low <= high, got {low} and {high}")
    if link_radius <= 0 or n_seeds < 1 or iterations < 1 or damping <= 0:
        raise ValueError(f"need link_radius > 0, n_seeds >= 1, iterations >= 1, damping > 0, got "
                         f"{link_radius}, {n_seeds}, {iterations}, {damping}")
    boxes = [tuple(arr(x) for x in _checked_boxes(label, given))
             for label, given in (("vehicle_boxes", vehicle_boxes), ("scene_boxes", scene_boxes))]
    n_groups = int(group.max()) + 1
    if world is None:
        world = capsule_world(chain, link_radius, mount, vehicle_boxes, scene_boxes, n_groups, SPHERE_SPACING, dtype)
    world = _checked_world(world, chain, n_groups, dtype)
    lo, up = np.asarray(chain.lower, dtype=np.float64), np.asarray(chain.upper, dtype=np.float64)
    u = np.asarray(jax.random.uniform(jax.random.key(seed), (n_seeds, chain.n_joints), dtype=jnp.float32))
    return ArmDockingProblem(
        chain=jax.tree_util.tree_map(lambda x: _on_device(x, dtype), chain), T_vehicle_base=arr(mount),
        T_world_tool=arr(T_tool),
        group=jnp.asarray(group, dtype=jnp.int32), seeds=arr(lo + u * (up - lo)), pose_low=arr(low),
        pose_high=arr(high), p_dock=arr(p_dock), p_i=arr(p_i),
        objective=make_objective(paper_weights(a, b, terms), dtype), world=world,
        T_vehicle_box=boxes[0][0], vehicle_half=boxes[0][1], T_world_box=boxes[1][0], scene_half=boxes[1][1],
        damping=arr(damping), n_groups=n_groups, iterations=int(iterations),
    )


def _on_device(x, dtype) -> Array:
    """``x`` cast to ``dtype`` on the host (NumPy rounds as XLA does), then put on the device: a
    cast on the device, like ``jnp.asarray`` of a NumPy array, compiles a program per shape,
    some 25 while a problem is built; ``jax.device_put`` compiles none."""
    return jax.device_put(np.asarray(x).astype(jnp.dtype(dtype)))


def _checked_targets(T_world_tool, group) -> tuple[np.ndarray, np.ndarray]:
    """``T_world_tool (k, 4, 4)`` and ``group (k,)`` (default: each pose its own target) as
    NumPy arrays, or a ValueError naming what is wrong."""
    T_tool = np.asarray(T_world_tool, dtype=np.float64)
    if T_tool.ndim != 3 or T_tool.shape[1:] != (4, 4) or T_tool.shape[0] < 1:
        raise ValueError(f"T_world_tool must have shape (k, 4, 4) with k >= 1, got {T_tool.shape}")
    if not np.all(np.isfinite(T_tool)):
        raise ValueError("T_world_tool contains NaN or infinite values")
    k = T_tool.shape[0]
    group = np.arange(k) if group is None else np.asarray(group)
    if group.shape != (k,) or not np.issubdtype(group.dtype, np.integer) or group.min() != 0 \
            or set(np.unique(group)) != set(range(int(group.max()) + 1)):
        raise ValueError(f"group must be ({k},) integers covering 0 … g − 1, got {group}")
    return T_tool, group


def _checked_boxes(label: str, boxes) -> tuple[np.ndarray, np.ndarray]:
    """``(T_box (m, 4, 4), half (m, 3))`` of ``boxes`` (a pose and positive half sizes each), or
    a ValueError naming ``label``."""
    T_box = np.asarray(boxes[0], dtype=np.float64).reshape(-1, 4, 4)
    half = np.asarray(boxes[1], dtype=np.float64).reshape(-1, 3)
    if T_box.shape[0] != half.shape[0] or np.any(half <= 0):
        raise ValueError(f"{label}: need as many poses as positive half sizes, got {T_box.shape[0]} and {half}")
    return T_box, half


def _checked_world(world: SphereWorld, chain: Chain, n_groups: int, dtype) -> SphereWorld:
    """``world`` in the problem's float dtype (indices and masks stay as they are), or a
    ValueError when its rows are not the ``n_groups`` targets or name bodies beyond the arm."""
    if world.rows.radius.shape[0] != n_groups or int(jnp.max(world.rows.body, initial=0)) > chain.n_joints:
        raise ValueError(f"world has {world.rows.radius.shape[0]} rows for {n_groups} targets, or bodies beyond the "
                         f"arm's {chain.n_joints}")
    return jax.tree_util.tree_map(lambda x: _on_device(x, dtype) if jnp.issubdtype(x.dtype, jnp.floating) else x, world)


# A vehicle frame is level when its z axis is within this of the world's (a rotation's rounding
# error): only then does a fixed base match a docking pose, whose vehicle only yaws.
LEVEL_ATOL = 1e-6


def arm_tool_poses(problem: ArmDockingProblem, pose: Array) -> tuple[Array, Array, Array]:
    """The demanded tool poses seen from the arm at vehicle poses ``(..., 4)`` (traceable).

    Returns:
      ``T_world_vehicle (..., 4, 4)``, ``T_world_base (..., 4, 4)`` and ``T_base_tool (..., k, 4, 4)``.
    """
    T_world_vehicle = base_transform(pose)
    T_world_base = kin.matmul(T_world_vehicle, problem.T_vehicle_base)
    return T_world_vehicle, T_world_base, kin.matmul(kin.pose_inverse(T_world_base)[..., None, :, :], problem.T_world_tool)


def arm_solutions(problem: ArmDockingProblem, pose: Array) -> tuple[Array, Array, Array]:
    """All seeds' IK solutions for vehicle poses ``(..., 4)`` (traceable; jitted as
    :func:`arm_solutions_jit`).

    Returns:
      ``q (..., k, S, n)``, ``valid (..., k, S)`` (reached, within limits, collision-free) and
      ``w (..., k, S)`` manipulability (0 where not valid).
    """
    p = problem
    _, T_world_base, T_base_tool = arm_tool_poses(p, pose)
    q = kin.dls_ik(p.chain, T_base_tool[..., None, :, :], p.seeds, p.iterations, p.damping, limits="wrap")  # (..., k, S, n)
    K = kin.kinematics(p.chain, q)
    reached = kin.reaches(T_base_tool[..., None, :, :], K.T_base_tool)
    within = jnp.all((q >= p.chain.lower) & (q <= p.chain.upper), axis=-1)
    hit = world_collides(p.world, p.group, T_world_base, K.T_base_joint)
    valid = reached & within & ~hit
    w = jnp.where(valid, indices.manipulability_of(p.chain, q), 0.0)
    return q, valid, w


arm_solutions_jit = jax.jit(arm_solutions)


def vehicle_clear(problem: ArmDockingProblem, pose: Array) -> Array:
    """``(...)`` True where no vehicle box overlaps a scene box."""
    T_vb = kin.matmul(base_transform(pose)[..., None, None, :, :], problem.T_vehicle_box[:, None])  # (..., mv, 1, 4, 4)
    hit = boxes_overlap(T_vb, problem.vehicle_half[:, None], problem.T_world_box, problem.scene_half)
    return ~jnp.any(hit, axis=(-1, -2))


def target_w(problem: ArmDockingProblem, w: Array) -> Array:
    """``(..., g)`` best w per target from per-pose, per-seed ``w (..., k, S)``."""
    w_pose = jnp.max(w, axis=-1)  # (..., k)
    w_t = jnp.moveaxis(w_pose, -1, 0)
    best = jax.ops.segment_max(w_t, problem.group, num_segments=problem.n_groups, indices_are_sorted=False)
    return jnp.moveaxis(best, 0, -1)


def arm_terms(problem: ArmDockingProblem, pose: Array, w: Array) -> DockingEval:
    """Objective terms of vehicle poses ``(..., 4)`` from the manipulability ``w (..., k, S)``
    of each demanded tool pose's ``S`` candidate solutions (0 where not valid); ``S = 1`` for
    one value per tool pose (e.g. a learned map's, :mod:`uvms_jax.surrogate`)."""
    p = problem
    M_a = jnp.min(target_w(p, w), axis=-1)  # eq. 1
    p_d = kin.matvec(base_transform(pose)[..., :3, :3], p.p_dock) + pose[..., :3]
    D = jnp.linalg.norm(p_d - p.p_i, axis=-1)  # eq. 3
    inside = jnp.all((pose >= p.pose_low) & (pose <= p.pose_high), axis=-1)
    feasible = inside & vehicle_clear(p, pose)  # eq. 14: Wd
    fitness = p.objective(FitnessInputs(pose, M_a, D), feasible)  # eq. 15
    return DockingEval(fitness=fitness, M_a=M_a, D=D, feasible=feasible)


def evaluate_arm_traced(problem: ArmDockingProblem, pose: Array) -> DockingEval:
    """Objective terms of vehicle poses ``(..., 4)`` (eq. 1, 3, 14, 15), for use inside ``jit``."""
    return arm_terms(problem, pose, arm_solutions(problem, pose)[2])


_evaluate_arm_jit = jax.jit(evaluate_arm_traced)


def _check_poses(problem: ArmDockingProblem, pose) -> Array | np.ndarray:
    """``pose`` in the problem's dtype, checked; a NumPy array stays on the host (no compiled
    conversion or NaN test per shape)."""
    xp = np if isinstance(pose, np.ndarray) else jnp
    pose = xp.asarray(pose, dtype=problem.pose_low.dtype)
    if pose.ndim == 0 or pose.shape[-1] != 4:
        raise ValueError(f"pose must have shape (..., 4) = [x, y, z, psi], got {pose.shape}")
    if bool(xp.isnan(pose).any()):
        raise ValueError("pose contains NaN")
    return pose


def evaluate_arm(problem: ArmDockingProblem, pose) -> DockingEval:
    """Objective terms of vehicle poses ``(..., 4) = [x, y, z, ψ]`` [m, rad] (eager, checked).

    Returns:
      :class:`~uvms_jax.evo.DockingEval` with fields of shape ``(...)``.
    """
    return _evaluate_arm_jit(problem, _check_poses(problem, pose))


def fixed_base_M_a(problem: ArmDockingProblem, T_world_base) -> float | None:
    """M_a (eq. 1) of the docking task with the arm's base fixed at ``T_world_base (4, 4)`` and
    no vehicle hull (a fixed mount, e.g. the thesis's cage top): the problem at the vehicle pose
    that puts the base there, when that pose is level (the docking problem's vehicle only yaws);
    None otherwise."""
    T = np.asarray(T_world_base, dtype=float) @ np.linalg.inv(np.asarray(problem.T_vehicle_base, dtype=float))
    if not np.allclose(T[2, :3], (0, 0, 1), atol=LEVEL_ATOL):
        return None
    pose = np.array([*T[:3, 3], np.arctan2(T[1, 0], T[0, 0])])
    # M_a depends on the hull only through the arm's collisions with it (the world's mask); the
    # hull's own clearance enters the fitness alone. Same shapes as the docking stage's problem:
    # its compiled report serves here.
    no_hull = problem.replace(world=problem.world.without_vehicle())
    return float(arm_report(no_hull, pose[None]).terms.M_a[0])


class ArmReport(NamedTuple):
    """Objective terms and the best IK solution per demanded tool pose of vehicle poses.

    Attributes:
      terms: :class:`~uvms_jax.evo.DockingEval`, fields ``(...)``.
      q: ``(..., k, n)`` best valid solution of each demanded tool pose (NaN where none).
      valid: ``(..., k)`` some seed's solution is valid.
      w: ``(..., k)`` its manipulability (0 where none).
    """

    terms: DockingEval
    q: Array
    valid: Array
    w: Array


@jax.jit
def _report(problem: ArmDockingProblem, pose: Array) -> ArmReport:
    q, valid, w = arm_solutions(problem, pose)
    best = jnp.argmax(w, axis=-1)  # (..., k)
    q_best = jnp.take_along_axis(q, best[..., None, None], axis=-2)[..., 0, :]
    ok = jnp.any(valid, axis=-1)
    return ArmReport(arm_terms(problem, pose, w), jnp.where(ok[..., None], q_best, jnp.nan), ok, jnp.max(w, axis=-1))


# arm_report evaluates its poses in calls of this many (the last call padded with its first
# pose): reports of 1, 4 or 16 poses (a docking run's optima, a map's candidates, a refinement
# step) then share one compiled program, where each batch shape would compile the whole IK and
# collision test anew (seconds on a CPU); a padded pose costs milliseconds.
REPORT_CHUNK = 4


def arm_report(problem: ArmDockingProblem, pose) -> ArmReport:
    """:func:`evaluate_arm` plus the best valid IK solution of every demanded tool pose, for
    vehicle poses ``(..., 4)`` [m, rad], in calls of :data:`REPORT_CHUNK` poses of one compiled
    program (arrays are NumPy)."""
    pose = _check_poses(problem, np.asarray(pose))
    flat = pose.reshape(-1, 4)
    n = flat.shape[0]
    if n == 0:
        raise ValueError(f"arm_report needs at least one pose, got shape {pose.shape}")
    padded = np.concatenate([flat, np.broadcast_to(flat[:1], (-n % REPORT_CHUNK, 4))])
    parts = [_report(problem, padded[i:i + REPORT_CHUNK]) for i in range(0, len(padded), REPORT_CHUNK)]
    return jax.tree_util.tree_map(lambda *a: np.concatenate(a)[:n].reshape(pose.shape[:-1] + a[0].shape[1:]), *parts)
