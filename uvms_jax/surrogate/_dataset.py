"""Training and test datasets for the index surrogates (dexterity paper §3.1, §4.2, Fig. 7).

Two datasets on the 12-DOF UVMS (``kin.uvms12``), labelled by the index of a Jacobian
:class:`IndexForm`: by default the geometric Jacobian (rows: tool-point linear velocity,
angular velocity; base frame), optionally the paper's spatial-twist form (eq. 6) with the
normalisation of eq. 7:

- D1 (eq. 11): inputs θ1…θ11 (joint indices 0…10) → ``KCI = σ_min / σ_max``.
- D2 (eq. 12): inputs θ5…θ11 (joint indices 4…10) → ``w = sqrt(det(J Jᵀ))``.

θ12 never enters J (paper §2.2) and is not an input. A network's ``index_fn(q)`` takes the
full configuration ``q: (..., 12)`` and reads only its input joints. The other joints do not
change the index: with the geometric Jacobian the singular values of J, hence w and KCI, are
invariant to θ12 and to the vehicle translation θ1…θ3 and roll θ4 (base invariance; checked
numerically to 1e-15). With the spatial form w is the same, but KCI depends on θ1…θ4 (it
falls as the vehicle moves away from the base origin), which is why D1 has them as inputs.
Wherever a configuration is built from the inputs alone, the joints not in the input are held
at 0.

Sampling (paper Fig. 7, "paper" mode): a task point TP; the manipulator base MB (the point
where the first two arm axes meet) lies in the annulus ``r_min ≤ |MB − TP|_xy ≤ r_max`` at the
height of TP, within the sampling angle φ centred on ``heading`` (direction TP → MB in the
x–y plane). The vehicle rotations θx, θy, θz and the six arm joints are drawn from the grid
``nominal + {−15°, −10°, …, +15°}`` (a ``half_range`` and ``step`` of 15° and 5°); the CoG
position θ1…θ3 then follows from MB and the vehicle rotation. The nominal vehicle attitude
is level with yaw ``heading + π/2`` (the arm, which points along +y of the vehicle, faces TP).
The nominal arm pose ``(0°, 30°, 60°, 0°, 30°, 0°)`` bends the elbow and the wrist away from
the arm's singularities (stretched elbow at θm3 = 0, aligned wrist axes at θm5 = ±90°); the
paper does not give its nominal pose. With it, w stays within ≈ 8.3…10.3 and KCI within
≈ 0.39…0.46, far from 0, so the relative error ``|(T − S)/T|`` (eq. 21) is well posed.

"full" mode draws every revolute joint uniformly within the chain's limits (MB still in the
annulus). There θy can reach ±90° (gimbal lock of the vehicle's XYZ Euler angles), where w and
KCI go to 0 and a relative error is not meaningful.
"""

from __future__ import annotations

import dataclasses
import json
import math
from functools import partial
from pathlib import Path
from typing import Callable

import jax
import jax.numpy as jnp
import numpy as np
from flax import struct
from jax import Array

from uvms_jax import kin
from uvms_jax.files import atomic_path, write_json
from uvms_jax.surrogate._form import IndexForm, index_fn, index_of

INDEX_NAMES = ("w", "kci")
# Joint indices (0-based) of the network inputs, paper eqs. (11)–(12).
INDEX_INPUTS = {"kci": tuple(range(0, 11)), "w": tuple(range(4, 11))}
SAMPLING_MODES = ("paper", "full")
DEG = math.pi / 180.0


def index_inputs(index: str) -> tuple[int, ...]:
    """Joint indices that feed the surrogate of ``index`` ("w" → θ5…θ11, "kci" → θ1…θ11)."""
    if index not in INDEX_INPUTS:
        raise ValueError(f"unknown index {index!r}; expected one of {INDEX_NAMES}")
    return INDEX_INPUTS[index]


def analytic_index(chain: kin.Chain, q, index: str, form: IndexForm = IndexForm()) -> Array:
    """Analytic index of ``q: (..., n_joints)`` [m, rad]: w or KCI of the Jacobian ``form``, ``(...)``.

    Default form: ``indices.manipulability_of`` / ``indices.kci_of`` (geometric Jacobian, fused).
    """
    if index not in INDEX_INPUTS:
        raise ValueError(f"unknown index {index!r}; expected one of {INDEX_NAMES}")
    return index_of(chain, q, index, form)


def analytic_index_fn(chain: kin.Chain, index: str, form: IndexForm = IndexForm()) -> Callable[[Array], Array]:
    """``q: (..., n_joints) → (...)`` analytic index, jitted: the reference a surrogate replaces,
    and the project's fastest analytic path (one fused kernel that never stores J)."""
    if index not in INDEX_INPUTS:
        raise ValueError(f"unknown index {index!r}; expected one of {INDEX_NAMES}")
    return index_fn(chain, index, form)


@dataclasses.dataclass(frozen=True)
class Sampling:
    """How configurations are drawn (hashable: it is a static argument of the jitted sampler).

    Attributes:
      mode: "paper" (Fig. 7 annulus + ±half_range joint grid) or "full" (joint limits).
      task_point: ``(3,)`` TP in the base (world) frame [m].
      r_min, r_max: annulus radii of MB around TP in the x–y plane [m] (Table 2: 0.2, 1.0).
      phi: sampling angle of the annulus sector [rad] (paper: 30°).
      heading: direction of the sector's centre line, TP → MB, from +x [rad].
      nominal_arm: ``(6,)`` nominal arm joints θm1…θm6 [rad].
      half_range: half width of each grid joint's range [rad] (paper: 15°).
      step: grid step [rad] (paper: 5°).
      continuous: draw the grid joints uniformly in ``nominal ± half_range`` instead of on
        the grid (for off-grid test sets).
    """

    mode: str = "paper"
    task_point: tuple[float, float, float] = (0.0, 0.0, 0.0)
    r_min: float = 0.2
    r_max: float = 1.0
    phi: float = 30.0 * DEG
    heading: float = -90.0 * DEG
    nominal_arm: tuple[float, ...] = (0.0, 30.0 * DEG, 60.0 * DEG, 0.0, 30.0 * DEG, 0.0)
    half_range: float = 15.0 * DEG
    step: float = 5.0 * DEG
    continuous: bool = False

    def __post_init__(self):
        object.__setattr__(self, "task_point", tuple(float(v) for v in self.task_point))
        object.__setattr__(self, "nominal_arm", tuple(float(v) for v in self.nominal_arm))
        if self.mode not in SAMPLING_MODES:
            raise ValueError(f"unknown sampling mode {self.mode!r}; expected one of {SAMPLING_MODES}")
        if len(self.task_point) != 3:
            raise ValueError(f"task_point must have 3 coordinates, got {self.task_point}")
        if len(self.nominal_arm) != 6:
            raise ValueError(f"nominal_arm must have 6 joint values, got {self.nominal_arm}")
        if not 0.0 <= self.r_min < self.r_max:
            raise ValueError(f"need 0 <= r_min < r_max, got r_min={self.r_min}, r_max={self.r_max}")
        if not 0.0 < self.phi <= 2.0 * math.pi:
            raise ValueError(f"phi must be in (0, 2π] rad, got {self.phi}")
        if self.half_range < 0.0 or self.step <= 0.0:
            raise ValueError(f"need half_range >= 0 and step > 0, got {self.half_range}, {self.step}")
        values = (*self.task_point, *self.nominal_arm, self.r_min, self.r_max, self.phi, self.heading)
        if not all(math.isfinite(v) for v in values):
            raise ValueError("sampling parameters must be finite")

    def grid(self) -> np.ndarray:
        """Grid offsets ``(k,)`` [rad]: −half_range … +half_range in ``step`` increments."""
        n = int(math.floor(self.half_range / self.step + 1e-9))
        return np.arange(-n, n + 1) * self.step

    def to_dict(self) -> dict:
        return dataclasses.asdict(self)


def mb_offset(chain: kin.Chain) -> np.ndarray:
    """Manipulator base MB in the vehicle frame at q = 0 [m]: the point nearest both of the
    first two arm axes (joints 7 and 8 of the UVMS; they intersect at ``(0, y_MB, l1)``)."""
    twists = np.asarray(chain.twists, dtype=np.float64)
    rows, rhs = [], []
    for i in (6, 7):
        v, w = twists[i, :3], twists[i, 3:]
        point = np.cross(w, v)  # axis point nearest the origin, for ξ = [−ω × q, ω]
        P = np.eye(3) - np.outer(w, w)  # distance to the line: |P (x − point)|
        rows.append(P)
        rhs.append(P @ point)
    return np.linalg.lstsq(np.concatenate(rows), np.concatenate(rhs), rcond=None)[0]


def _rotation_xyz(angles: Array) -> Array:
    """``Rx(a0) Ry(a1) Rz(a2)`` for ``angles: (..., 3)`` [rad] → ``(..., 3, 3)`` (joints 4–6)."""
    Rx, Ry, Rz = (kin.axis_rotation(k, angles[..., k]) for k in range(3))
    return kin.matmul(kin.matmul(Rx, Ry), Rz)


def _check_uvms(chain: kin.Chain) -> None:
    if chain.n_joints != 12 or chain.kinds[:3] != ("prismatic",) * 3:
        raise ValueError(
            f"surrogate datasets need the 12-DOF UVMS (3 prismatic + 9 revolute joints), got chain "
            f"{chain.name!r} with {chain.n_joints} joints"
        )


@partial(jax.jit, static_argnames=("sampling", "n", "dtype"))
def _sample(key: Array, chain: kin.Chain, mb0: Array, sampling: Sampling, n: int, dtype) -> Array:
    k_r, k_a, k_rot, k_arm = jax.random.split(key, 4)
    lower, upper = chain.lower.astype(dtype), chain.upper.astype(dtype)
    nominal = jnp.concatenate(
        [jnp.array([0.0, 0.0, sampling.heading + math.pi / 2], dtype), jnp.asarray(sampling.nominal_arm, dtype)]
    )
    if sampling.mode == "full":
        angles = jax.random.uniform(k_arm, (n, 9), dtype, lower[3:], upper[3:])
    elif sampling.continuous:
        angles = nominal + jax.random.uniform(k_arm, (n, 9), dtype, -sampling.half_range, sampling.half_range)
    else:
        grid = jnp.asarray(sampling.grid(), dtype)
        angles = nominal + grid[jax.random.randint(k_arm, (n, 9), 0, grid.shape[0])]
    # MB uniform by area in the annulus sector around TP (Fig. 7).
    r = jnp.sqrt(jax.random.uniform(k_r, (n,), dtype, sampling.r_min**2, sampling.r_max**2))
    alpha = sampling.heading + jax.random.uniform(k_a, (n,), dtype, -sampling.phi / 2, sampling.phi / 2)
    p_mb = jnp.asarray(sampling.task_point, dtype) + jnp.stack([r * jnp.cos(alpha), r * jnp.sin(alpha), jnp.zeros_like(r)], -1)
    # Joints 1–6 map a vehicle-frame point p to (x, y, z) + Rx Ry Rz p, so the CoG is:
    p_cog = p_mb - jnp.einsum("nij,j->ni", _rotation_xyz(angles[:, :3]), mb0.astype(dtype), precision=jax.lax.Precision.HIGHEST)
    return jnp.concatenate([p_cog, angles], axis=-1)


def sample_configurations(key: Array, chain: kin.Chain, sampling: Sampling, n: int, dtype=jnp.float32) -> Array:
    """Draw ``n`` UVMS configurations ``q: (n, 12)`` [m, rad] as described in the module doc.

    One jitted call; ``sampling`` and ``n`` are static (a new value compiles once).
    """
    _check_uvms(chain)
    if n <= 0:
        raise ValueError(f"n must be positive, got {n}")
    return _sample(key, chain, jnp.asarray(mb_offset(chain)), sampling, int(n), jnp.dtype(dtype))


@struct.dataclass
class Dataset:
    """Input/target pairs of one index.

    Attributes:
      q: ``(n, 12)`` full configurations [m, rad].
      x: ``(n, d)`` network inputs ``q[:, inputs]``.
      y: ``(n,)`` analytic index values (w [units of det(JJᵀ)^½] or KCI [−]).
      index: "w" or "kci" (static).
      inputs: joint indices of ``x`` (static).
      sampling: how ``q`` was drawn (static).
      form: Jacobian form and normalisation of the index ``y`` (static).
    """

    q: Array
    x: Array
    y: Array
    index: str = struct.field(pytree_node=False)
    inputs: tuple[int, ...] = struct.field(pytree_node=False)
    sampling: Sampling = struct.field(pytree_node=False)
    form: IndexForm = struct.field(pytree_node=False, default=IndexForm())

    def __len__(self) -> int:
        return int(self.y.shape[0])

    def split(self, n_first: int) -> tuple["Dataset", "Dataset"]:
        """The first ``n_first`` samples and the rest (e.g. train and test sets of one draw)."""
        if not 0 < n_first < len(self):
            raise ValueError(f"n_first must be in (0, {len(self)}), got {n_first}")
        head = self.replace(q=self.q[:n_first], x=self.x[:n_first], y=self.y[:n_first])
        tail = self.replace(q=self.q[n_first:], x=self.x[n_first:], y=self.y[n_first:])
        return head, tail


@partial(jax.jit, static_argnames=("sampling", "n", "index", "dtype", "form"))
def _make(key, chain, mb0, sampling, n, index, dtype, form):
    q = _sample(key, chain, mb0, sampling, n, dtype)
    # Without the barrier XLA fuses the sampler (RNG, sin/cos) into every consumer of q in the
    # unrolled kinematics; compilation then takes minutes instead of seconds.
    q = jax.lax.optimization_barrier(q)
    return q, analytic_index(chain, q, index, form)


def make_dataset(key: Array, chain: kin.Chain, sampling: Sampling, n: int, index: str, dtype=jnp.float32,
                 form: IndexForm = IndexForm()) -> Dataset:
    """Sample ``n`` configurations and label them with the analytic ``index`` — one jitted call.

    Args:
      key: PRNG key.
      chain: the 12-DOF UVMS (``kin.uvms12()``).
      sampling: sampling scheme (paper Fig. 7 or full joint range).
      n: number of samples (1000 for the paper's test sets).
      index: "w" (dataset D2) or "kci" (dataset D1).
      dtype: float32 or float64 (float64 needs ``jax_enable_x64``).
      form: Jacobian form and normalisation of the index (default: geometric, unnormalised;
        the paper's is ``IndexForm("spatial")`` with its eq. 7 limits, if known).
    """
    inputs = index_inputs(index)
    _check_uvms(chain)
    form.check_chain(chain)
    if n <= 0:
        raise ValueError(f"n must be positive, got {n}")
    q, y = _make(key, chain, jnp.asarray(mb_offset(chain)), sampling, int(n), index, jnp.dtype(dtype), form)
    return Dataset(q=q, x=q[:, list(inputs)], y=y, index=index, inputs=inputs, sampling=sampling, form=form)


def save_dataset(path, ds: Dataset, **meta) -> tuple[Path, Path]:
    """Write ``<path>.npz`` (q, x, y) and ``<path>.json`` (index, inputs, sampling, ``meta``)."""
    path = Path(path).with_suffix("")
    path.parent.mkdir(parents=True, exist_ok=True)
    npz, js = path.with_suffix(".npz"), path.with_suffix(".json")
    with atomic_path(npz) as tmp, tmp.open("wb") as f:
        np.savez(f, q=np.asarray(ds.q), x=np.asarray(ds.x), y=np.asarray(ds.y))
    config = {"index": ds.index, "inputs": list(ds.inputs), "n": len(ds), "dtype": str(ds.y.dtype),
              "sampling": ds.sampling.to_dict(), "form": ds.form.to_dict(), **meta}
    write_json(js, config)
    return npz, js


def load_dataset(path) -> Dataset:
    """Read a dataset written by :func:`save_dataset` (arrays keep their saved dtype)."""
    path = Path(path).with_suffix("")
    config = json.loads(path.with_suffix(".json").read_text())
    with np.load(path.with_suffix(".npz")) as data:
        q, x, y = (jnp.asarray(data[k]) for k in ("q", "x", "y"))
    sampling = Sampling(**config["sampling"])
    form = IndexForm(**config.get("form", {}))  # files written before forms existed: geometric
    return Dataset(q=q, x=x, y=y, index=config["index"], inputs=tuple(config["inputs"]), sampling=sampling,
                   form=form)
