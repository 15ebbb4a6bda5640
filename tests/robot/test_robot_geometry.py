"""The collision model from the description: URDF collision primitives and meshes, MJCF geoms,
each where the file puts it (hand-computed forward kinematics and MuJoCo's own model of the file
as oracles); unresolvable or unreadable meshes fall back to capsules, said once; the Bravo 7
keeps its capsules; the Franka Panda's STL meshes load and the planning scene and the sphere
checker work with them."""

import importlib.metadata
import logging
from pathlib import Path

import mujoco
import numpy as np
import pytest
import yaml

from uvms_jax import robot
from uvms_jax.hw._sim_model import sim_spec
from uvms_jax.plan import CollisionChecker, Context, SphereChecker, build_scene
from uvms_jax.robot._geometry import resolve_mesh

ROBOTS = importlib.metadata.distribution("example-robot-data").locate_file("cmeel.prefix/share/example-robot-data/robots")
PANDA = ROBOTS / "panda_description/urdf/panda.urdf"
SCENARIO = yaml.safe_load((Path(__file__).parents[2] / "configs" / "scenario" / "thesis_cage.yaml").read_text())
ATOL = 1e-8  # [m] float64 round-off of MuJoCo's and the hand-computed poses (and of numbers written in URDF text)

# A unit cube's corners, offset from the file's origin (MuJoCo re-centres meshes: the oracle
# compares vertices, not frames).
CUBE_OBJ = "".join(f"v {x} {y} {z}\n" for x in (0.1, 0.2) for y in (0.0, 0.05) for z in (-0.02, 0.03)) + """\
f 1 2 4 3
f 5 7 8 6
f 1 5 6 2
f 3 4 8 7
f 1 3 7 5
f 2 6 8 4
"""

URDF = """<robot name="two_link">
  <link name="base_link">
    <collision><origin xyz="0 0 0.05"/><geometry><box size="0.2 0.16 0.1"/></geometry></collision>
  </link>
  <link name="link1">
    <collision><origin xyz="0 0 0.15"/><geometry><cylinder radius="0.04" length="0.3"/></geometry></collision>
    <collision><origin xyz="0.01 0 0.1" rpy="0 0 0.5"/><geometry><mesh filename="meshes/cube.obj" scale="2 1 1"/></geometry></collision>
  </link>
  <link name="link2">
    <collision><origin xyz="0.01 0.02 0.125" rpy="0.1 0.2 0.3"/><geometry><box size="0.05 0.06 0.25"/></geometry></collision>
  </link>
  <link name="tool">
    <collision><origin xyz="0 0 0.05"/><geometry><sphere radius="0.03"/></geometry></collision>
  </link>
  <joint name="j1" type="revolute"><parent link="base_link"/><child link="link1"/>
    <origin xyz="0 0 0.1"/><axis xyz="0 0 1"/><limit lower="-3" upper="3" velocity="1" effort="1"/></joint>
  <joint name="j2" type="revolute"><parent link="link1"/><child link="link2"/>
    <origin xyz="0 0 0.3" rpy="0.3 0 0"/><axis xyz="0 1 0"/><limit lower="-2" upper="2" velocity="1" effort="1"/></joint>
  <joint name="flange" type="fixed"><parent link="link2"/><child link="tool"/><origin xyz="0 0 0.25"/></joint>
</robot>
"""


def _rot(axis: str, a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return {"x": np.array([[1, 0, 0], [0, c, -s], [0, s, c]]), "y": np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]]),
            "z": np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])}[axis]


def _T(xyz=(0, 0, 0), rpy=(0, 0, 0)) -> np.ndarray:
    T = np.eye(4)
    T[:3, :3] = _rot("z", rpy[2]) @ _rot("y", rpy[1]) @ _rot("x", rpy[0])  # URDF fixed-axis roll, pitch, yaw
    T[:3, 3] = xyz
    return T


def _Rq(axis: str, q: float) -> np.ndarray:
    T = np.eye(4)
    T[:3, :3] = _rot(axis, q)
    return T


def _write(tmp_path, text=URDF) -> Path:
    (tmp_path / "meshes").mkdir(exist_ok=True)
    (tmp_path / "meshes" / "cube.obj").write_text(CUBE_OBJ)
    path = tmp_path / "two_link.urdf"
    path.write_text(text)
    return path


def _model(arm: robot.Robot):
    model = robot.robot_spec(arm).compile()
    return model, mujoco.MjData(model)


def _geom_T(model, data, name: str) -> np.ndarray:
    g = model.geom(name).id
    T = np.eye(4)
    T[:3, :3] = data.geom_xmat[g].reshape(3, 3)
    T[:3, 3] = data.geom_xpos[g]
    return T


def _world_vertices(model, data, name: str) -> np.ndarray:
    g = model.geom(name).id
    k = model.geom_dataid[g]
    v = model.mesh_vert[model.mesh_vertadr[k]: model.mesh_vertadr[k] + model.mesh_vertnum[k]].astype(float)
    return data.geom_xpos[g] + v @ data.geom_xmat[g].reshape(3, 3).T


def _same_points(a: np.ndarray, b: np.ndarray, atol: float) -> bool:
    d = np.linalg.norm(a[:, None] - b[None], axis=2)
    return len(a) == len(b) and d.min(1).max() < atol and d.min(0).max() < atol


def test_urdf_shapes_sit_where_the_file_puts_them(tmp_path):
    arm = robot.load_robot(_write(tmp_path), tip="tool", link_radius=0.05)
    assert [(s.body, s.kind, s.link) for s in arm.shapes] == [
        (-1, "box", "base_link"), (0, "cylinder", "link1"), (0, "mesh", "link1"), (1, "box", "link2"),
        (1, "sphere", "tool")]
    assert arm.shapes[2].file == str((tmp_path / "meshes" / "cube.obj").resolve()) and arm.shapes[2].scale == (2, 1, 1)
    model, data = _model(arm)
    names = [model.geom(g).name for g in range(model.ngeom)]
    assert names == ["geom_base_0", "geom_j1_0", "geom_j1_1", "geom_j2_0", "geom_j2_1"]  # no capsules
    cube = np.array([[float(x) for x in line.split()[1:]] for line in CUBE_OBJ.splitlines() if line.startswith("v ")])
    rng = np.random.default_rng(0)
    for q in rng.uniform(arm.lower, arm.upper, (20, 2)):
        data.qpos[:] = q
        mujoco.mj_kinematics(model, data)
        # Forward kinematics by hand, from the URDF's numbers.
        T1 = _T((0, 0, 0.1)) @ _Rq("z", q[0])
        T2 = T1 @ _T((0, 0, 0.3), (0.3, 0, 0)) @ _Rq("y", q[1])
        expected = {"geom_base_0": _T((0, 0, 0.05)), "geom_j1_0": T1 @ _T((0, 0, 0.15)),
                    "geom_j2_0": T2 @ _T((0.01, 0.02, 0.125), (0.1, 0.2, 0.3)),
                    "geom_j2_1": T2 @ _T((0, 0, 0.25)) @ _T((0, 0, 0.05))}
        # Boxes and cylinders are convex meshes (MuJoCo re-centres those: compare vertices).
        for name, size in (("geom_base_0", (0.2, 0.16, 0.1)), ("geom_j2_0", (0.05, 0.06, 0.25))):
            corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]) * np.array(size) / 2
            T = expected[name]
            assert _same_points(_world_vertices(model, data, name), corners @ T[:3, :3].T + T[:3, 3], 1e-6), name
        local = (np.linalg.inv(expected["geom_j1_0"]) @ np.c_[_world_vertices(model, data, "geom_j1_0"), np.ones(64)].T).T
        np.testing.assert_allclose(np.linalg.norm(local[:, :2], axis=1), 0.04 / np.cos(np.pi / 32), atol=1e-6)
        np.testing.assert_allclose(np.abs(local[:, 2]), 0.15, atol=1e-6)
        np.testing.assert_allclose(_geom_T(model, data, "geom_j2_1")[:3, 3], expected["geom_j2_1"][:3, 3], atol=ATOL)
        T_mesh = T1 @ _T((0.01, 0, 0.1), (0, 0, 0.5))
        assert _same_points(_world_vertices(model, data, "geom_j1_1"),
                            (cube * [2, 1, 1]) @ T_mesh[:3, :3].T + T_mesh[:3, 3], 1e-6)
        # The sphere against the base box: the closed-form point–box distance less the radius.
        centre = np.linalg.inv(expected["geom_base_0"]) @ np.r_[data.geom_xpos[model.geom("geom_j2_1").id], 1.0]
        outside = np.maximum(np.abs(centre[:3]) - [0.1, 0.08, 0.05], 0.0)
        if np.any(outside > 0):
            d = mujoco.mj_geomDistance(model, data, model.geom("geom_base_0").id, model.geom("geom_j2_1").id,
                                       1.0, None)
            assert d == pytest.approx(np.linalg.norm(outside) - 0.03, abs=1e-6)


MJCF = """<mujoco model="geoms">
  <compiler angle="radian" meshdir="meshes"/>
  <asset>
    <mesh name="cube" file="cube.obj" scale="1 2 0.5"/>
    <mesh name="tet" vertex="0 0 0  0.05 0 0  0 0.05 0  0 0 0.05"/>
  </asset>
  <worldbody>
    <geom name="floor" type="plane" size="1 1 0.1"/>
    <body name="base">
      <geom name="b_box" type="box" size="0.1 0.08 0.02" pos="0 0 0.02"/>
      <geom name="b_visual" type="sphere" size="0.3" contype="0" conaffinity="0"/>
      <body name="upper" pos="0 0 0.1" euler="0.2 0 0">
        <joint name="shoulder" type="hinge" axis="0 1 0" range="-1.5 1.5"/>
        <geom name="u_capsule" type="capsule" fromto="0 0 0 0.3 0 0" size="0.03"/>
        <geom name="u_cube" type="mesh" mesh="cube" pos="0.1 0 0" euler="0.3 0.1 0"/>
        <body name="flange" pos="0.3 0 0">
          <geom name="f_ellipsoid" type="ellipsoid" size="0.02 0.03 0.04"/>
          <body name="lower" euler="0 0 0.3">
            <joint name="elbow" type="hinge" axis="0 0 1" range="-2 2"/>
            <geom name="l_cylinder" type="cylinder" fromto="0 0 0 0.25 0 0" size="0.02"/>
            <geom name="l_tet" type="mesh" mesh="tet" pos="0.2 0 0"/>
            <site name="hand" pos="0.25 0 0"/>
          </body>
        </body>
      </body>
    </body>
  </worldbody>
</mujoco>
"""


def test_mjcf_shapes_sit_where_mujoco_puts_the_files_geoms(tmp_path):
    """Oracle: MuJoCo's model of the description file itself, at the same joint angles."""
    (tmp_path / "meshes").mkdir()
    (tmp_path / "meshes" / "cube.obj").write_text(CUBE_OBJ)
    path = tmp_path / "arm.xml"
    path.write_text(MJCF)
    arm = robot.load_robot(path, base="base", tip="hand", link_radius=0.05)
    assert [(s.body, s.kind, s.link) for s in arm.shapes] == [
        (-1, "box", "base"), (0, "capsule", "upper"), (0, "mesh", "upper"), (0, "box", "flange"),
        (1, "cylinder", "lower"), (1, "mesh", "lower")]  # no visual geom, no floor
    assert arm.shapes[3].size == pytest.approx((0.04, 0.06, 0.08))  # the ellipsoid's bounding box
    original = mujoco.MjModel.from_xml_path(str(path))
    od = mujoco.MjData(original)
    model, data = _model(arm)
    pairs = {"b_box": "geom_base_0", "u_capsule": "geom_shoulder_0", "u_cube": "geom_shoulder_1",
             "l_cylinder": "geom_elbow_0", "l_tet": "geom_elbow_1"}
    for q in np.random.default_rng(1).uniform(arm.lower, arm.upper, (20, 2)):
        od.qpos[:], data.qpos[:] = q, q
        mujoco.mj_kinematics(original, od)
        mujoco.mj_kinematics(model, data)
        for theirs, ours in pairs.items():
            if original.geom(theirs).type[0] == mujoco.mjtGeom.mjGEOM_CAPSULE:
                np.testing.assert_allclose(_geom_T(model, data, ours), _geom_T(original, od, theirs), atol=ATOL)
                continue
            if original.geom(theirs).type[0] == mujoco.mjtGeom.mjGEOM_MESH:
                assert _same_points(_world_vertices(model, data, ours), _world_vertices(original, od, theirs), 1e-6)
        for theirs, ours in (("b_box", "geom_base_0"), ("l_cylinder", "geom_elbow_0")):  # primitives → hulls
            T = _geom_T(original, od, theirs)
            local = (np.linalg.inv(T) @ np.c_[_world_vertices(model, data, ours), np.ones(8 if "box" in theirs else 64)].T).T
            half = original.geom(theirs).size
            if "box" in theirs:
                np.testing.assert_allclose(np.abs(local[:, :3]), np.broadcast_to(half, (8, 3)), atol=1e-7)
            else:
                np.testing.assert_allclose(np.linalg.norm(local[:, :2], axis=1), half[0] / np.cos(np.pi / 32), atol=1e-7)
                np.testing.assert_allclose(np.abs(local[:, 2]), half[1], atol=1e-7)


def test_unresolvable_mesh_falls_back_to_capsules_said_once(tmp_path, caplog):
    text = URDF.replace("meshes/cube.obj", "package://nowhere_pkg/meshes/cube.stl")
    with caplog.at_level(logging.INFO, logger="uvms_jax.robot"):
        arm = robot.robot_from_config({"description": str(_write(tmp_path, text)), "tip": "tool", "link_radius": 0.05})
    assert arm.shapes == ()
    said = [r for r in caplog.records if "collision model" in r.getMessage()]
    assert len(said) == 1 and said[0].levelno == logging.WARNING
    assert "package://nowhere_pkg/meshes/cube.stl" in said[0].getMessage() and "capsules" in said[0].getMessage()
    model, _ = _model(arm)
    assert [model.geom(g).name for g in range(model.ngeom)] == ["geom_base", "geom_j1", "geom_j2"]
    assert all(model.geom(g).type[0] == mujoco.mjtGeom.mjGEOM_CAPSULE for g in range(model.ngeom))


@pytest.mark.parametrize("mesh, why", [("cube.dae", "STL and OBJ"), ("empty.stl", "cannot read")])
def test_unreadable_mesh_falls_back(tmp_path, caplog, mesh, why):
    path = _write(tmp_path, URDF.replace("meshes/cube.obj", f"meshes/{mesh}"))
    (tmp_path / "meshes" / mesh).write_text("")  # a skeleton file
    with caplog.at_level(logging.INFO, logger="uvms_jax.robot"):
        assert robot.load_robot(path, tip="tool", link_radius=0.05).shapes == ()
    assert [why in r.getMessage() for r in caplog.records if "collision model" in r.getMessage()] == [True]


def test_package_paths_resolve_by_ancestor_and_ros_package_path(tmp_path, monkeypatch):
    pkg = tmp_path / "ws" / "my_arm"
    (pkg / "meshes").mkdir(parents=True)
    (pkg / "urdf").mkdir()
    (pkg / "meshes" / "a.stl").write_text("x")
    assert resolve_mesh("package://my_arm/meshes/a.stl", pkg / "urdf") == (pkg / "meshes" / "a.stl").resolve()
    assert resolve_mesh("package://my_arm/meshes/a.stl", tmp_path) is None
    monkeypatch.setenv("ROS_PACKAGE_PATH", str(tmp_path / "ws"))
    assert resolve_mesh("package://my_arm/meshes/a.stl", None) == (pkg / "meshes" / "a.stl").resolve()
    assert resolve_mesh(f"file://{pkg}/meshes/a.stl", None) == (pkg / "meshes" / "a.stl").resolve()
    assert resolve_mesh("../meshes/a.stl", pkg / "urdf") == (pkg / "meshes" / "a.stl").resolve()


def test_capsules_on_request_and_for_the_bravo7(tmp_path):
    assert robot.load_robot(_write(tmp_path), tip="tool", link_radius=0.05, collision="capsules").shapes == ()
    arm = robot.robot_from_config({"description": str(_write(tmp_path)), "tip": "tool", "link_radius": 0.05,
                                   "collision": "capsules"})
    assert arm.shapes == ()
    with pytest.raises(ValueError, match="collision must be"):
        robot.load_robot(_write(tmp_path), tip="tool", link_radius=0.05, collision="meshes")
    bravo = robot.load_arm("bravo7")  # its URDF has no collision geometry: capsules, as before
    model = robot.robot_spec(bravo).compile()
    assert bravo.shapes == () and model.nmesh == 0
    names = [model.geom(g).name for g in range(model.ngeom)]
    assert names == ["geom_base", *(f"geom_{j}" for j in bravo.joint_names), "geom_jaw_left", "geom_jaw_right"]


@pytest.fixture(scope="module")
def panda():
    """The Panda with its own hand (the gripper joint of its URDF)."""
    return robot.load_robot(PANDA, tip="panda_hand_tcp", link_radius=0.05, gripper="panda_finger_joint1",
                            gripper_velocity=0.1)


def test_panda_loads_its_stl_meshes(panda):
    links = [f"panda_link{i}" for i in range(8)] + ["panda_hand"]
    assert [s.link for s in panda.shapes] == links  # the fingers are the hand's (Robot.fingers)
    assert all(s.kind == "mesh" and Path(s.file).is_file() and s.file.endswith(".stl") for s in panda.shapes)
    assert all(Path(s.file).is_relative_to(Path(ROBOTS).resolve()) for s in panda.shapes)  # package://example-robot-data
    assert [len(f.shapes) for f in panda.fingers] == [4, 4]  # screw mount, sledge, diagonal, rubber tip
    pairs = robot.self_collision_pairs(panda, n_samples=50)
    assert len(pairs["adjacent"]) == 7 and ("panda_link0", "panda_link1") in pairs["adjacent"]
    sim = sim_spec(panda).compile()  # the simulated arm: the same meshes (fingers' boxes as convex meshes)
    assert sim.nmesh == 9 + 8 and all(sim.body_mass[1:] > 0)


def test_panda_scene_and_sphere_checker(panda):
    arm = {**SCENARIO["arm"], "jaws_open": 0.04}  # the Panda's fingers slide 4 cm each
    scene = build_scene(panda, {**SCENARIO, "arm": arm, "start_q": None})
    m = scene.model
    arm_meshes = [g for g in range(m.ngeom) if m.geom(g).name.startswith("geom_panda")
                  or m.geom(g).name.startswith("geom_base")]
    assert len(arm_meshes) == 9 + 8 and all(m.geom_type[g] == mujoco.mjtGeom.mjGEOM_MESH for g in arm_meshes)
    reference = CollisionChecker(scene)
    ctx = Context()
    assert reference.is_valid(scene.start_q, ctx)
    fast = SphereChecker(reference)
    Q = np.random.default_rng(2).uniform(reference.lower, reference.upper, (400, panda.n_joints))
    ok, mj = fast.spheres_free(Q, ctx), reference.is_valid_batch(Q, ctx)
    assert not np.any(ok & ~mj), "the spheres accepted a configuration MuJoCo rejects"
    # The spheres bulge out of the meshes (the wrist links 5 and 7 are 2 cm apart at most), so
    # they reject some configurations MuJoCo accepts and MuJoCo decides those: motions still
    # get MuJoCo's answer.
    starts = Q[mj][:6]
    for q0, q1 in zip(starts[:-1], starts[1:]):
        q1 = q0 + 0.2 * (q1 - q0)
        assert fast.motion_is_valid(q0, q1, ctx, 0.02) == reference.path_is_valid(np.stack([q0, q1]), ctx, 0.02)


def _yourdfpy_panda():
    import yourdfpy

    return yourdfpy.URDF.load(str(PANDA), load_meshes=False, build_collision_scene_graph=False)


def _box_corners(size, T) -> np.ndarray:
    corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]) * np.asarray(size) / 2
    return corners @ T[:3, :3].T + T[:3, 3]


def test_panda_fingers_load_from_its_urdf(panda):
    assert [(f.link, f.joint, f.body, f.multiplier, f.offset) for f in panda.fingers] == [
        ("panda_leftfinger", "panda_finger_joint1", 6, 1.0, 0.0), ("panda_rightfinger", "panda_finger_joint2", 6, 1.0, 0.0)]
    assert (panda.gripper.joint, panda.gripper.lower, panda.gripper.upper) == ("panda_finger_joint1", 0.0, 0.04)
    T_link7_hand = _yourdfpy_panda().get_transform("panda_hand", "panda_link7")
    for f, sign in zip(panda.fingers, (1, -1)):  # the URDF's axes: ±y of the hand
        np.testing.assert_allclose(T_link7_hand[:3, :3].T @ f.axis, [0, sign, 0], atol=ATOL)
        assert [(s.kind, s.link) for s in f.shapes] == [("box", f.link)] * 4 and all(s.body == 6 for s in f.shapes)
    # Settings that name a gripper joint the file lacks keep the card's finger boxes.
    jaws = robot.load_robot(PANDA, tip="panda_hand_tcp", link_radius=0.05,
                            gripper={"joint": "jaws", "lower": 0.0, "upper": 0.1, "velocity": 0.1})
    assert jaws.fingers == ()
    with pytest.raises(ValueError, match="outside the gripper's limits"):
        robot.robot_spec(panda, jaws_open=0.05)


def test_panda_fingers_sit_where_yourdfpy_puts_them(panda):
    """Oracle: yourdfpy's forward kinematics of the URDF (its mimic joint included)."""
    urdf = _yourdfpy_panda()
    link_of = {link.name: link for link in urdf.robot.links}
    rng = np.random.default_rng(3)
    sim = sim_spec(panda, dynamics=False).compile()
    sim_data = mujoco.MjData(sim)
    for opening in (0.0, 0.013, 0.04):
        model, data = _model_at(panda, opening)
        for q in rng.uniform(panda.lower, panda.upper, (3, panda.n_joints)):
            data.qpos[:] = q
            mujoco.mj_kinematics(model, data)
            urdf.update_cfg({**dict(zip(panda.joint_names, q)), "panda_finger_joint1": opening})
            for name, v in zip(panda.joint_names + ("panda_finger_joint1", "panda_finger_joint2"), (*q, opening, opening)):
                sim_data.qpos[sim.joint(name).qposadr[0]] = v  # the simulated arm: fingers on their slide joints
            mujoco.mj_kinematics(sim, sim_data)
            for f in panda.fingers:
                T_link = urdf.get_transform(f.link, "panda_link0")
                for k, c in enumerate(link_of[f.link].collisions):
                    expected = _box_corners(c.geometry.box.size, T_link @ c.origin)
                    for m, d in ((model, data), (sim, sim_data)):
                        assert _same_points(_world_vertices(m, d, f"geom_{f.joint}_{k}"), expected, 1e-6), (f.link, k)
    # The mimic follows the gripper joint in the simulation (a joint equality).
    mujoco.mj_resetData(sim, sim_data)
    sim_data.qpos[sim.joint("panda_finger_joint1").qposadr[0]] = 0.03
    for _ in range(500):
        mujoco.mj_step(sim, sim_data)
    q1, q2 = (sim_data.qpos[sim.joint(j).qposadr[0]] for j in ("panda_finger_joint1", "panda_finger_joint2"))
    assert q2 == pytest.approx(q1, abs=1e-3)  # soft constraint: within a millimetre


def _model_at(arm: robot.Robot, opening: float):
    model = robot.robot_spec(arm, jaws_open=opening).compile()
    return model, mujoco.MjData(model)
