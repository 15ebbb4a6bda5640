"""Settings of the docking run: plain frozen dataclasses mirroring ``configs/docking.yaml``.

Build them from a plain mapping with :func:`uvms_jax.settings.from_mapping`; the defaults are
the paper's values of the configs (docking paper §III, Table 2).
"""

from __future__ import annotations

import dataclasses
import math

FIELDS = ("x", "y", "z", "psi")  # the variables of a docking pose, in chromosome order


@dataclasses.dataclass(frozen=True)
class SceneSettings:
    """The docking scene (``configs/docking/scene/*.yaml``); see :func:`make_docking_problem`."""

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


@dataclasses.dataclass(frozen=True)
class FieldBits:
    """Bits per chromosome field (resolution over the box of Wd)."""

    x: int = 11
    y: int = 11
    z: int = 8
    psi: int = 6


@dataclasses.dataclass(frozen=True)
class GASettings:
    """Binary GA (``configs/ga/*.yaml``): sizes of :class:`BinaryGA`, codec and :class:`GAParams`."""

    population_size: int = 60
    max_generations: int = 500
    n_elites: int = 1
    tournament_size: int = 2
    bits: FieldBits = FieldBits()
    gray: bool = True
    crossover_rate: float = 0.20
    crossover_bias: float = 1.0
    mutation_rate: float = 0.08
    rate_decay: float = 0.99
    improvement_decay: float = 0.95
    crossover_rate_min: float = 0.05
    mutation_rate_min: float = 0.005
    stall_generations: int = 50
    improvement_tol: float = 1.0e-3
    eval_chunk: int | None = 40


@dataclasses.dataclass(frozen=True)
class GridSettings:
    """Dense grid reference and its zoom stages (x, y, z, ψ counts)."""

    counts: tuple[int, ...] = (81, 81, 16, 12)
    chunk_size: int = 16384
    refine_stages: int = 12
    refine_counts: tuple[int, ...] = (11, 11, 11, 11)
    refine_shrink: float = 0.5


@dataclasses.dataclass(frozen=True)
class CMAESSettings:
    """CMA-ES baseline (evosax); ``std_init`` in units of the search box."""

    enabled: bool = True
    n_runs: int = 7
    population_size: int = 16
    generations: int = 300
    std_init: float = 0.3


@dataclasses.dataclass(frozen=True)
class WmaxSettings:
    """Resolution of the eq. 16 maps over the task area."""

    n_per_side: int = 41


@dataclasses.dataclass(frozen=True)
class DockingSettings:
    """A whole docking run (``configs/docking.yaml`` after composition).

    Attributes:
      seed: PRNG seed; GA run r uses ``split(key(seed), n_runs)[r]``, CMA-ES ``key(seed + 1)``.
      n_runs: independent GA runs.
      dtype: ``"float32"`` or ``"float64"`` (the latter needs ``jax_enable_x64``).
      time_single_runs: also time each GA run alone (else each run gets the batch time).
      ill_placed_pose: ``[x, y, z, ψ]`` [m, rad] of the paper's ill-placed pose (Fig. 10).
      accept_ratio: a GA best ≥ ``accept_ratio`` × grid optimum counts as found.
    """

    seed: int = 0
    n_runs: int = 7
    dtype: str = "float32"
    time_single_runs: bool = True
    ill_placed_pose: tuple[float, float, float, float] = (-0.491, -0.464, 0.213, 0.83)
    accept_ratio: float = 0.99
    scene: SceneSettings = SceneSettings()
    ga: GASettings = GASettings()
    grid: GridSettings = GridSettings()
    cmaes: CMAESSettings = CMAESSettings()
    wmax: WmaxSettings = WmaxSettings()
