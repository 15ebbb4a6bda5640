"""The batched JAX planner: problems of different worlds in one call; what it calls solved is free
for the Numba checker at every sample of the CPU path's final check, starts at the start and
ends at the goal; a free straight motion is found as it is; a blocked one is solved by a
detour; a colliding goal is reported, not planned. And the MBM benchmark script on a few
problems on the CPU."""

import importlib.metadata
import importlib.util
import json
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from uvms_jax import robot as R
from uvms_jax.plan import Obstacle, densify
from uvms_jax.plan._batch_jax import BatchSettings, plan_batch
from uvms_jax.plan._vector import robot_spheres_model
from uvms_jax.plan._vector_kernels import FREE, states_status
from uvms_jax.plan._vector_jax import sphere_arm, sphere_worlds
from uvms_jax.plan._worlds import World

ROOT = Path(__file__).parents[2]
DATA = Path(__file__).parent / "data" / "mbm"  # MotionBenchMaker problems (see its README)
ROBOTS = Path(str(importlib.metadata.distribution("example-robot-data").locate_file(
    "cmeel.prefix/share/example-robot-data/robots")))
OPENING = 0.04  # [m]
RESOLUTION = 0.01  # [rad] the check resolution
# 8 random vertices a round: the detour is found in the first round as with 16, and the
# round's edge checks (quadratic in the vertices) take a third of the time.
SETTINGS = BatchSettings(nodes=8, rounds=3, lazy=3, waypoints=5, samples=1024, chunk=1024)
ENDS_TOL = 1e-6  # [rad] the path's first and last rows are the start and goal, in float32


@pytest.fixture(scope="module")
def panda():
    return R.load_robot(ROBOTS / "panda_description/urdf/panda.urdf", tip="panda_hand_tcp", link_radius=0.05,
                        gripper="panda_finger_joint1")


def _pillar_world() -> World:
    return World((Obstacle("pillar", "box", (0.45, 0.0, 0.4), dims=(0.12, 0.12, 0.8)),), name="pillar")


class _SpheresOnly:
    """The Numba checker's covering spheres alone: what the batch planner sees (a state the
    spheres cannot tell counts as a collision). A motion is free when every sample of the CPU
    path's final check (densify) is: the one kernel of the test's verdicts."""

    def __init__(self, side, world: World):
        self.model = side.model(world)

    def states_free(self, Q) -> np.ndarray:
        return states_status(np.ascontiguousarray(Q, dtype=np.float64), *self.model[:9], *self.model[11:]) == FREE

    def motions_free(self, starts, ends, resolution: float) -> np.ndarray:
        """``(m,)`` bool: each motion ``starts[i] → ends[i]`` free, all in one kernel call."""
        dense = [densify(np.stack([a, b]), resolution) for a, b in zip(starts, ends)]
        free = self.states_free(np.concatenate(dense))
        return np.array([f.all() for f in np.split(free, np.cumsum([len(d) for d in dense])[:-1])])

    def motion_free(self, q0, q1, resolution: float) -> bool:
        return bool(self.motions_free([q0], [q1], resolution)[0])


def _problems(panda, checker: _SpheresOnly, rng):
    """Three queries found with the Numba checker in the pillar world: a short free straight
    motion, a blocked straight motion with many free one-waypoint detours, a colliding goal."""
    lo, hi = panda.lower, panda.upper
    Q = rng.uniform(lo, hi, (4000, panda.n_joints))
    free = checker.states_free(Q)
    q = Q[free][0]
    easy = (q, np.clip(q + 0.05, lo, hi))
    assert checker.motion_free(*easy, RESOLUTION)
    W = Q[free][:200]
    for a, b in zip(Q[free][1::2], Q[free][2::2]):
        if checker.motion_free(a, b, RESOLUTION):
            continue
        detours = np.sum(checker.motions_free([a] * len(W), W, RESOLUTION)
                         & checker.motions_free(W, [b] * len(W), RESOLUTION))
        if detours >= 40:  # a fifth of the free states: the random vertices meet one
            hard = (a, b)
            break
    else:
        pytest.fail("no blocked query with a detour among the samples")
    blocked = (q, Q[~free][0])
    return [easy, hard, blocked]


def test_batch_plans_are_free_and_honest(panda):
    side = robot_spheres_model(panda, OPENING)
    world = _pillar_world()
    checker = _SpheresOnly(side, world)
    queries = _problems(panda, checker, np.random.default_rng(0))
    worlds = sphere_worlds(side, [world] * 3)
    starts = jnp.asarray(np.stack([a for a, _ in queries]), jnp.float32)
    goals = jnp.asarray(np.stack([b for _, b in queries]), jnp.float32)
    out = jax.tree.map(np.asarray, plan_batch(sphere_arm(side), worlds, starts, goals, jax.random.key(0), SETTINGS))
    assert out.path.shape == (3, SETTINGS.waypoints, panda.n_joints)
    assert out.solved.tolist() == [True, True, False] and out.endpoints_free.tolist() == [True, True, False]
    assert out.count[0] == 2 and out.count[1] >= 3 and out.count[2] == 0  # the straight motion; a detour
    for b in range(2):
        path = out.path[b, :out.count[b]].astype(np.float64)
        np.testing.assert_allclose(path[[0, -1]], np.stack(queries[b]), atol=ENDS_TOL)
        tail = out.path[b, out.count[b]:]
        np.testing.assert_allclose(tail, np.broadcast_to(path[-1], tail.shape))
        assert checker.states_free(densify(path, RESOLUTION)).all()
        np.testing.assert_allclose(out.length[b], np.sum(np.linalg.norm(np.diff(path, axis=0), axis=1)), rtol=1e-5)
    assert np.isinf(out.length[2])
    assert 1 <= int(out.rounds) <= SETTINGS.rounds


@pytest.mark.parametrize("bad", [dict(nodes=0), dict(waypoints=1), dict(resolution=0.0), dict(uniform=1.5)])
def test_settings_are_checked(bad):
    with pytest.raises(ValueError, match="BatchSettings"):
        BatchSettings(**bad)


@pytest.mark.slow
def test_mbm_script_on_cpu(tmp_path):
    """benchmarks/mbm_gpu.py on two problems of two families on the CPU (the tests' MBM files laid
    out as the set is): the record holds the timings and counts, and every path the batch
    solved passed the re-check."""
    problems = tmp_path / "problems"
    for family in ("bookshelf_thin", "box"):
        (problems / f"{family}_panda").mkdir(parents=True)
        for kind in ("scene", "request"):
            (problems / f"{family}_panda" / f"{kind}0001.yaml").write_bytes((DATA / f"{family}_{kind}.yaml").read_bytes())
    spec = importlib.util.spec_from_file_location("mbm_gpu", ROOT / "benchmarks" / "mbm_gpu.py")
    script = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(script)
    out = tmp_path / "mbm.json"
    record = script.main(["--problems", str(problems), "--families", "bookshelf_thin_panda", "box_panda",
                          "--count", "1", "--nodes", "8", "--rounds", "2", "--lazy", "2", "--samples", "1024",
                          "--chunk", "1024", "--repeats", "1", "--out", str(out)])
    assert json.loads(out.read_text()) == json.loads(json.dumps(record))
    assert record["n_problems"] == 2 and record["compile_s"] > 0 and len(record["run_s"]) == 1
    t = record["totals"]
    assert t["problems"] == 2 and t["solved"] <= t["endpoints_free"] and t["rechecked_free"] == t["solved"]
    assert set(record["families"]) == {"bookshelf_thin_panda", "box_panda"}
