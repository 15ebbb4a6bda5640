"""URDF/MJCF import against independent implementations: pytorch-kinematics (URDF), MuJoCo (MJCF),
hand-composed transforms, and the project's own Bravo 7 model."""

import importlib.metadata

import jax
import mujoco
import numpy as np
import pytest
import pytorch_kinematics as pk
import torch

from uvms_jax import kin, robot

N_RANDOM = 1000
ATOL_ORACLE = 1e-6  # pytorch-kinematics parses URDF numbers as float32 before casting to float64
ATOL_64 = 1e-9  # float64 computations of the same model: only round-off differs
ATOL_TEXT = 1e-8  # a model written to URDF with 10 significant digits and read back
ATOL_MJCF_TEXT = 1e-6  # a model MuJoCo writes as MJCF (6 significant digits) and reads back

# Real arms shipped inside the example-robot-data wheel (offline): (file, base link, tip link).
ROBOTS = importlib.metadata.distribution("example-robot-data").locate_file(
    "cmeel.prefix/share/example-robot-data/robots"
)
ARMS = {
    "panda": ("panda_description/urdf/panda.urdf", None, "panda_hand_tcp"),  # 7R, fixed flange + hand
    "xarm7": ("xarm_description/urdf/xarm7.urdf", None, None),  # 7R, fixed world and eef joints
    "ur5": ("ur_description/urdf/ur5_robot.urdf", "base_link", "tool0"),  # 6R, fixed tool0
    "kinova": ("kinova_description/robots/kinova.urdf", None, "j2s6s200_end_effector"),  # continuous joints
    "z1": ("z1_description/urdf/z1.urdf", None, "gripperStator"),  # 6R
    "so100": ("so_arm_description/urdf/so100.urdf", None, "gripper"),  # 5R
    "tiago": ("tiago_description/robots/tiago.urdf", None, "arm_4_link"),  # prismatic torso + 4R
}

# Reach Alpha 5 (4 DOF + jaws), the package's description (public alpha_description numbers).
ALPHA5_URDF = (robot.DESCRIPTIONS / "alpha5.urdf").read_text()


def _anonymous(chain):
    """The same chain with generic names, so arms of one topology share one compiled program."""
    return chain.replace(joint_names=tuple(f"q{i}" for i in range(chain.n_joints)), name="arm")


_pose_and_jacobian = jax.jit(lambda chain, q: (kin.fk(chain, q), kin.jacobian(chain, q)))


def pose_and_jacobian(chain, q):
    T, J = _pose_and_jacobian(_anonymous(chain), q)
    return np.asarray(T), np.asarray(J)


def random_q(chain, n, seed=0):
    rng = np.random.default_rng(seed)
    return rng.uniform(np.asarray(chain.lower), np.asarray(chain.upper), (n, chain.n_joints))


def _oracle(urdf: bytes, tip: str, base: str = ""):
    return pk.build_serial_chain_from_urdf(urdf, tip, base).to(dtype=torch.float64)


def _check_against_pytorch_kinematics(chain, urdf: bytes, tip: str, base: str = "", seed: int = 0):
    oracle = _oracle(urdf, tip, base)
    assert oracle.get_joint_parameter_names() == list(chain.joint_names)
    q = random_q(chain, N_RANDOM, seed)
    T, J = pose_and_jacobian(chain, q)
    np.testing.assert_allclose(T, oracle.forward_kinematics(torch.from_numpy(q)).get_matrix().numpy(), atol=ATOL_ORACLE)
    np.testing.assert_allclose(J, oracle.jacobian(torch.from_numpy(q)).numpy(), atol=ATOL_ORACLE)


@pytest.mark.parametrize("arm", list(ARMS))
def test_real_arms_match_pytorch_kinematics(arm):
    path, base, tip = ARMS[arm]
    chain = robot.chain_from_urdf(ROBOTS / path, base_link=base, tip_link=tip)
    _check_against_pytorch_kinematics(chain, (ROBOTS / path).read_bytes(), tip or "link_eef", base or "")


def test_the_arms_cover_4_to_7_joints_fixed_prismatic_and_continuous():
    chains = {arm: robot.chain_from_urdf(ROBOTS / p, base_link=b, tip_link=t) for arm, (p, b, t) in ARMS.items()}
    assert {c.n_joints for c in chains.values()} == {5, 6, 7}  # 4 DOF: the Alpha 5 below
    assert chains["tiago"].kinds[0] == "prismatic"
    # Kinova's continuous joints 1, 4 and 6 get [−π, π]; the others keep their URDF limits.
    np.testing.assert_allclose(np.asarray(chains["kinova"].upper)[[0, 3, 5]], np.pi)
    np.testing.assert_allclose(np.asarray(chains["kinova"].lower)[1], 0.820304748437)
    np.testing.assert_allclose(np.asarray(chains["panda"].velocity_limits), [2.175] * 4 + [2.61] * 3)


def test_alpha5_matches_pytorch_kinematics_and_the_hand_composed_tool():
    chain = robot.chain_from_urdf(ALPHA5_URDF, tip_link="ee_base_link")
    assert chain.n_joints == 4 and chain.joint_names == ("axis_e", "axis_d", "axis_c", "axis_b")
    _check_against_pytorch_kinematics(chain, ALPHA5_URDF.encode(), "ee_base_link")
    # At q = 0 the origins add up (the yaw of 3.14159 after C turns B's x offset, almost
    # flipping it): z = 0.014 + 0.033 − 0.1453 + 0.033 + 0.09975, the fixed tool joint included.
    yaw = 3.14159
    expected = [-0.02 - 0.04 + 0.02 * np.cos(yaw), 0.02 * np.sin(yaw), 0.014 + 0.033 - 0.1453 + 0.033 + 0.09975]
    np.testing.assert_allclose(np.asarray(chain.T_base_tool0)[:3, 3], expected, atol=1e-12)
    # The default tip is the only leaf: the jaws' push rod, reached through the prismatic A.
    full = robot.chain_from_urdf(ALPHA5_URDF)
    assert full.n_joints == 5 and full.kinds[-1] == "prismatic"


def test_bravo7_urdf_imports_as_kin_bravo7():
    ref = kin.bravo7()
    chain = robot.chain_from_urdf(kin.bravo7_urdf(), tip_link="tool")
    assert (chain.kinds, chain.joint_names, chain.name) == (ref.kinds, ref.joint_names, ref.name)
    for field in ("twists", "T_base_tool0", "T_base_joint0", "lower", "upper", "velocity_limits"):
        np.testing.assert_allclose(np.asarray(getattr(chain, field)), np.asarray(getattr(ref, field)), atol=ATOL_64)


@pytest.mark.parametrize("arm", ["panda", "kinova", "tiago"])
def test_to_urdf_round_trips(arm):
    path, base, tip = ARMS[arm]
    chain = robot.chain_from_urdf(ROBOTS / path, base_link=base, tip_link=tip)
    again = robot.chain_from_urdf(kin.to_urdf(chain))
    assert (again.kinds, again.joint_names, again.name) == (chain.kinds, chain.joint_names, chain.name)
    for field in ("twists", "T_base_tool0", "T_base_joint0", "lower", "upper", "velocity_limits"):
        np.testing.assert_allclose(np.asarray(getattr(again, field)), np.asarray(getattr(chain, field)), atol=ATOL_TEXT)


def test_path_argument_and_text_agree():
    path, base, tip = ARMS["z1"]
    a = robot.chain_from_urdf(ROBOTS / path, tip_link=tip)
    b = robot.chain_from_urdf((ROBOTS / path).read_text(), tip_link=tip)
    np.testing.assert_array_equal(np.asarray(a.twists), np.asarray(b.twists))


def _urdf(joint_xml: str) -> str:
    return (
        '<robot name="r"><link name="a"/><link name="b"/>'
        f'<joint name="j" {joint_xml}<parent link="a"/><child link="b"/></joint></robot>'
    )


@pytest.mark.parametrize(
    "source,kwargs,match",
    [
        (ROBOTS / ARMS["panda"][0], {"tip_link": "panda_rightfinger"}, "mimics"),
        (ROBOTS / ARMS["panda"][0], {}, "candidates are"),
        (ROBOTS / ARMS["panda"][0], {"tip_link": "nowhere"}, "not found"),
        (ROBOTS / ARMS["panda"][0], {"base_link": "panda_link3", "tip_link": "panda_link1"}, "not below"),
        (_urdf('type="floating">'), {}, "floating"),
        (_urdf('type="revolute"><axis xyz="0 0 1"/>'), {}, "needs <limit"),
        (_urdf('type="revolute"><axis xyz="0 0 0"/><limit lower="-1" upper="1"/>'), {}, "zero length"),
        (_urdf('type="fixed">'), {}, "no moving joint"),
        ("/no/such/file.urdf", {}, "not found"),
    ],
)
def test_urdf_errors_are_clear(source, kwargs, match):
    with pytest.raises(ValueError, match=match):
        robot.chain_from_urdf(source, **kwargs)


def test_non_unit_axes_are_normalised():
    text = _urdf('type="prismatic"><axis xyz="0 0 2"/><limit lower="-1" upper="1"/>')
    chain = robot.chain_from_urdf(text)
    np.testing.assert_allclose(np.asarray(chain.twists), [[0, 0, 1, 0, 0, 0]])


# MJCF with what a URDF cannot say: two joints in one body, a hinge off the body origin with a
# non-unit axis and a ref, a slide, an unlimited hinge, a rotated site, and a base that is not
# the world.
MJCF = """
<mujoco model="test_arm">
  <compiler angle="radian"/>
  <worldbody>
    <body name="mount" pos="0.1 -0.2 0.3" quat="0.9 0.1 0.3 0.2">
      <body name="l1" pos="0 0 0.1">
        <joint name="a" type="hinge" axis="0 0 2" range="-2 2"/>
        <joint name="b" type="hinge" axis="1 1 0" pos="0.05 0 0" range="-1.5 1.5" ref="0.3"/>
        <geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.02"/>
        <body name="l2" pos="0.3 0 0" euler="0.2 0.1 -0.4">
          <joint name="c" type="slide" axis="1 0 0" range="-0.1 0.2"/>
          <geom type="box" size="0.05 0.02 0.02"/>
          <body name="l3" pos="0.2 0.05 0">
            <joint name="d" type="hinge" axis="0 1 0"/>
            <geom type="sphere" size="0.02"/>
            <site name="tcp" pos="0.1 0 0.02" euler="0.3 -0.2 0.1"/>
          </body>
        </body>
      </body>
    </body>
  </worldbody>
</mujoco>
"""


def test_mjcf_matches_mujoco_kinematics_and_jacobian():
    chain = robot.chain_from_mjcf(MJCF, base_body="mount", tip_site="tcp")
    assert chain.joint_names == ("a", "b", "c", "d") and chain.kinds[2] == "prismatic" and chain.name == "test_arm"
    np.testing.assert_allclose(np.asarray(chain.upper), [2.0, 1.5, 0.2, np.pi])
    model = mujoco.MjModel.from_xml_string(MJCF)
    data = mujoco.MjData(model)
    site, mount = model.site("tcp").id, model.body("mount").id
    q = random_q(chain, 50, seed=3)
    T, J = pose_and_jacobian(chain, q)
    jacp, jacr = np.zeros((3, model.nv)), np.zeros((3, model.nv))
    for qi, Ti, Ji in zip(q, T, J):
        data.qpos[:] = qi
        mujoco.mj_kinematics(model, data)
        mujoco.mj_comPos(model, data)
        R_wm, p_wm = data.xmat[mount].reshape(3, 3), data.xpos[mount]
        np.testing.assert_allclose(Ti[:3, 3], R_wm.T @ (data.site_xpos[site] - p_wm), atol=ATOL_64)
        np.testing.assert_allclose(Ti[:3, :3], R_wm.T @ data.site_xmat[site].reshape(3, 3), atol=ATOL_64)
        mujoco.mj_jacSite(model, data, jacp, jacr, site)
        np.testing.assert_allclose(Ji, np.concatenate([R_wm.T @ jacp, R_wm.T @ jacr]), atol=ATOL_64)


def test_bravo7_mjcf_imports_as_kin_bravo7():
    ref = kin.bravo7()
    chain = robot.chain_from_mjcf(robot.robot_mjcf(robot.load_arm("bravo7")), tip_site="tool")
    assert chain.joint_names == ref.joint_names
    q = random_q(ref, 200, seed=4)
    for a, b in zip(pose_and_jacobian(chain, q), pose_and_jacobian(ref, q)):
        np.testing.assert_allclose(a, b, atol=ATOL_MJCF_TEXT)


def _mjcf(body: str, extra: str = "") -> str:
    return f'<mujoco><worldbody><body name="b">{body}<geom size="0.1"/></body></worldbody>{extra}</mujoco>'


@pytest.mark.parametrize(
    "source,kwargs,match",
    [
        (_mjcf('<joint type="ball"/>'), {}, "ball"),
        (_mjcf("<freejoint/>"), {}, "free"),
        (_mjcf('<joint name="s" type="slide"/>'), {}, "no range"),
        (
            _mjcf(
                '<joint name="h1"/><body name="c"><joint name="h2"/><geom size="0.1"/></body>',
                '<equality><joint joint1="h1" joint2="h2"/></equality>',
            ),
            {},
            "equality",
        ),
        (_mjcf('<joint name="h"/>'), {"tip_body": "b", "tip_site": "s"}, "not both"),
        (_mjcf('<joint name="h"/>'), {"tip_site": "s"}, "not found"),
        (_mjcf('<joint name="h"/>'), {"base_body": "nope"}, "not found"),
    ],
)
def test_mjcf_errors_are_clear(source, kwargs, match):
    with pytest.raises(ValueError, match=match):
        robot.chain_from_mjcf(source, **kwargs)
