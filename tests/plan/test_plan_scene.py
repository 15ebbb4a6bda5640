"""Scene and collision checker: geometry from config, contexts, a capsule through a thin box."""

import copy
from pathlib import Path

import mujoco
import numpy as np
import pytest
import yaml
from scipy.spatial.transform import Rotation

from uvms_jax import kin
from uvms_jax.plan import CollisionChecker, Context, SceneSpec, build_scene, densify
from uvms_jax.robot import load_arm  # noqa: E402

BRAVO7 = load_arm("bravo7")

SCENARIO = Path(__file__).parents[2] / "configs" / "scenario" / "thesis_cage.yaml"
FK_ATOL = 1e-9  # float64 FK of kin vs MuJoCo site: same maths, round-off only
DIST_ATOL = 1e-6  # separated pairs: both MuJoCo paths solve the same convex distance problem
PEN_ATOL = 2e-3  # penetrating pairs: depth estimates of EPA and mj_geomDistance differ by < 2 mm
C0 = Context()  # nothing held, nothing ignored: every query names its context


@pytest.fixture(scope="module")
def raw():
    return yaml.safe_load(SCENARIO.read_text())


@pytest.fixture(scope="module")
def scene(raw):
    return build_scene(BRAVO7, raw)


def _rpy(R):
    """URDF roll-pitch-yaw of ``R = Rz(yaw) Ry(pitch) Rx(roll)``: scipy's extrinsic x-y-z angles."""
    return Rotation.from_matrix(R).as_euler("xyz")


def _with_box(raw, name, T, size):
    """The scenario plus one box obstacle with pose ``T`` (4, 4) and full ``size``."""
    spec = copy.deepcopy(raw)
    spec["tables"].append({"name": name, "pos": T[:3, 3].tolist(), "size": list(size),
                           "rpy": _rpy(T[:3, :3]).tolist()})
    return build_scene(BRAVO7, spec)


def test_scene_from_config(scene, raw):
    spec = scene.spec
    assert spec.cage_size == (2.0, 2.0, 1.0)
    sizes = {o.name: o for o in spec.objects}
    assert sizes["cube1"].dims == (0.08, 0.08, 0.08) and sizes["cube2"].dims == (0.08, 0.08, 0.08)
    assert sizes["cylinder"].dims == (0.04, 0.06)
    assert sizes["hexagon"].dims == (0.04, 0.06)
    assert sorted(scene.objects) == [1, 2, 3, 4] and sorted(scene.bases) == [5, 6, 7, 8]
    # Every object rests on its table: bottom face on the table top.
    for node, o in scene.objects.items():
        top = scene.tables[o.table].T_world_top
        bottom = scene.T_world_object(node) @ np.array([0, 0, -o.height / 2, 1])
        assert np.isclose((np.linalg.inv(top) @ bottom)[2], 0.0, atol=1e-12)
    # Hexagonal prism volume = 3√3/2 a² h.
    assert np.isclose(sizes["hexagon"].volume, 1.5 * np.sqrt(3) * 0.04**2 * 0.06)


def test_site_matches_kin_fk(scene):
    """The arm inside the scene is kin's arm: tool site = T_world_base · fk(q)."""
    d = mujoco.MjData(scene.model)
    chain = kin.bravo7()
    for q in np.random.default_rng(0).uniform(0, 3.0, size=(5, 6)):
        d.qpos[:] = q
        mujoco.mj_kinematics(scene.model, d)
        p = (scene.T_world_base @ np.asarray(kin.fk(chain, q)))[:3, 3]
        np.testing.assert_allclose(d.site_xpos[0], p, atol=FK_ATOL)


def test_bad_spec_names_problem(raw):
    spec = copy.deepcopy(raw)
    spec["objects"][0]["table"] = "nowhere"
    with pytest.raises(ValueError, match="nowhere"):
        SceneSpec.from_mapping(spec)
    spec = copy.deepcopy(raw)
    spec["objects"][0]["shape"] = "sphere"
    with pytest.raises(ValueError, match="sphere"):
        SceneSpec.from_mapping(spec)


def test_start_is_valid_and_limits(scene):
    ch = CollisionChecker(scene)
    q = np.asarray(scene.start_q)
    assert ch.is_valid(q, C0) and ch.is_valid(q, C0, margin=0.0)
    assert ch.clearance(q, C0) > ch.margin
    q_out = q.copy()
    q_out[1] = 3.6  # F's limit is 3.5
    assert not ch.is_valid(q_out, C0)
    with pytest.raises(ValueError, match="margin"):
        ch.is_valid(q, C0, margin=0.5)


def test_capsule_through_thin_box_is_a_collision(raw, scene):
    """A capsule whose axis runs through a thin box, both ends outside — MuJoCo's primitive
    capsule–box test misses it; the scene's mesh boxes must not."""
    q = np.asarray(scene.start_q)
    d = mujoco.MjData(scene.model)
    d.qpos[:] = q
    mujoco.mj_kinematics(scene.model, d)
    # Link E's capsule runs from joint E's origin to joint D's origin.
    a = d.xpos[mujoco.mj_name2id(scene.model, mujoco.mjtObj.mjOBJ_BODY, "link_E")]
    b = d.xpos[mujoco.mj_name2id(scene.model, mujoco.mjtObj.mjOBJ_BODY, "link_D")]
    axis = (b - a) / np.linalg.norm(b - a)
    assert np.linalg.norm(b - a) > 0.1  # both capsule ends well outside a 4 mm plate
    x = np.cross(axis, [0.0, 0.0, 1.0])
    x /= np.linalg.norm(x)
    T = np.eye(4)
    T[:3, :3] = np.stack([x, np.cross(axis, x), axis], axis=1)  # plate normal = capsule axis
    T[:3, 3] = (a + b) / 2
    plate = _with_box(raw, "plate", T, (0.2, 0.2, 0.004))
    ch = CollisionChecker(plate)
    assert not ch.is_valid(q, C0, margin=0.0)
    assert ch.clearance(q, C0) < 0.0
    names = {n for c in ch.contacts(q, C0, margin=0.0) for n in c[:2]}
    assert {"plate", "geom_E"} <= names
    # The same plate far away: valid again (the contact came from the plate).
    T[:3, 3] += 0.5 * np.array([0, 0, -1.0]) + 0.6 * x
    assert CollisionChecker(_with_box(raw, "plate", T, (0.2, 0.2, 0.004))).is_valid(q, C0)


def test_clearance_matches_geom_distance(scene):
    """Clearance from the margin-model contacts equals the smallest mj_geomDistance between
    the clearance geoms and the scene (an independent MuJoCo query)."""
    ch = CollisionChecker(scene, clearance_max=0.3)
    m = scene.model
    d = mujoco.MjData(m)
    scene_geoms = [g for gs in scene.obstacle_geoms.values() for g in gs]
    rng = np.random.default_rng(1)
    for q in rng.uniform(ch.lower, ch.upper, size=(40, 6)):
        d.qpos[:] = q
        mujoco.mj_kinematics(m, d)
        ref = min(mujoco.mj_geomDistance(m, d, g1, g2, 0.3, None) for g1 in scene.clearance_geoms for g2 in scene_geoms)
        got = ch.clearance(q, C0)
        if ref >= 0:
            assert got == pytest.approx(min(ref, 0.3), abs=DIST_ATOL)
        else:  # penetration depths of two convex solvers (EPA vs distance query) differ slightly
            assert got < 0 and got == pytest.approx(ref, abs=PEN_ATOL)


def test_contexts_switch_geoms(scene):
    ch = CollisionChecker(scene)
    q = np.asarray(scene.start_q, dtype=float)
    with pytest.raises(ValueError, match="unknown held"):
        ch.is_valid(q, Context(held=42))
    with pytest.raises(ValueError, match="cannot ignore"):
        ch.is_valid(q, Context(ignore=("nope",)))
    ch.is_valid(q, Context(held=1, ignore=("start_left",)))  # switches the geoms on entry
    held = scene.held_geoms[1]
    assert ch._m.geom_contype[held] != 0 and ch._m.geom_contype[scene.obstacle_geoms[1][0]] == 0
    ch.is_valid(q, Context())
    assert ch._m.geom_contype[held] == 0


def test_straight_path_through_obstacle_rejected(raw, scene):
    """A thin wall across the tool's sweep under joint G: both ends valid, the straight joint
    path between them is not, and the planner finds a way around."""
    from uvms_jax.plan import plan_motion, seed_ompl

    seed_ompl(7)
    q = np.asarray(scene.start_q)
    d = mujoco.MjData(scene.model)
    d.qpos[:] = q
    mujoco.mj_kinematics(scene.model, d)
    p = d.site_xpos[0].copy()
    radial = np.array([p[0], p[1], 0.0]) / np.hypot(p[0], p[1])
    T = np.eye(4)
    T[:3, :3] = np.stack([radial, [0, 0, 1.0], np.cross(radial, [0, 0, 1.0])], axis=1)  # wall normal = sweep
    T[:3, 3] = p
    wall = _with_box(raw, "wall", T, (0.12, 0.12, 0.005))
    ch = CollisionChecker(wall)
    qa, qb = q.copy(), q.copy()
    qa[0] -= 0.4
    qb[0] += 0.4
    assert ch.is_valid(qa, C0) and ch.is_valid(qb, C0)
    assert not ch.path_is_valid(np.stack([qa, qb]), C0, 0.01)
    dense = densify(np.stack([qa, qb]), 0.01)
    assert not ch.is_valid_batch(dense, C0).all() and ch.is_valid_batch(dense, C0)[[0, -1]].all()
    res = plan_motion(ch, qa, qb, C0, "RRTConnect", budget_s=5.0)
    assert res.success and len(res.path) > 2
    np.testing.assert_allclose(res.path[[0, -1]], np.stack([qa, qb]))
    assert ch.path_is_valid(res.path, C0, 0.01, margin=0.0)
