"""The MotionBenchMaker benchmark's VAMP peer (benchmarks/mbm.py --vamp): without the package it
stops with one line saying how to get it; with it, the obstacles VAMP receives sit where the
world's are (poses from our frames, compared with the axes and end points VAMP computes from its
Euler angles), and a planned path runs from the start to the goal."""

import importlib.util
import sys
from pathlib import Path

import numpy as np
import pytest

from uvms_jax import frames
from uvms_jax import plan as P
from uvms_jax.plan import Obstacle

ROOT = Path(__file__).parents[2]
DATA = Path(__file__).parent / "data" / "mbm"  # MotionBenchMaker problems (see its README)
FLOAT32_TOL = 1e-5  # [m or 1] VAMP stores its shapes in float32 (positions of order 1 m)
ENDS_TOL = 1e-6  # [rad] the path's ends are the start and goal, in float32

_spec = importlib.util.spec_from_file_location("mbm", ROOT / "benchmarks" / "mbm.py")
mbm = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(mbm)


def test_a_missing_vamp_stops_with_how_to_get_it(monkeypatch):
    monkeypatch.setitem(sys.modules, "vamp", None)  # import vamp raises ImportError
    with pytest.raises(SystemExit, match="vamp-planner.*docs/planning.md"):
        mbm.VampPeer()


def _world() -> P.World:
    tilt = tuple(frames.matrix_quat(frames.rpy_matrix([0.3, -0.5, 1.1])))
    return P.World((Obstacle("box", "box", (0.4, -0.1, 0.3), dims=(0.2, 0.1, 0.6), quat=tilt),
                    Obstacle("can", "cylinder", (0.5, 0.2, 0.1), rpy=(0.2, 0.7, -0.4), dims=(0.03, 0.12)),
                    Obstacle("ball", "sphere", (0.1, 0.6, 0.5), dims=(0.07,))))


def test_obstacles_reach_vamp_where_the_world_has_them():
    vamp = pytest.importorskip("vamp")
    world = _world()
    box, can, ball = world.obstacles
    env = mbm.vamp_environment(vamp, world, "table_pick")
    (cuboid,), (capsule,), (sphere,) = env.cuboids, env.capsules, env.spheres
    T = box.T_world
    axes = np.array([[getattr(cuboid, f"axis_{i}_{c}") for c in "xyz"] for i in (1, 2, 3)])
    np.testing.assert_allclose(axes, T[:3, :3].T, atol=FLOAT32_TOL)
    np.testing.assert_allclose([cuboid.x, cuboid.y, cuboid.z], T[:3, 3], atol=FLOAT32_TOL)
    np.testing.assert_allclose([cuboid.axis_1_r, cuboid.axis_2_r, cuboid.axis_3_r], [0.1, 0.05, 0.3], atol=FLOAT32_TOL)
    T = can.T_world
    ends = {tuple(np.round(T[:3, :3] @ [0, 0, s * 0.06] + T[:3, 3], 4)) for s in (1, -1)}
    got = {tuple(np.round([capsule.x1, capsule.y1, capsule.z1], 4)), tuple(np.round([capsule.x2, capsule.y2,
                                                                                      capsule.z2], 4))}
    assert got == ends and abs(capsule.r - 0.03) < FLOAT32_TOL
    assert np.allclose([sphere.x, sphere.y, sphere.z, sphere.r], [0.1, 0.6, 0.5, 0.07], atol=FLOAT32_TOL)
    # In the box family a cylinder is its bounding box: half extents r, r, h / 2 about its axes.
    env = mbm.vamp_environment(vamp, world, "box")
    assert not env.capsules and len(env.cuboids) == 2
    cuboid = env.cuboids[1] if abs(env.cuboids[0].axis_1_r - 0.1) < FLOAT32_TOL else env.cuboids[0]
    np.testing.assert_allclose([cuboid.axis_1_r, cuboid.axis_2_r, cuboid.axis_3_r], [0.03, 0.03, 0.06],
                               atol=FLOAT32_TOL)
    np.testing.assert_allclose([cuboid.axis_3_x, cuboid.axis_3_y, cuboid.axis_3_z], T[:3, 2], atol=FLOAT32_TOL)


def test_a_vamp_path_runs_from_start_to_goal():
    pytest.importorskip("vamp")
    robot = mbm.panda()
    world = P.load_moveit_scene(DATA / "table_pick_scene.yaml")
    req = P.load_moveit_request(DATA / "table_pick_request.yaml", robot)
    start, goal = np.clip(req.start, robot.lower, robot.upper), np.clip(req.goal, robot.lower, robot.upper)
    peer = mbm.VampPeer()
    env = mbm.vamp_environment(peer.vamp, world, "table_pick")
    solved, spent, own, path = peer.plan(env, start, goal)
    assert solved and spent >= own > 0 and path.shape[1] == 7
    np.testing.assert_allclose(path[[0, -1]], [start, goal], atol=ENDS_TOL)
