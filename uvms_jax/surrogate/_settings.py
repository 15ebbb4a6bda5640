"""Settings of the surrogate design run: plain frozen dataclasses mirroring ``configs/surrogate.yaml``.

Build them from a plain mapping with ``uvms_jax.settings.from_mapping(SurrogateSettings, d)``;
the defaults are the paper-sized run (dexterity paper Table 3). Angles of the sampling are in
degrees here, as in the config, and in radians in :class:`Sampling` (:meth:`SamplingSettings.to_sampling`).
"""

from __future__ import annotations

import dataclasses
import math

from uvms_jax.surrogate._dataset import INDEX_NAMES, Sampling
from uvms_jax.surrogate._design import TRAINERS
from uvms_jax.settings import check_fields, setting
from uvms_jax.surrogate._form import IndexForm

NETWORK_KINDS = ("ffbn", "rbfn")
# Every network a run can design: "<kind>_<index>".
NETWORK_NAMES = tuple(f"{kind}_{index}" for kind in NETWORK_KINDS for index in INDEX_NAMES)
TRAIN_DTYPES = ("float32", "float64")


def split_network_name(name: str) -> tuple[str, str]:
    """``"ffbn_w"`` → ``("ffbn", "w")``; raises ValueError for a name not in ``NETWORK_NAMES``."""
    if name not in NETWORK_NAMES:
        raise ValueError(f"unknown network {name!r}; expected one of {NETWORK_NAMES}")
    kind, index = name.split("_")
    return kind, index


class _PerIndex:
    """One value per index (w, KCI), read as ``values["w"]``; each field's :func:`setting` says
    which values are valid, checked on construction too."""

    def __post_init__(self):
        problems = [m for f in dataclasses.fields(self) for m in f.metadata["check"].problems(getattr(self, f.name), f.name)]
        if problems:
            raise ValueError("; ".join(problems))

    def __getitem__(self, index: str):
        if index not in INDEX_NAMES:
            raise KeyError(f"unknown index {index!r}; expected one of {INDEX_NAMES}")
        return getattr(self, index)


@dataclasses.dataclass(frozen=True)
class IndexInts(_PerIndex):
    """One positive integer per index (w, KCI), e.g. training-set sizes or unit limits."""

    w: int = setting(ge=1)
    kci: int = setting(ge=1)


@dataclasses.dataclass(frozen=True)
class IndexFloats(_PerIndex):
    """One positive finite number per index (w, KCI), e.g. target mse [index units²]."""

    w: float = setting(gt=0.0, lt=math.inf)
    kci: float = setting(gt=0.0, lt=math.inf)


@dataclasses.dataclass(frozen=True)
class SamplingSettings:
    """The paper's sampling (Fig. 7) with angles in degrees; see :class:`Sampling` for the meaning.

    Attributes:
      mode: "paper" (annulus + joint grid) or "full" (every revolute joint within its limits).
      task_point: TP [m]; r_min, r_max: annulus radii [m] (Table 2).
      phi_deg: sampling angle φ [deg]; heading_deg: sector centre line TP → MB [deg].
      nominal_arm_deg: ``(6,)`` nominal arm joints [deg]; half_range_deg, step_deg: joint grid [deg].
      continuous: uniform in ``nominal ± half_range`` instead of on the grid.
    """

    mode: str = "paper"
    task_point: tuple[float, float, float] = (0.0, 0.0, 0.0)
    r_min: float = 0.2
    r_max: float = 1.0
    phi_deg: float = 30.0
    heading_deg: float = -90.0
    nominal_arm_deg: tuple[float, ...] = (0.0, 30.0, 60.0, 0.0, 30.0, 0.0)
    half_range_deg: float = 15.0
    step_deg: float = 5.0
    continuous: bool = False

    def __post_init__(self):
        self.to_sampling()  # Sampling checks every value and names the bad one

    def to_sampling(self) -> Sampling:
        """The same scheme with angles in radians, as the sampler takes it."""
        rad = math.radians
        return Sampling(
            mode=self.mode, task_point=self.task_point, r_min=self.r_min, r_max=self.r_max, phi=rad(self.phi_deg),
            heading=rad(self.heading_deg), nominal_arm=tuple(rad(v) for v in self.nominal_arm_deg),
            half_range=rad(self.half_range_deg), step=rad(self.step_deg), continuous=self.continuous,
        )


@dataclasses.dataclass(frozen=True)
class DataSettings:
    """Dataset sizes: training samples per index and test samples (Table 3: T = 1000), each ≥ 1."""

    n_train: IndexInts = IndexInts(w=3000, kci=6000)
    n_test: int = setting(1000, ge=1)

    def __post_init__(self):
        if self.n_test < 1:
            raise ValueError(f"data.n_test must be positive, got {self.n_test}")


@dataclasses.dataclass(frozen=True)
class AdamSettings:
    """Full-batch Adam, the first-order alternative to Levenberg–Marquardt: steps ≥ 1, learning
    rate > 0."""

    steps: int = setting(3000, ge=1)
    learning_rate: float = setting(0.01, gt=0)


@dataclasses.dataclass(frozen=True)
class FFBNSettings:
    """FFBN design loop (paper Fig. 6a, Table 3).

    Attributes:
      trainer: "lm" (Levenberg–Marquardt, the paper's) or "adam".
      error_goal: E > 0, goal of the max relative test error (eq. 21).
      max_hidden: L_iter per index; hidden_step: neurons added per step, ≥ 1.
      target_mse: E_mse per index [index units²]; max_epochs: L_epochs, ≥ 1.
      adam: Adam settings (trainer "adam").
      together: sizes of one padded width trained side by side in one vmapped call, ≥ 1
        (:func:`~uvms_jax.surrogate.design_ffbn`; the same loop, a few wide calls on a GPU
        instead of many small ones).
    """

    trainer: str = setting("lm", choices=TRAINERS)
    error_goal: float = setting(0.02, gt=0)
    max_hidden: IndexInts = IndexInts(w=100, kci=100)
    hidden_step: int = setting(1, ge=1)
    target_mse: IndexFloats = IndexFloats(w=1.0e-3, kci=5.0e-6)
    max_epochs: int = setting(100, ge=1)
    adam: AdamSettings = AdamSettings()
    together: int = setting(32, ge=1)

    def __post_init__(self):
        if self.trainer not in TRAINERS:
            raise ValueError(f"ffbn.trainer: unknown trainer {self.trainer!r}; expected one of {TRAINERS}")


@dataclasses.dataclass(frozen=True)
class RBFNSettings:
    """RBFN spread search (paper Fig. 6b).

    Attributes:
      error_goal: E > 0; spread_start, spread_step, spread_max: spreads tried (normalised input
        units), each > 0.
      target_mse: E_th per index [index units²]; the paper's 1e-2 (w) and 1e-4 (KCI) are for its
        own index scales, these give a comparable relative fit for w ≈ 9.4 and KCI ≈ 0.42.
      max_centres: unit limit per index.
    """

    error_goal: float = setting(0.02, gt=0)
    spread_start: float = setting(1.0, gt=0)
    spread_step: float = setting(1.0, gt=0)
    spread_max: float = setting(10.0, gt=0)
    target_mse: IndexFloats = IndexFloats(w=1.0e-4, kci=1.0e-6)
    max_centres: IndexInts = IndexInts(w=300, kci=300)


@dataclasses.dataclass(frozen=True)
class TimingSettings:
    """Network vs analytic index timing: batch sizes, repeats (median) and chunk size.

    Batches above ``chunk`` are evaluated in chunks (bounds the memory of the analytic index).
    """

    batches: tuple[int, ...] = setting((1000, 100000, 1000000), ge=1)
    repeats: int = setting(5, ge=1)
    chunk: int = setting(100000, ge=1)

    def __post_init__(self):
        if not self.batches or min(self.batches) < 1:
            raise ValueError(f"timing.batches must be positive batch sizes, got {self.batches}")
        if self.repeats < 1 or self.chunk < 1:
            raise ValueError(f"timing.repeats and timing.chunk must be positive, got {self.repeats}, {self.chunk}")


@dataclasses.dataclass(frozen=True)
class AcceptanceSettings:
    """Thresholds of the acceptance figures in the report (units, speed-ups, seconds)."""

    ffbn_w_max_hidden: int = 25
    ffbn_kci_max_hidden: int = 100
    speedup_w_at_1e5: float = 2.0  # against the fused analytic kernel, the fastest analytic path
    speedup_kci_at_1e5: float = 20.0
    ffbn_w_design_seconds: float = 300.0


@dataclasses.dataclass(frozen=True)
class SurrogateSettings:
    """Everything a surrogate run needs; fields mirror ``configs/surrogate.yaml``.

    Attributes:
      seed: recorded with the datasets (the caller derives the PRNG key from it).
      train_dtype: "float64" or "float32" (``TRAIN_DTYPES``) for datasets and training; float64 needs
        ``jax_enable_x64``, which the caller sets at start. Timing is always float32.
      networks: names of the networks to design, each of ``NETWORK_NAMES``.
      index_form: Jacobian form and eq. 7 normalisation the indices are computed from
        (default: the paper's spatial form, unnormalised, since this run reproduces the paper;
        ``IndexForm("geometric")`` gives the project's own form).
    """

    seed: int = 0
    train_dtype: str = setting("float64", choices=TRAIN_DTYPES)
    networks: tuple[str, ...] = NETWORK_NAMES
    index_form: IndexForm = IndexForm("spatial")
    sampling: SamplingSettings = SamplingSettings()
    data: DataSettings = DataSettings()
    ffbn: FFBNSettings = FFBNSettings()
    rbfn: RBFNSettings = RBFNSettings()
    timing: TimingSettings = TimingSettings()
    acceptance: AcceptanceSettings = AcceptanceSettings()

    def __post_init__(self):
        check_fields(self)
        if not self.networks:
            raise ValueError("networks must name at least one network")
        for name in self.networks:
            split_network_name(name)
        if len(set(self.networks)) != len(self.networks):
            raise ValueError(f"networks are listed twice: {self.networks}")

    @property
    def indices(self) -> tuple[str, ...]:
        """The indices the chosen networks need, in the order w, KCI."""
        wanted = {split_network_name(n)[1] for n in self.networks}
        return tuple(i for i in INDEX_NAMES if i in wanted)

    def to_dict(self) -> dict:
        """Plain nested dict with the config's keys (tuples stay tuples; JSON writes them as lists)."""
        return dataclasses.asdict(self)
