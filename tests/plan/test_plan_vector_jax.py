"""The JAX sphere checker against the Numba kernel (an independent implementation of the same
verdicts): thousands of states of MotionBenchMaker problems and of a world of every primitive,
through jit and vmap, in float64 and float32; padding never changes a verdict; the motion
samples are the CPU path's (densify)."""

import importlib.metadata
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from uvms_jax import robot as R
from uvms_jax.plan import Obstacle, densify, load_moveit_scene
from uvms_jax.plan._vector import robot_spheres_model
from uvms_jax.plan._vector_jax import (motion_samples, numba_model, sphere_arm, sphere_worlds,
                                       states_free)
from uvms_jax.plan._vector_kernels import FREE, sphere_obstacle_distance, states_status
from uvms_jax.plan._worlds import World, near_obstacles, obstacle_rows


def numba_states_free(Q, model):
    """The Numba kernel's covering-sphere verdicts (what the JAX checker computes)."""
    return states_status(np.ascontiguousarray(Q), *model[:9], *model[11:]) == FREE


ROBOTS = Path(str(importlib.metadata.distribution("example-robot-data").locate_file(
    "cmeel.prefix/share/example-robot-data/robots")))
DATA = Path(__file__).parent / "data" / "mbm"  # MotionBenchMaker problems (see its README)
FAMILIES = ("bookshelf_thin", "cage", "table_pick")
OPENING = 0.04  # [m] the gripper's largest opening
# Verdicts may differ only for states whose nearest sphere is within round-off of touching.
# The bracket: a state free by Numba with the margin raised by TOL is free here, and one
# colliding by Numba with the margin lowered by TOL collides here. float64: a state's
# clearance is a chain of ~100 operations on metre-scale numbers (ulp 2e-16 m), far below
# 1e-9 m. float32: ulp 6e-8 on ~1 m coordinates through 7 chained body poses and the
# distance formulas, a few 1e-6 m at worst; 2e-5 m holds with margin.
TOL = {np.float64: 1e-9, np.float32: 2e-5}
AMBIGUOUS = 0.01  # most of the states the bracket leaves open (it must not make the test vacuous)


@pytest.fixture(scope="module")
def panda():
    return R.load_robot(ROBOTS / "panda_description/urdf/panda.urdf", tip="panda_hand_tcp", link_radius=0.05,
                        gripper="panda_finger_joint1")


@pytest.fixture(scope="module")
def side(panda):
    return robot_spheres_model(panda, OPENING)


def _mbm_worlds():
    return [load_moveit_scene(DATA / f"{f}_scene.yaml") for f in FAMILIES]


def _primitives_world(tmp_path) -> World:
    """A box, sphere, capsule, cylinder and convex mesh (an irregular octahedron: a polytope of
    8 faces) in the arm's reach, turned, and one link pair allowed to touch."""
    obj = tmp_path / "octahedron.obj"
    v = [(0.12, 0, 0), (-0.09, 0, 0), (0, 0.1, 0), (0, -0.07, 0), (0, 0, 0.11), (0, 0, -0.08)]
    f = [(1, 3, 5), (3, 2, 5), (2, 4, 5), (4, 1, 5), (3, 1, 6), (2, 3, 6), (4, 2, 6), (1, 4, 6)]
    obj.write_text("".join(f"v {a} {b} {c}\n" for a, b, c in v) + "".join(f"f {a} {b} {c}\n" for a, b, c in f))
    obstacles = (Obstacle("box", "box", (0.45, 0.2, 0.4), (0.3, 0.2, 0.1), dims=(0.2, 0.1, 0.3)),
                 Obstacle("ball", "sphere", (0.3, -0.3, 0.6), dims=(0.12,)),
                 Obstacle("rod", "capsule", (-0.3, 0.3, 0.5), (1.0, 0.2, 0.0), dims=(0.05, 0.4)),
                 Obstacle("post", "cylinder", (0.5, -0.1, 0.2), (0.0, 0.7, 0.3), dims=(0.08, 0.3)),
                 Obstacle("gem", "mesh", (0.0, -0.45, 0.45), (0.4, 0.1, 0.9), file=str(obj)))
    return World(obstacles, frozenset({frozenset(("panda_link1", "panda_link4"))}), name="primitives")


def test_distances_match_the_numba_kernel_for_every_kind(tmp_path):
    """Point by point, every primitive: the same signed distance to float64 round-off."""
    from uvms_jax.plan._vector_jax import obstacle_distance

    rows, planes = obstacle_rows(_primitives_world(tmp_path).obstacles)
    P = np.random.default_rng(0).uniform(-0.8, 0.8, (2000, 3)) + [0.1, 0.0, 0.4]
    want = np.array([[sphere_obstacle_distance(*p, o, planes) for o in rows] for p in P])
    got = jax.jit(obstacle_distance)(*(jnp.asarray(P[:, i, None]) for i in range(3)), jnp.asarray(rows.T[:, None, :]),
                                     jnp.asarray(planes))
    assert np.all(want < 0, axis=0).sum() == 0 and np.any(want < 0, axis=0).all()  # inside every kind somewhere
    np.testing.assert_allclose(np.asarray(got), want, rtol=0, atol=TOL[np.float64])


def _states(panda, rng, k):
    """``(k, n)``: half uniform in the limits, half along random straight motions (which cross
    the boundaries between free and colliding)."""
    uniform = rng.uniform(panda.lower, panda.upper, (k // 2, panda.n_joints))
    a, b = rng.uniform(panda.lower, panda.upper, (2, k // 40, panda.n_joints))
    s = np.linspace(0, 1, 20)[None, :, None]
    return np.concatenate([uniform, (a[:, None] + s * (b - a)[:, None]).reshape(-1, panda.n_joints)])


def _bracket(side, worlds, index, Q, got, tol):
    model = numba_model(side, worlds, index)
    # The near lists are built for a margin: rebuilt for each.
    lo, hi = (model[:6] + (model[6] + m,) + model[7:12] + (near_obstacles(*model[:2], *model[3:5], model[6] + m),)
              for m in (-tol, tol))
    free_lo, free_hi = numba_states_free(Q, lo), numba_states_free(Q, hi)
    assert not np.any(free_hi & ~got), "free by Numba with a larger margin, colliding here"
    assert not np.any(got & ~free_lo), "colliding by Numba with a smaller margin, free here"
    assert np.mean(free_lo != free_hi) <= AMBIGUOUS
    assert 0.05 < np.mean(got) < 0.95  # both verdicts occur
    return np.mean(got != numba_states_free(Q, model))


@pytest.mark.slow
@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_mbm_verdicts_match_numba_batched(panda, side, dtype):
    """Three MBM worlds as one padded batch (B, k, n) through jit and vmap: each world's verdicts
    are Numba's on its own rows, up to :data:`TOL`; the padding rows change nothing."""
    worlds = _mbm_worlds()
    arm, batch = sphere_arm(side, dtype), sphere_worlds(side, worlds, margin=0.01, dtype=dtype)
    rng = np.random.default_rng(1)
    Q = np.stack([_states(panda, rng, 3000) for _ in worlds])
    got = np.asarray(jax.jit(jax.vmap(states_free, in_axes=(None, 0, 0)))(arm, batch, jnp.asarray(Q, dtype)))
    for b, w in enumerate(worlds):
        unpadded = numba_states_free(Q[b], side.model(w, 0.01))
        np.testing.assert_array_equal(unpadded, numba_states_free(Q[b], numba_model(side, batch, b)))
        _bracket(side, batch, b, Q[b].astype(np.float64), got[b], TOL[dtype])
    if dtype == np.float64:
        assert all(_bracket(side, batch, b, Q[b], got[b], TOL[dtype]) == 0 for b in range(len(worlds)))


# Each shape compiles the checker afresh (tens of seconds on 2 cores): the fast suite takes the
# batch of several leading axes, the slow suite the flat one.
@pytest.mark.parametrize("shape", [pytest.param((4000,), marks=pytest.mark.slow), (2, 5, 400)])
def test_every_primitive_and_batch_shape(panda, side, tmp_path, shape):
    """The five kinds and an allowed pair, one world padded to more rows and faces than it has;
    states in a flat batch and in one of several axes, one jitted call each."""
    world = _primitives_world(tmp_path)
    batch = sphere_worlds(side, [world], dtype=np.float64, n_obstacles=9, n_planes=12)
    one = type(batch)(*(a[0] for a in batch))
    assert not np.asarray(one.pair_on).all()  # the allowed pair is off
    Q = _states(panda, np.random.default_rng(2), int(np.prod(shape))).reshape(*shape, panda.n_joints)
    got = np.asarray(jax.jit(states_free)(sphere_arm(side, np.float64), one, jnp.asarray(Q)))
    assert got.shape == shape
    flat = Q.reshape(-1, panda.n_joints)
    np.testing.assert_array_equal(numba_states_free(flat, numba_model(side, one)),
                                  numba_states_free(flat, side.model(world)))
    _bracket(side, one, None, flat, got.reshape(-1), TOL[np.float64])


def test_motion_samples_are_the_cpu_paths():
    """A padded path's samples are densify's (the CPU path's final check) without the start,
    then the last waypoint repeated; a path with one sample more than room says it does not
    fit. Both paths through one compiled call (the same shapes and room)."""
    rng = np.random.default_rng(3)
    longer = rng.uniform(-1, 1, (4, 7))
    path = 0.9 * longer  # fewer samples than the longer path
    pad = lambda p: jnp.asarray(np.concatenate([p, np.repeat(p[-1:], 3, axis=0)]))  # noqa: E731
    dense = densify(path, 0.01)[1:]
    room = len(densify(longer, 0.01)) - 2  # one sample short of the longer path's
    assert room > len(dense)
    samples = jax.jit(motion_samples, static_argnums=(2, 3))
    Q, seg, used, fits = samples(pad(path), 4, 0.01, room)
    assert bool(fits) and int(used.sum()) == len(dense)
    np.testing.assert_allclose(np.asarray(Q)[:len(dense)], dense, rtol=0, atol=1e-12)
    np.testing.assert_allclose(np.asarray(Q)[len(dense):], np.repeat(path[-1:], room - len(dense), axis=0))
    starts = np.cumsum([0] + [len(densify(path[k:k + 2], 0.01)) - 1 for k in range(3)])
    assert np.all(np.asarray(seg)[:len(dense)] == np.searchsorted(starts, np.arange(len(dense)), side="right") - 1)
    assert not bool(samples(pad(longer), 4, 0.01, room)[3])
