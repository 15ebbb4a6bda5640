"""kin.uvms: any arm on a vehicle, against the vehicle pose composed by hand (scipy rotations)."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from uvms_jax import kin

ATOL = 1e-9  # float64 composition of the same rigid motions: only round-off differs
FD_STEP = 1e-6
FD_ATOL = 1e-7  # central differences in float64


def _uvms12_by_hand(y_mb=0.75, l1=0.1, l2=0.4, l3=0.4):
    """The dexterity paper's UVMS written out twist by twist (docs/theory.md §1.2)."""
    x, y, z = np.eye(3)
    q2, q3, q4 = (0.0, y_mb, l1), (0.0, y_mb + l2, l1), (0.0, y_mb + l2 + l3, l1)
    rev = lambda w, p: np.concatenate([-np.cross(w, p), w])  # noqa: E731
    twists = [np.concatenate([a, np.zeros(3)]) for a in (x, y, z)]
    twists += [rev(w, (0, 0, 0)) for w in (x, y, z)]
    twists += [rev(w, p) for w, p in [(z, q2), (-x, q2), (-x, q3), (z, q4), (-x, q4), (y, q4)]]
    tool = np.eye(4)
    tool[:3, 3] = q4
    return np.stack(twists), tool


def _vehicle_pose(values: dict) -> np.ndarray:
    """Trans(x, y, z) · Rx(roll) Ry(pitch) Rz(yaw), missing DOFs at 0."""
    T = np.eye(4)
    T[:3, :3] = Rotation.from_euler("XYZ", [values.get(k, 0.0) for k in ("roll", "pitch", "yaw")]).as_matrix()
    T[:3, 3] = [values.get(k, 0.0) for k in ("x", "y", "z")]
    return T


def _random_mount(rng) -> np.ndarray:
    T = np.eye(4)
    T[:3, :3] = Rotation.random(random_state=rng.integers(1 << 31)).as_matrix()
    T[:3, 3] = rng.uniform(-0.5, 0.5, 3)
    return T


@pytest.mark.parametrize("y_mb,l1", [(0.75, 0.1), (0.5, 0.2)])
def test_uvms12_equals_the_hand_built_twists(y_mb, l1):
    chain = kin.uvms12(y_mb=y_mb, l1=l1)
    twists, tool = _uvms12_by_hand(y_mb=y_mb, l1=l1)
    np.testing.assert_allclose(np.asarray(chain.twists), twists, atol=1e-15)
    np.testing.assert_allclose(np.asarray(chain.T_base_tool0), tool, atol=1e-15)
    assert chain.joint_names == ("x", "y", "z", "theta_x", "theta_y", "theta_z") + tuple(
        f"theta_m{i}" for i in range(1, 7)
    )
    assert chain.kinds == ("prismatic",) * 3 + ("revolute",) * 9 and chain.name == "uvms12"
    np.testing.assert_allclose(np.asarray(chain.upper)[:6], [10.0] * 3 + [np.pi] * 3)
    np.testing.assert_allclose(np.asarray(chain.upper)[6:], kin.docking_arm().upper)
    np.testing.assert_allclose(np.asarray(chain.velocity_limits), [1.0] * 3 + [0.5] * 3 + [1.0] * 6)
    # Every joint frame lies on its joint's axis (ξ = [−ω × p, ω] holds at the frame origin).
    frames = np.asarray(chain.T_base_joint0)
    for i in range(6, 12):
        w = twists[i, 3:]
        np.testing.assert_allclose(-np.cross(w, frames[i, :3, 3]), twists[i, :3], atol=1e-15)
    # Joint 8's frame is the manipulator base MB.
    np.testing.assert_allclose(frames[7, :3, 3], [0.0, y_mb, l1], atol=1e-15)


@pytest.mark.parametrize(
    "dofs", [kin.VEHICLE_DOFS, ("x", "y", "z", "yaw"), ("yaw",)], ids=["6dof", "4dof", "yaw"]
)
def test_fk_is_vehicle_pose_times_mount_times_arm_fk(dofs):
    rng = np.random.default_rng(0)
    arm = kin.bravo7()
    mount = _random_mount(rng)
    chain = kin.uvms(arm, mount=mount, vehicle_dofs=dofs)
    assert chain.n_joints == len(dofs) + 6 and chain.joint_names[len(dofs):] == arm.joint_names
    n = 64
    q_v = rng.uniform(-np.pi, np.pi, (n, len(dofs)))
    q_a = rng.uniform(np.asarray(arm.lower), np.asarray(arm.upper), (n, 6))
    T = np.asarray(kin.fk(chain, np.concatenate([q_v, q_a], axis=1)))
    T_arm = np.asarray(kin.fk(arm, q_a))
    expected = np.stack([_vehicle_pose(dict(zip(dofs, qv))) @ mount @ Ta for qv, Ta in zip(q_v, T_arm)])
    np.testing.assert_allclose(T, expected, atol=ATOL)
    # The arm's columns of the Jacobian are the arm's own Jacobian turned into the world frame.
    J = np.asarray(kin.jacobian(chain, np.concatenate([q_v, q_a], axis=1)))
    J_arm = np.asarray(kin.jacobian(arm, q_a))
    R = np.stack([_vehicle_pose(dict(zip(dofs, qv)))[:3, :3] @ mount[:3, :3] for qv in q_v])
    np.testing.assert_allclose(J[:, :3, len(dofs):], R @ J_arm[:, :3], atol=ATOL)
    np.testing.assert_allclose(J[:, 3:, len(dofs):], R @ J_arm[:, 3:], atol=ATOL)


def test_vehicle_jacobian_columns_match_finite_differences():
    arm = kin.docking_arm()
    chain = kin.uvms(arm, mount=_random_mount(np.random.default_rng(1)))
    rng = np.random.default_rng(2)
    q = np.concatenate([rng.uniform(-1, 1, (8, 6)), rng.uniform(-1, 1, (8, 6))], axis=1)
    J = np.asarray(kin.jacobian(chain, q))
    for i in range(6):
        dq = np.zeros(12)
        dq[i] = FD_STEP
        Tp, Tm = np.asarray(kin.fk(chain, q + dq)), np.asarray(kin.fk(chain, q - dq))
        np.testing.assert_allclose(J[:, :3, i], (Tp[:, :3, 3] - Tm[:, :3, 3]) / (2 * FD_STEP), atol=FD_ATOL)


def test_limits_names_and_frames():
    arm = kin.docking_arm()
    mount = _random_mount(np.random.default_rng(3))
    chain = kin.uvms(arm, mount=mount, vehicle_dofs=("x", "y", "z", "yaw"), translation_limit=3.0, name="rov")
    assert chain.name == "rov" and chain.joint_names[:4] == ("x", "y", "z", "theta_z")
    np.testing.assert_allclose(np.asarray(chain.lower)[:4], [-3.0, -3.0, -3.0, -np.pi])
    np.testing.assert_allclose(np.asarray(chain.T_base_joint0)[4:], mount @ np.asarray(arm.T_base_joint0), atol=ATOL)
    assert kin.uvms(arm).name == "docking_arm_uvms"


@pytest.mark.parametrize(
    "kwargs,match",
    [
        ({"vehicle_dofs": ("x", "surge")}, "unknown vehicle DOFs"),
        ({"vehicle_dofs": ("yaw", "x")}, "order"),
        ({"vehicle_dofs": ("x", "x")}, "repeated"),
        ({"mount": np.eye(3)}, r"\(4, 4\)"),
        ({"mount": np.diag([1.0, 1.0, -1.0, 1.0])}, "rotation"),
        ({"translation_limit": 0.0}, "positive"),
    ],
)
def test_bad_arguments_raise_clear_errors(kwargs, match):
    with pytest.raises(ValueError, match=match):
        kin.uvms(kin.docking_arm(), **kwargs)


def test_arm_joint_named_like_a_vehicle_joint_is_refused():
    arm = kin.docking_arm()
    arm = arm.replace(joint_names=("x",) + arm.joint_names[1:])
    with pytest.raises(ValueError, match="named like vehicle joints"):
        kin.uvms(arm)
