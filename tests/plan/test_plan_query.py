"""The query path (uvms_jax.plan.plan_query) on MoveIt worlds: the compiled kernels against
MuJoCo (body poses, primitive distances), motions against their samples one by one, the spheres
never calling a state free that MuJoCo finds in contact, the MoveIt import, the hard budget, and
errors that name the joint.

The worlds are MotionBenchMaker problems (Chamzas et al., RA-L 2022) for the Franka Panda with
its own hand and fingers: ``tests/plan/data/mbm/<family>_{scene,request}.yaml``."""

from __future__ import annotations

import importlib.metadata
import re
from pathlib import Path

import mujoco
import numpy as np
import pytest

from uvms_jax import frames
from uvms_jax import plan as P
from uvms_jax.plan import _vector_kernels as K
from uvms_jax.plan._collision import densify
from uvms_jax.robot import load_robot, robot_spec

DATA = Path(__file__).parent / "data" / "mbm"
FAMILIES = ("box", "bookshelf_thin", "cage", "table_pick")
ROBOTS = importlib.metadata.distribution("example-robot-data").locate_file(
    "cmeel.prefix/share/example-robot-data/robots")
OPENING = 0.04  # [m] the Panda URDF's largest finger opening
POSE_ATOL = 1e-9  # [m] float64 chain products against MuJoCo's
# [m] a surface point against its shape's box: a rotation and a translation of points ~1 m out
# in float64 round off by ~1e-15 m; far below the 1e-9 m the kernels add to every box
BOX_ROUNDOFF = 1e-12
DIST_ATOL = 1e-6  # [m] MuJoCo's distances of convex primitives (its GJK/MPR stops at ~1e-10 relative)


@pytest.fixture(scope="module")
def panda():
    return load_robot(ROBOTS / "panda_description/urdf/panda.urdf", tip="panda_hand_tcp", link_radius=0.05,
                      gripper="panda_finger_joint1")


@pytest.fixture(scope="module")
def problems(panda):
    return {f: (P.load_moveit_scene(DATA / f"{f}_scene.yaml"),
                P.load_moveit_request(DATA / f"{f}_request.yaml", panda)) for f in FAMILIES}


def test_body_poses_match_mujoco(panda):
    model = robot_spec(panda).compile()
    data = mujoco.MjData(model)
    side = P.VectorChecker(panda, P.World(), OPENING).side
    R, t = np.empty((panda.n_joints, 3, 3)), np.empty((panda.n_joints, 3))
    for q in np.random.default_rng(0).uniform(panda.lower, panda.upper, (20, panda.n_joints)):
        data.qpos[[model.joint(j).qposadr[0] for j in panda.joint_names]] = q
        mujoco.mj_kinematics(model, data)
        K.pose_bodies(q, side.kin, R, t)
        for i, link in enumerate(panda.link_names):
            np.testing.assert_allclose(t[i], data.body(link).xpos, atol=POSE_ATOL)
            np.testing.assert_allclose(R[i], data.body(link).xmat.reshape(3, 3), atol=POSE_ATOL)


@pytest.mark.parametrize("shape,dims", [("box", (0.3, 0.1, 0.05)), ("sphere", (0.1,)), ("capsule", (0.05, 0.3)),
                                        ("cylinder", (0.08, 0.2))])
def test_primitive_distances_match_mujoco(shape, dims):
    rng = np.random.default_rng(1)
    quat = frames.matrix_quat(frames.rpy_matrix(rng.uniform(-np.pi, np.pi, 3)))
    obstacle = P.Obstacle("o", shape, (0.1, -0.2, 0.3), dims=dims, quat=tuple(quat))
    rows, planes = P._worlds.obstacle_rows([obstacle])
    spec = mujoco.MjSpec()
    P._worlds.add_obstacles(spec, [obstacle])
    probe = spec.worldbody.add_body(name="probe", mocap=True)
    probe.add_geom(type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[1e-4, 0, 0])
    model = spec.compile()
    data = mujoco.MjData(model)
    for p in obstacle.T_world[:3, 3] + rng.uniform(-0.4, 0.4, (200, 3)):
        data.mocap_pos[0] = p
        mujoco.mj_kinematics(model, data)
        mine = K.sphere_obstacle_distance(*p, rows[0], planes)
        theirs = mujoco.mj_geomDistance(model, data, 0, 1, 1.0, None) + 1e-4
        if shape == "box":  # a convex mesh in MuJoCo: exact outside, inside a penetration depth
            if mine > 0:
                assert mine == pytest.approx(theirs, abs=DIST_ATOL)
            else:
                assert theirs <= 1e-4
        elif theirs < 1.0 and mine < 1.0 - 1e-4:
            assert mine == pytest.approx(theirs, abs=DIST_ATOL)


@pytest.mark.parametrize("shape,dims", [("box", (0.3, 0.1, 0.05)), ("capsule", (0.05, 0.3)), ("cylinder", (0.08, 0.2)),
                                        ("sphere", (0.1,))])
def test_obstacle_boxes_are_the_shapes_extents(shape, dims):
    """The axis-aligned box around a rotated primitive: the extents of points on its surface
    (a box's corners, a cylinder's rims, a capsule's or sphere's ball at the ends), all inside
    and the box no larger by more than the sampling's step."""
    rng = np.random.default_rng(5)
    for _ in range(10):
        R = frames.rpy_matrix(rng.uniform(-np.pi, np.pi, 3))
        obstacle = P.Obstacle("o", shape, (0.1, -0.2, 0.3), dims=dims, quat=tuple(frames.matrix_quat(R)))
        box = P._worlds._obstacle_boxes(P._worlds.obstacle_rows([obstacle])[0])[0]
        u = np.linspace(0, 2 * np.pi, 3601)[:, None]
        if shape == "box":
            local = (np.array([[i, j, k] for i in (-1, 1) for j in (-1, 1) for k in (-1, 1)]) * dims) / 2
        elif shape == "cylinder":
            rim = dims[0] * np.hstack([np.cos(u), np.sin(u), 0 * u])
            local = np.vstack([rim + [0, 0, h] for h in (-dims[1] / 2, dims[1] / 2)])
        else:  # a ball at each end (the sphere's one, at the centre)
            d = rng.normal(size=(20000, 3))
            ball = dims[0] * d / np.linalg.norm(d, axis=1, keepdims=True)
            local = np.vstack([ball + [0, 0, h] for h in ((-dims[1] / 2, dims[1] / 2) if shape == "capsule" else (0,))])
        points = local @ R.T + obstacle.T_world[:3, 3]
        extent = np.max(np.abs(points - box[:3]), axis=0)
        assert np.all(extent <= box[3:] + BOX_ROUNDOFF)
        assert np.all(box[3:] - extent < 2e-3 * max(dims)), (shape, box[3:] - extent)


def test_near_lists_change_no_verdict(panda, problems):
    """Each group tests only the obstacles within its reach, behind their grown boxes: 4096
    random states give the verdicts of the model that tests every group against every
    obstacle (the ones the spheres call FREE are free for MuJoCo: see the test below)."""
    Q = np.random.default_rng(6).uniform(panda.lower, panda.upper, (4096, panda.n_joints))
    cut = {}
    for family, (world, _) in problems.items():
        model = P.VectorChecker(panda, world, OPENING).model
        groups, rows = model[1], model[3]
        moving = np.flatnonzero(groups[:, 2] >= 0)
        start = np.zeros(len(groups) + 1, np.int64)
        start[1:] = np.cumsum(np.where(groups[:, 2] >= 0, len(rows), 0))
        unbounded = [0, 0, 0, np.inf, np.inf, np.inf]
        every = np.array([[m, *unbounded] for _ in moving for m in range(len(rows))]).reshape(-1, 7)
        got = K.states_status(Q, *model[:9], *model[11:])
        np.testing.assert_array_equal(got, K.states_status(Q, *model[:9], model[11], (start, every)), family)
        assert {K.FREE, K.HIT} <= set(got.tolist()), family
        cut[family] = 1 - len(model[12][1]) / len(every)
    assert cut["bookshelf_thin"] > 0.2, cut  # the links near the base reach none of the shelves


def test_motion_is_free_exactly_when_every_sample_is(panda, problems):
    world, _ = problems["bookshelf_thin"]
    checker = P.VectorChecker(panda, world, OPENING)
    rng = np.random.default_rng(2)
    free = rng.uniform(panda.lower, panda.upper, (2000, panda.n_joints))
    free = free[checker.states_free(free)]
    verdicts = set()
    for q0, q1 in zip(free[:-1:2], free[1::2]):
        for resolution in (0.01, 0.05):
            samples = densify(np.stack([q0, q1]), resolution)[1:]
            expected = bool(checker.states_free(samples).all())
            assert checker.motion_free(q0, q1, resolution) == expected
            verdicts.add(expected)
    assert verdicts == {True, False}


def test_spheres_never_call_free_a_state_in_contact(panda, problems):
    """The oracle is MuJoCo on the description's own meshes and the fingers at the opening."""
    rng = np.random.default_rng(3)
    for family, (world, _) in problems.items():
        checker = P.VectorChecker(panda, world, OPENING)
        exact = P.ExactChecker(checker.side, world)
        Q = rng.uniform(panda.lower, panda.upper, (1500, panda.n_joints))
        status = checker.states_status(Q)
        in_contact = {i for i, *_ in exact.contacts(Q)}
        # FREE by the covering spheres: never in contact; HIT by the inscribed ones: always.
        assert not in_contact & set(np.flatnonzero(status == K.FREE)), family
        assert set(np.flatnonzero(status == K.HIT)) <= in_contact, family
        assert {K.FREE, K.HIT, K.MAYBE} <= set(status.tolist()), family
        # With MuJoCo settling the MAYBE states the verdicts are MuJoCo's.
        np.testing.assert_array_equal(checker.states_free(Q), [i not in in_contact for i in range(len(Q))])


def test_moveit_scene_and_request(panda):
    world = P.load_moveit_scene(DATA / "box_scene.yaml")
    names = {o.name for o in world.obstacles}
    assert {"base", "side_back", "side_cap", "side_front", "side_left", "side_right"} <= names
    cap = next(o for o in world.obstacles if o.name == "side_cap")
    # The file's quaternion is x, y, z, w; an Obstacle's is w, x, y, z.
    import yaml
    raw = next(c for c in yaml.safe_load((DATA / "box_scene.yaml").read_text())["world"]["collision_objects"]
               if c["id"] == "side_cap")
    x, y, z, w = raw["primitive_poses"][0]["orientation"]
    np.testing.assert_allclose(np.abs(np.dot(cap.quat, [w, x, y, z])), 1.0, atol=1e-12)
    assert cap.dims == tuple(raw["primitives"][0]["dimensions"])
    assert world.allows("panda_hand", "panda_leftfinger") and not world.allows("panda_link0", "panda_hand")
    req = P.load_moveit_request(DATA / "box_request.yaml", panda)
    assert req.start.shape == req.goal.shape == (7,) and req.opening == pytest.approx(0.065)


def test_srdf_disabled_pairs_join_the_allowed_matrix(panda, tmp_path):
    srdf = ROBOTS / "panda_description/srdf/panda.srdf"
    allowed = P.load_srdf(srdf)
    # The oracle: the file's elements read by a regular expression, not by an XML parser.
    expected = {frozenset(m) for m in re.findall(r'<disable_collisions link1="([^"]+)" link2="([^"]+)"', srdf.read_text())}
    assert allowed == expected and frozenset(("panda_hand", "panda_link5")) in allowed
    world = P.World(allowed=allowed)
    side = P.VectorChecker(panda, P.World(), OPENING).side
    groups = {links: k for k, links in enumerate(side.group_links)}
    link5 = groups[frozenset({"panda_link5"})]
    hand = next(k for links, k in groups.items() if "panda_hand" in links)
    assert [link5, hand] in side.pairs(P.World()).tolist() and [link5, hand] not in side.pairs(world).tolist()
    Q = np.random.default_rng(1).uniform(panda.lower, panda.upper, (400, panda.n_joints))
    without, with_srdf = (P.VectorChecker(panda, w, OPENING).exact for w in (P.World(), world))
    hit_without = np.array([bool(without.contacts(q[None])) for q in Q])
    hit_with = np.array([bool(with_srdf.contacts(q[None])) for q in Q])
    assert not np.any(hit_with & ~hit_without) and np.sum(hit_with) < np.sum(hit_without)
    entity = tmp_path / "bad.srdf"
    entity.write_text('<!DOCTYPE r [<!ENTITY x SYSTEM "file:///etc/passwd">]><robot>&x;</robot>')
    assert P.load_srdf(entity) == frozenset()  # the entity is not resolved
    for text, match in (("<robot><disable_collisions link1='a'/></robot>", "link1 and link2"),
                        ("<urdf/>", "root element is <robot>"), ("<robot>", "not a readable SRDF")):
        entity.write_text(text)
        with pytest.raises(ValueError, match=match):
            P.load_srdf(entity)


def test_moveit_files_with_errors_are_refused_in_one_line(panda, tmp_path):
    bad = tmp_path / "scene.yaml"
    bad.write_text("world:\n  collision_objects:\n    - id: c\n      primitives: [{type: cone, dimensions: [1, 2]}]\n"
                   "      primitive_poses: [{position: [0, 0, 0], orientation: [0, 0, 0, 1]}]\n")
    with pytest.raises(ValueError, match="cone"):
        P.load_moveit_scene(bad)
    req = tmp_path / "request.yaml"
    req.write_text("start_state: {joint_state: {name: [panda_joint1], position: [0]}}\n")
    with pytest.raises(ValueError, match="no value for joints"):
        P.load_moveit_request(req, panda)


def test_limits_are_compared_in_float64_and_errors_name_the_joint(panda, problems):
    world, req = problems["box"]
    goal = req.goal.copy()
    goal[3] = float(panda.upper[3]) + 2e-8  # float32 rounding of the limit: accepted
    P.plan_query(panda, world, req.start, goal, opening=OPENING, budget_s=0.5, exact=False)
    goal[3] = float(panda.upper[3]) + 0.05
    with pytest.raises(ValueError, match=r"goal: joint 'panda_joint4' at .* outside its limits \[.*\]"):
        P.plan_query(panda, world, req.start, goal, opening=OPENING)
    with pytest.raises(ValueError, match="panda_finger_joint1"):
        P.plan_query(panda, world, req.start, req.goal, opening=0.065)


def test_budget_is_hard(panda, problems):
    """A budget spent before the first iteration ends the query there, planning and
    simplification both: no path, reason ``timeout``. (Times are the benchmark's to measure.)"""
    world, req = problems["bookshelf_thin"]
    checker = P.VectorChecker(panda, world, OPENING)
    assert not checker.motion_free(req.start, req.goal, 0.05)  # the planner has to search
    result = P.plan_query(panda, world, req.start, req.goal, opening=OPENING, budget_s=1e-6, checker=checker)
    assert (result.success, result.reason, result.iterations) == (False, "timeout", 0)


def test_a_planned_path_passes_mujoco_on_every_family(panda, problems):
    for family, (world, req) in problems.items():
        result = P.plan_query(panda, world, req.start, req.goal, opening=OPENING, budget_s=5.0)
        assert result.success, (family, result.reason)
        np.testing.assert_array_equal(result.path[[0, -1]], np.stack([req.start, req.goal]))
        exact = P.ExactChecker(P.VectorChecker(panda, world, OPENING).side, world)
        assert not exact.contacts(densify(result.path, 0.01)), family


def test_another_arm_with_another_hand_plans_in_a_moveit_scene(tmp_path):
    """The Z1 (example-robot-data) with its card's jaw boxes, in a MoveIt PlanningScene written as
    MoveIt writes it: a query whose straight motion is blocked is solved, and its path passes
    MuJoCo with the jaws."""
    import yaml

    arms = yaml.safe_load((Path(__file__).parents[2] / "examples" / "arms.yaml").read_text())
    z1 = load_robot(ROBOTS / arms["arms"]["z1"]["description"], tip=arms["arms"]["z1"]["tip"], link_radius=0.04,
                    gripper=arms["jaws"])
    assert not z1.fingers and z1.gripper is not None  # the card's jaws stand for its hand
    boxes = {"table": ([0.45, 0.0, -0.05], [0.6, 0.8, 0.1]), "wall": ([0.35, 0.0, 0.25], [0.04, 0.8, 0.2])}
    scene = {"world": {"collision_objects": [
        {"id": name, "primitives": [{"type": "box", "dimensions": size}],
         "primitive_poses": [{"position": pos, "orientation": [0, 0, 0.0998, 0.995]}]}
        for name, (pos, size) in boxes.items()]}}
    (tmp_path / "scene.yaml").write_text(yaml.safe_dump(scene))
    world = P.load_moveit_scene(tmp_path / "scene.yaml")
    checker = P.VectorChecker(z1, world)
    rng = np.random.default_rng(5)
    Q = rng.uniform(z1.lower, z1.upper, (4000, z1.n_joints))
    free = Q[checker.states_free(Q)]
    start, goal = next((a, b) for a, b in zip(free[::2], free[1::2]) if not checker.motion_free(a, b, 0.05))
    result = P.plan_query(z1, world, start, goal, budget_s=5.0, checker=checker)
    assert result.success, result.reason
    assert not checker.exact.contacts(densify(result.path, 0.01))
    assert any(g.startswith("geom_jaw") for g in (checker.exact.model.geom(k).name
                                                  for k in range(checker.exact.model.ngeom)))


def test_numba_cache_goes_to_the_users_cache(tmp_path):
    """Compiled kernels are cached under the user's cache folder, not beside the installed source."""
    import os
    import subprocess
    import sys

    env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"} | {"XDG_CACHE_HOME": str(tmp_path)}
    for first in ("uvms_jax.plan, numba", "numba, uvms_jax.plan"):  # whichever the user imports first
        out = subprocess.run([sys.executable, "-c", f"import {first}; print(numba.config.CACHE_DIR)"],
                             env=env, capture_output=True, text=True, check=True).stdout.strip()
        assert out == str(tmp_path / "uvms_jax" / "numba"), first
