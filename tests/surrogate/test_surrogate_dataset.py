"""Dataset sampling (paper Fig. 7): annulus, sampling angle, joint grid; labels; validation."""

from __future__ import annotations

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from uvms_jax import indices, kin
from uvms_jax.surrogate import Sampling, analytic_index, make_dataset, mb_offset, sample_configurations

N = 256
# Geometry tolerances: float64 sampling, then FK through kin (rounding only).
GEOM_ATOL = 1e-9
SAMPLING = Sampling(task_point=(1.0, -2.0, 0.5), heading=math.radians(40.0))


@pytest.fixture(scope="module")
def chain():
    return kin.uvms12()


@pytest.fixture(scope="module")
def q(chain):
    return np.asarray(sample_configurations(jax.random.key(0), chain, SAMPLING, N, jnp.float64))


@pytest.fixture(scope="module")
def d2(chain):
    return make_dataset(jax.random.key(0), chain, SAMPLING, N, "w", jnp.float64)


def test_mb_offset_is_the_arm_base_of_uvms12():
    np.testing.assert_allclose(mb_offset(kin.uvms12(y_mb=0.75, l1=0.1)), [0.0, 0.75, 0.1], atol=1e-12)
    np.testing.assert_allclose(mb_offset(kin.uvms12(y_mb=0.5, l1=0.2)), [0.0, 0.5, 0.2], atol=1e-12)


def test_manipulator_base_lies_in_the_annulus_sector(q):
    # Oracle: joints 1–6 move a vehicle point p to (x, y, z) + R p with R = Rx Ry Rz, i.e. SciPy's
    # intrinsic "XYZ" Euler angles; MB is (0, y_MB, l1) on the vehicle (checked above).
    R = Rotation.from_euler("XYZ", q[:, 3:6]).as_matrix()
    p_mb = q[:, :3] + R @ np.array([0.0, 0.75, 0.1])
    rel = p_mb - np.asarray(SAMPLING.task_point)
    r = np.hypot(rel[:, 0], rel[:, 1])
    assert np.all(r >= SAMPLING.r_min - GEOM_ATOL) and np.all(r <= SAMPLING.r_max + GEOM_ATOL)
    angle = np.angle(np.exp(1j * (np.arctan2(rel[:, 1], rel[:, 0]) - SAMPLING.heading)))
    assert np.all(np.abs(angle) <= SAMPLING.phi / 2 + GEOM_ATOL)
    np.testing.assert_allclose(rel[:, 2], 0.0, atol=GEOM_ATOL)
    # The samples fill the sector, not a corner of it.
    assert r.min() < 0.5 and r.max() > 0.8 and angle.min() < -0.15 and angle.max() > 0.15


def test_rotations_and_arm_joints_lie_on_the_grid(q):
    nominal = np.array([0.0, 0.0, SAMPLING.heading + math.pi / 2, *SAMPLING.nominal_arm])
    steps = (q[:, 3:] - nominal) / SAMPLING.step
    np.testing.assert_allclose(steps, np.round(steps), atol=1e-9)
    assert np.abs(np.round(steps)).max() == 3  # ±15° in 5° steps
    assert len(np.unique(np.round(steps))) == 7
    np.testing.assert_allclose(np.degrees(SAMPLING.grid()), [-15, -10, -5, 0, 5, 10, 15])


@pytest.mark.slow
def test_mb_from_kinematics_matches_the_sampler(chain, q):
    # Joint 8's frame origin is MB at q = 0 and lies on the axes of joints 7 and 8 (neither moves it).
    p_mb = np.asarray(kin.kinematics(chain, jnp.asarray(q)).T_base_joint[:, 7, :3, 3])
    R = Rotation.from_euler("XYZ", q[:, 3:6]).as_matrix()
    np.testing.assert_allclose(p_mb, q[:, :3] + R @ np.array([0.0, 0.75, 0.1]), atol=GEOM_ATOL)


@pytest.mark.slow  # compiles the UVMS kinematics (tens of seconds on a loaded 2-core CPU)
def test_labels_and_inputs(chain, d2):
    assert d2.inputs == tuple(range(4, 11)) and d2.x.shape == (N, 7)
    np.testing.assert_array_equal(np.asarray(d2.x), np.asarray(d2.q[:, 4:11]))
    w = indices.manipulability(kin.jacobian(chain, d2.q))
    np.testing.assert_allclose(np.asarray(d2.y), np.asarray(w), rtol=1e-12)
    np.testing.assert_allclose(np.asarray(analytic_index(chain, d2.q, "w")), np.asarray(w), rtol=1e-12)
    # The nominal pose keeps w far from 0, so the relative error is well posed.
    assert float(d2.y.min()) > 5.0


@pytest.mark.slow
def test_full_range_and_continuous_modes(chain):
    q = np.asarray(sample_configurations(jax.random.key(1), chain, Sampling(mode="full"), N, jnp.float64))
    lower, upper = np.asarray(chain.lower), np.asarray(chain.upper)
    assert np.all(q[:, 3:] >= lower[3:]) and np.all(q[:, 3:] <= upper[3:])
    assert np.ptp(q[:, 6]) > 4.0  # spans most of ±2.8 rad
    s = Sampling(continuous=True)
    q = np.asarray(sample_configurations(jax.random.key(1), chain, s, N, jnp.float64))
    offsets = q[:, 6:] - np.asarray(s.nominal_arm)
    assert np.all(np.abs(offsets) <= s.half_range + 1e-12)
    assert not np.allclose(offsets / s.step, np.round(offsets / s.step))


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(r_min=1.0, r_max=0.5), "r_min"),
        (dict(mode="grid"), "mode"),
        (dict(phi=0.0), "phi"),
        (dict(step=0.0), "step"),
        (dict(nominal_arm=(0.0,) * 5), "nominal_arm"),
        (dict(task_point=(0.0, float("nan"), 0.0)), "finite"),
    ],
)
def test_sampling_rejects_bad_parameters(kwargs, match):
    with pytest.raises(ValueError, match=match):
        Sampling(**kwargs)


def test_make_dataset_rejects_bad_arguments(chain):
    with pytest.raises(ValueError, match="index"):
        make_dataset(jax.random.key(0), chain, Sampling(), 10, "kappa")
    with pytest.raises(ValueError, match="12-DOF"):
        make_dataset(jax.random.key(0), kin.docking_arm(), Sampling(), 10, "w")
    with pytest.raises(ValueError, match="positive"):
        sample_configurations(jax.random.key(0), chain, Sampling(), 0)
