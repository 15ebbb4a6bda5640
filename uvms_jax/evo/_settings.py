"""Settings of the docking run: plain frozen dataclasses mirroring ``configs/docking.yaml``.

Build them from a plain mapping with :func:`uvms_jax.settings.from_mapping`; the defaults are
the paper's values of the configs (docking paper §III, Table 2; its scene §IV), written here as
literals (tests/papers compares them with the tables of :mod:`uvms_jax.papers`).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from typing import Any

from uvms_jax.evo._fitness import FITNESS_TERMS, PAPER_TERMS
from uvms_jax.settings import check_fields, from_mapping, setting

FIELDS = ("x", "y", "z", "psi")  # the variables of a docking pose, in chromosome order
DTYPES = ("float32", "float64")  # DockingSettings.dtype


@dataclasses.dataclass(frozen=True)
class TermSettings:
    """A fitness term beyond eq. 8's two: a registered name (:func:`~uvms_jax.evo.register_fitness_term`)
    and its weight in the sum."""

    name: str = setting(choices=FITNESS_TERMS)
    weight: float = 1.0

    def __post_init__(self):
        check_fields(self)
        if self.name in PAPER_TERMS:
            raise ValueError(f"fitness term {self.name!r} is weighed by the scene's a or b, not by its terms")


def term_weights(terms: tuple[TermSettings, ...]) -> dict[str, float]:
    """``name → weight`` of a scene's further fitness terms (a ValueError if one is named twice)."""
    names = [t.name for t in terms]
    twice = sorted({n for n in names if names.count(n) > 1})
    if twice:
        raise ValueError(f"fitness terms {twice} are named twice")
    return {t.name: t.weight for t in terms}


@dataclasses.dataclass(frozen=True)
class SceneSettings:
    """The docking scene (``configs/docking/scene/*.yaml``); see :func:`make_docking_problem`.
    ``a``, ``b`` weigh eq. 8's terms; ``terms`` adds registered ones with their weights."""

    block_size: tuple[float, float, float] = (2.0, 2.0, 2.0)
    task_center: tuple[float, float, float] = (0.0, 0.0, 0.0)
    task_size: float = 0.4
    control_points_per_side: int = 2
    p_init: tuple[float, float, float] = (-2.0, -2.0, 2.0)
    psi_init: float = math.pi / 4
    p_bp: tuple[float, float, float] = (-0.3, 0.0, -0.2)
    d: float = 0.3
    a: float = 100.0
    b: float = 0.5
    yaw_mode: str = "heading"
    tool_yaw: float = 0.0
    arm_lengths: tuple[float, float, float] = (0.1, 0.4, 0.4)
    terms: tuple[TermSettings, ...] = ()

    def __post_init__(self):
        term_weights(self.terms)


@dataclasses.dataclass(frozen=True)
class BoxSettings:
    """A box: centre ``pos`` [m], full ``size`` [m], orientation ``rpy`` [rad] (fixed x-y-z axes)."""

    name: str = "box"
    pos: tuple[float, float, float] = (0.0, 0.0, 0.0)
    size: tuple[float, float, float] = (1.0, 1.0, 1.0)
    rpy: tuple[float, float, float] = (0.0, 0.0, 0.0)


@dataclasses.dataclass(frozen=True)
class PanelSettings:
    """Control points on a vertical task panel (:func:`uvms_jax.evo.panel_targets`).

    Attributes:
      center: centre of the task area on the panel face, in W [m].
      approach_yaw: heading of the approach direction (into the panel, horizontal) in W [rad].
      size: width (horizontal) and height of the task area [m].
      points_per_side: 2 = the four corners, n > 2 = an n × n grid.
      standoff: tool frame distance from the face, along the approach [m].
      roll: tool rotation about the approach axis [rad]; 0 = tool x axis up.
    """

    center: tuple[float, float, float] = (0.0, 0.0, 0.0)
    approach_yaw: float = 0.0
    size: tuple[float, float] = (0.3, 0.3)
    points_per_side: int = 3
    standoff: float = 0.1
    roll: float = 0.0


@dataclasses.dataclass(frozen=True)
class ArmSceneSettings:
    """Docking scene of any arm under a vehicle (``configs/docking/scene/bravo7_*.yaml``);
    see :func:`uvms_jax.evo.arm_docking_problem`.

    Attributes:
      arm: a shipped arm (``uvms_jax.robot.shipped_arms()``, e.g. ``bravo7``) or a URDF / MJCF
        file (the format read from its content).
      arm_tip: tool frame in that file (a URDF link, an MJCF body or site); None: the file's
        only leaf.
      mount_xyz, mount_rpy: arm base in the vehicle frame V [m, rad].
      link_radius: link capsule radius [m]; None = the arm's own (its card's, or the robot
        loader's default for a file).
      vehicle_boxes: the vehicle body, boxes in V.
      scene_boxes: obstacles in W (panel, seabed, tables).
      panel: targets on a task panel, or None: the task is then passed to
        :func:`uvms_jax.evo.run_docking` (e.g. a pick-and-place scenario's, from
        :func:`uvms_jax.plan.docking_task`).
      alternatives: at most this many alternative tool poses per target (evenly spaced among
        the symmetric grasps); None keeps all. Fewer make each evaluation cheaper.
      pose_low, pose_high: box of vehicle poses ``[x, y, z, ψ]`` [m, rad] (holds Wd).
      p_dock: docking point in V [m]; p_init: its initial position in W [m] (D of eq. 3).
      a, b: weights of eq. 8; terms: further registered fitness terms and their weights.
      ik_seeds, ik_iterations, ik_damping, ik_seed: numerical IK (seeds fixed for the run):
        seeds ≥ 1, iterations ≥ 1, damping > 0.
    """

    arm: str = "bravo7"
    arm_tip: str | None = None
    mount_xyz: tuple[float, float, float] = (0.35, 0.0, -0.2)
    mount_rpy: tuple[float, float, float] = (math.pi, 0.0, 0.0)
    link_radius: float | None = setting(None, gt=0)
    vehicle_boxes: tuple[BoxSettings, ...] = (BoxSettings("hull", (0.0, 0.0, 0.0), (0.9, 0.7, 0.4)),)
    scene_boxes: tuple[BoxSettings, ...] = ()
    panel: PanelSettings | None = None
    alternatives: int | None = setting(None, ge=1)
    pose_low: tuple[float, float, float, float] = (-1.6, -0.8, -0.4, -math.pi)
    pose_high: tuple[float, float, float, float] = (-0.4, 0.8, 0.8, math.pi)
    p_dock: tuple[float, float, float] = (0.0, 0.0, 0.0)
    p_init: tuple[float, float, float] = (-2.5, -1.5, 1.0)
    a: float = 300.0
    b: float = 0.5
    terms: tuple[TermSettings, ...] = ()
    ik_seeds: int = setting(32, ge=1)
    ik_iterations: int = setting(40, ge=1)
    ik_damping: float = setting(0.5, gt=0)
    ik_seed: int = 0

    def __post_init__(self):
        check_fields(self)
        term_weights(self.terms)


@dataclasses.dataclass(frozen=True)
class FieldBits:
    """Bits per chromosome field (resolution over the box of Wd), each ≥ 1."""

    x: int = setting(11, ge=1)
    y: int = setting(11, ge=1)
    z: int = setting(8, ge=1)
    psi: int = setting(6, ge=1)


@dataclasses.dataclass(frozen=True)
class GASettings:
    """Binary GA (``configs/ga/*.yaml``): sizes of :class:`BinaryGA`, codec and :class:`GAParams`.

    Attributes:
      population_size: individuals per run, ≥ 1; max_generations: ≥ 1.
      n_elites: best individuals copied unchanged, ≥ 0; tournament_size: ≥ 1.
      bits: bits per chromosome field; gray: reflected Gray code per field.
      crossover_rate: probability per pair in [0, 1], scaled by the parents' fitness rank;
        crossover_bias: β in [0, 1] of that scaling.
      mutation_rate: probability per bit in [0, 1].
      rate_decay, improvement_decay: factors in [0, 1] of both rates every generation and
        on improvement; crossover_rate_min, mutation_rate_min: floors in [0, 1].
      stall_generations: stop after this many generations (≥ 1) without improvement;
        improvement_tol: smaller relative improvements (≥ 0) don't count.
      eval_chunk: chromosomes per evaluation call, ≥ 1 (None: all in one call).
      host_loop: generations driven from Python, the fitness compiled once for the GA and the
        grid search of ``chunk_size = eval_chunk`` (:class:`BinaryGA`); needs ``eval_chunk``.
    """

    population_size: int = setting(60, ge=1)
    max_generations: int = setting(500, ge=1)
    n_elites: int = setting(1, ge=0)
    tournament_size: int = setting(2, ge=1)
    bits: FieldBits = FieldBits()
    gray: bool = True
    crossover_rate: float = setting(0.20, ge=0, le=1)
    crossover_bias: float = setting(1.0, ge=0, le=1)
    mutation_rate: float = setting(0.08, ge=0, le=1)
    rate_decay: float = setting(0.99, ge=0, le=1)
    improvement_decay: float = setting(0.95, ge=0, le=1)
    crossover_rate_min: float = setting(0.05, ge=0, le=1)
    mutation_rate_min: float = setting(0.005, ge=0, le=1)
    stall_generations: int = setting(50, ge=1)
    improvement_tol: float = setting(1.0e-3, ge=0)
    eval_chunk: int | None = setting(40, ge=1)
    host_loop: bool = False


@dataclasses.dataclass(frozen=True)
class GridSettings:
    """Dense grid reference and its zoom stages.

    Attributes:
      counts: grid points along x, y, z, ψ, each ≥ 1.
      chunk_size: candidates per jitted evaluation (bounds memory), ≥ 1.
      refine_stages: zoom grids around the best point, ≥ 0; refine_counts: their points per
        axis, each ≥ 1; refine_shrink: each zoom box as a fraction of the previous, in (0, 1].
      refine_starts: 1 polishes the grid's best point, its first zoom box half the search box
        (the reference); K > 1 polishes the K best distinct points of the grid and the GA runs
        at once (:func:`~uvms_jax.evo.distinct_best`, one grid cell apart), each zoom box
        starting one cell wide: a multistart search that keeps every basin the coarse grid
        found.
      shift: sample the grid on a lattice moved by a random fraction of a cell (from the
        run's seed, :func:`~uvms_jax.evo.grid_search`'s ``shift``), so that each seed
        looks at the box afresh; False: the lattice through the box's corners.
    """

    counts: tuple[int, ...] = setting((81, 81, 16, 12), ge=1)
    chunk_size: int = setting(16384, ge=1)
    refine_stages: int = setting(12, ge=0)
    refine_counts: tuple[int, ...] = setting((11, 11, 11, 11), ge=1)
    refine_shrink: float = setting(0.5, gt=0, le=1)
    refine_starts: int = setting(1, ge=1)
    shift: bool = False


@dataclasses.dataclass(frozen=True)
class CMAESSettings:
    """CMA-ES baseline (evosax): runs, population and generations each ≥ 1 (population ≥ 2);
    ``std_init`` > 0 in units of the search box."""

    enabled: bool = True
    n_runs: int = setting(7, ge=1)
    population_size: int = setting(16, ge=2)
    generations: int = setting(300, ge=1)
    std_init: float = setting(0.3, gt=0)


@dataclasses.dataclass(frozen=True)
class WmaxSettings:
    """Resolution of the eq. 16 maps over the task area: points per side, ≥ 2."""

    n_per_side: int = setting(41, ge=2)


@dataclasses.dataclass(frozen=True)
class DockingSettings:
    """A whole docking run (``configs/docking.yaml`` after composition).

    Attributes:
      seed: PRNG seed; GA run r uses ``split(key(seed), n_runs)[r]``, CMA-ES ``key(seed + 1)``.
      n_runs: independent GA runs, ≥ 1.
      dtype: ``"float32"`` or ``"float64"`` (:data:`DTYPES`; the latter needs ``jax_enable_x64``).
      time_single_runs: also time each GA run alone (else each run gets the batch time).
      accept_ratio: a GA best ≥ ``accept_ratio`` × grid optimum counts as found; in (0, 1].
      scene: the paper's scene (:class:`SceneSettings`) or an arm under a vehicle
        (:class:`ArmSceneSettings`).
    """

    seed: int = 0
    n_runs: int = setting(7, ge=1)
    dtype: str = setting("float32", choices=DTYPES)
    time_single_runs: bool = True
    accept_ratio: float = setting(0.99, gt=0, le=1)
    # SceneSettings | ArmSceneSettings; a mapping is converted in __post_init__, by its keys.
    scene: Any = SceneSettings()
    ga: GASettings = GASettings()
    grid: GridSettings = GridSettings()
    cmaes: CMAESSettings = CMAESSettings()
    wmax: WmaxSettings = WmaxSettings()

    def __post_init__(self):
        # A mapping with an ``arm`` key is an arm scene; converting here (not by trying both
        # types) lets a wrong key be reported against the scene type it belongs to.
        if isinstance(self.scene, Mapping):
            kind = ArmSceneSettings if "arm" in self.scene else SceneSettings
            object.__setattr__(self, "scene", from_mapping(kind, self.scene, "scene"))
        if not isinstance(self.scene, (SceneSettings, ArmSceneSettings)):
            raise ValueError(f"scene must be SceneSettings or ArmSceneSettings, got {type(self.scene).__name__}")
