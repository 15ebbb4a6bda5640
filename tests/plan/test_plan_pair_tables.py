"""The self pairs' distance tables against MuJoCo measured at the state itself: the tabled
distance is within the stated bound of the pair's distance everywhere, and the checker's
verdicts with tables are those without them."""

import importlib.metadata
from pathlib import Path

import mujoco
import numpy as np
import pytest

from uvms_jax import robot as R
from uvms_jax import plan as P
from uvms_jax.plan._vector_kernels import FREE, HIT, settle, states_status, without_tables

ROBOTS = Path(str(importlib.metadata.distribution("example-robot-data").locate_file(
    "cmeel.prefix/share/example-robot-data/robots")))
DATA = Path(__file__).parent / "data" / "mbm"
OPENING = 0.04  # [m] the gripper's largest opening


@pytest.fixture(scope="module")
def checker():
    panda = R.load_robot(ROBOTS / "panda_description/urdf/panda.urdf", tip="panda_hand_tcp", link_radius=0.05,
                         gripper="panda_finger_joint1")
    return P.VectorChecker(panda, P.load_moveit_scene(DATA / "table_pick_scene.yaml"), OPENING)


def _pair_distance(exact, g1: int, g2: int, q) -> float:
    """MuJoCo's least distance [m] between the two groups' geoms at ``q``, from Python."""
    m, d = exact.model, exact.data
    ranges, geoms = exact.arrays(np.zeros(0, bool))[4:6]
    d.qpos[exact.arrays(np.zeros(0, bool))[3]] = q
    mujoco.mj_kinematics(m, d)
    return min(mujoco.mj_geomDistance(m, d, int(a), int(b), 1.0, None)
               for a in geoms[ranges[g1, 0]:ranges[g1, 1]] for b in geoms[ranges[g2, 0]:ranges[g2, 1]])


def test_the_wrist_pairs_are_tabled(checker):
    """The Panda's pairs two joints apart (link 5 against the hand and each finger) have tables."""
    index, meta, _ = checker.model[11]
    tabled = {frozenset().union(checker.side.group_links[a], checker.side.group_links[b])
              for (a, b), k in zip(checker.model[5], index) if k >= 0}
    assert {"panda_link5", "panda_hand"} <= set().union(*tabled)
    assert len(tabled) == 3 and np.all(meta[:, :2] == [5, 6])


def test_tabled_distance_is_within_its_bound(checker):
    """At random states of the two joints (the others random too), MuJoCo's distance of each
    tabled pair lies within the table's bound of the value at the nearest node."""
    robot, exact = checker.robot, checker.exact
    index, meta, values = checker.model[11]
    rng = np.random.default_rng(3)
    worst = 0.0
    for (g1, g2), k in zip(checker.model[5], index):
        if k < 0:
            continue
        ja, jb, first_a, first_b, spacing, bound = meta[k, :6]
        for q in rng.uniform(robot.lower, robot.upper, (150, robot.n_joints)):
            i, j = (int(np.floor((q[int(c)] - f) / spacing + 0.5)) for c, f in ((ja, first_a), (jb, first_b)))
            truth = min(_pair_distance(exact, int(g1), int(g2), q), 0.1)  # tables stop at 0.1 m
            gap = abs(truth - float(values[k, i, j]))
            assert gap <= bound, (q, truth, values[k, i, j])
            worst = max(worst, gap)
    assert worst > 0.2 * meta[0, 5]  # the bound is not loose by orders of magnitude


def test_tables_change_no_verdict(checker):
    """4096 random states: the verdicts (spheres, tables, MuJoCo where undecided) equal those of
    the spheres and MuJoCo alone, and the tables leave fewer states undecided."""
    model = checker.model
    plain = model[:11] + (without_tables(len(model[5])),) + model[12:]
    Q = np.random.default_rng(4).uniform(checker.lower, checker.upper, (4096, checker.robot.n_joints))
    with_tables, without = (states_status(Q, *m[:9], *m[11:]) for m in (model, plain))
    assert np.all((with_tables == without) | (with_tables == 2) | (without == 2))
    assert np.mean(with_tables == 2) < 0.5 * np.mean(without == 2)
    np.testing.assert_array_equal(settle(Q, with_tables, model), settle(Q, without, plain))
    assert FREE in with_tables and HIT in with_tables
