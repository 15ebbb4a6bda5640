"""Docking's collision world (uvms_jax.evo._world): the segment distance of capsule pairs
against dense sampling, the boxes and polytopes moved into the base frame against the
distances computed in the world, polytopes of fewer faces than the padding by their own faces
only, and the capsule fallback at least as strict as the link capsules it stands for. The
planner's world is compared with the planner's checkers in tests/plan/test_plan_world.py."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from uvms_jax import evo, frames, kin
from uvms_jax.evo._collide import capsules_hit_boxes, link_points
from uvms_jax.evo._geometry import segment_distance
from uvms_jax.evo._world import obstacles_in_base
from uvms_jax.robot import load_arm

GRID = 400  # parameters per segment of the brute-force distance oracle
SEG_ATOL = 2e-3  # [m] the sampled minimum is within a grid step (segments < 1 m) of the exact one
BASE_ATOL = 1e-5  # [m] float32 round-off of a point moved into the base frame (coordinates < 2 m)

BRAVO7 = load_arm("bravo7")


def test_segment_distance_matches_dense_sampling():
    rng = np.random.default_rng(0)
    s = np.linspace(0.0, 1.0, GRID)
    dist = jax.jit(jax.vmap(segment_distance))
    cases = [rng.uniform(-0.5, 0.5, (4, 3)) for _ in range(40)]
    a = rng.uniform(-0.5, 0.5, 3)
    cases += [np.stack([a, a + [0.3, 0, 0], a + [0, 0.1, 0], a + [0.3, 0.1, 0]]),  # parallel
              np.stack([a, a, a + [0.1, 0.1, 0], a + [0.2, -0.1, 0.1]]),  # a point and a segment
              np.stack([a + [0.1, 0.1, 0], a + [0.2, -0.1, 0.1], a, a]),
              np.stack([a, a, a + 0.1, a + 0.1])]  # two points
    P = np.stack(cases)
    got = np.asarray(dist(*(jnp.asarray(P[:, i], jnp.float32) for i in range(4))))
    for (p1, q1, p2, q2), d in zip(P, got):
        x = p1 + s[:, None, None] * (q1 - p1)
        y = p2 + s[None, :, None] * (q2 - p2)
        ref = np.min(np.linalg.norm(x - y, axis=-1))
        assert d <= ref + 1e-6 and d >= ref - SEG_ATOL, (d, ref)


def test_obstacles_in_base_frame_keep_their_distances():
    """A box, a polytope and a sphere of the world moved into the base frame: a point's box
    and face distances there equal those of the point in the world."""
    rng = np.random.default_rng(1)
    T_box = frames.rpy_pose((0.3, -0.2, 0.5), (0.3, -0.4, 1.1))
    world = evo.make_sphere_world(
        {"body": np.zeros((1, 1), int), "centre": np.zeros((1, 1, 3)), "radius": np.full((1, 1), 0.01),
         "box_on": np.ones((1, 1, 1), bool), "face_on": np.ones((1, 1, 1), bool), "ball_on": np.ones((1, 1, 1), bool),
         "pair_a": np.zeros((1, 0), int), "pair_b": np.zeros((1, 0), int), "pair_on": np.zeros((1, 0, 0), bool),
         "cap_body": np.zeros((1, 0, 2), int),
         "cap_ends": np.zeros((1, 0, 2, 2, 3)), "cap_reach": np.zeros((1, 0)), "cap_on": np.zeros((1, 0), bool)},
        {"c": T_box[None, :3, 3], "R": T_box[None, :3, :3], "half": [[0.1, 0.2, 0.05]], "vehicle": [False]},
        np.array([[[0.0, 0.6, 0.8, -0.3], [1.0, 0.0, 0.0, -0.2]]]), np.array([[0.1, 0.2, 0.3, 0.05]]), 0.0, 0, 0)
    T_world_base = frames.rpy_pose((0.5, 0.1, 1.2), (np.pi, 0.2, -0.7))
    c, R, half, faces, balls = (np.asarray(a) for a in obstacles_in_base(world, jnp.asarray(T_world_base, jnp.float32)))
    x_w = rng.uniform(-1, 1, (50, 3))
    x_b = (x_w - T_world_base[:3, 3]) @ T_world_base[:3, :3]
    box_w = np.abs((x_w - T_box[:3, 3]) @ T_box[:3, :3]) - half[0]
    box_b = np.abs((x_b - c[0]) @ R[0]) - half[0]
    np.testing.assert_allclose(box_b, box_w, atol=BASE_ATOL)
    face_w = np.asarray(world.faces[0, :, :3]) @ x_w.T + np.asarray(world.faces[0, :, 3:])
    np.testing.assert_allclose(faces[0, :, :3] @ x_b.T + faces[0, :, 3:], face_w, atol=BASE_ATOL)
    np.testing.assert_allclose(np.linalg.norm(x_b - balls[0, :3], axis=-1),
                               np.linalg.norm(x_w - [0.1, 0.2, 0.3], axis=-1), atol=BASE_ATOL)


def test_capsule_world_is_at_least_as_strict_as_the_link_capsules():
    """Without a planning scene the links' capsules become spheres that contain them: every
    configuration whose capsules meet a box collides, and the base's capsule is tested against
    the scene, not the vehicle it is fixed to."""
    chain = BRAVO7.chain
    T_vb = frames.rpy_pose((0.35, 0.0, -0.2), (np.pi, 0.0, 0.0))
    hull = (np.eye(4)[None], np.array([[0.45, 0.35, 0.2]]))
    scene = (np.stack([frames.rpy_pose((0.6, 0.0, -0.6), (0.0, 0.3, 0.0)), frames.rpy_pose((0.0, 0.0, -1.2), (0.0, 0.0, 0.0))]),
             np.array([[0.05, 0.4, 0.3], [2.0, 2.0, 0.1]]))
    world = evo.capsule_world(chain, BRAVO7.link_radius, T_vb, hull, scene, 1, 0.03, jnp.float32)
    rng = np.random.default_rng(2)
    q = jnp.asarray(rng.uniform(BRAVO7.lower, BRAVO7.upper, (2000, chain.n_joints)), jnp.float32)
    K = kin.kinematics(chain, q)
    T_world_base = jnp.asarray(T_vb, jnp.float32)  # the vehicle at the world's origin
    hit = np.asarray(jax.jit(evo.world_collides)(world, jnp.zeros(1, jnp.int32), T_world_base,
                                                 K.T_base_joint[None]))[0]
    points = link_points(T_world_base, K.T_base_joint, K.T_base_tool)
    n_caps = points.shape[-2] - 1
    skip = np.zeros((n_caps, 3), bool)
    skip[0, 0] = True  # the base's capsule against the hull
    T_boxes = jnp.asarray(np.concatenate([hull[0], scene[0]]), jnp.float32)  # the vehicle's frame is the world's
    halves = jnp.asarray(np.concatenate([hull[1], scene[1]]), jnp.float32)
    capsule_hit = np.asarray(capsules_hit_boxes(points, BRAVO7.link_radius, T_boxes, halves, jnp.asarray(skip)))
    assert capsule_hit.any() and (~capsule_hit).any()
    assert not np.any(capsule_hit & ~hit)  # conservative: spheres contain the capsules
    assert np.mean(hit == capsule_hit) > 0.95  # and they bulge out by 2.7 mm at most


def test_chunked_poses_answer_as_one_call(monkeypatch):
    """Vehicle poses in chunks (a world too large for one call's blocks) give the same answers
    as one call: chunks of 1 and of 3 poses, 7 poses of 2 000 configurations each."""
    chain = BRAVO7.chain
    T_vb = frames.rpy_pose((0.35, 0.0, -0.2), (np.pi, 0.0, 0.0))
    scene = (np.stack([frames.rpy_pose((0.6, 0.0, -0.6), (0.0, 0.3, 0.0))]), np.array([[0.05, 0.4, 0.3]]))
    world = evo.capsule_world(chain, BRAVO7.link_radius, T_vb, (np.eye(4)[None], np.array([[0.45, 0.35, 0.2]])),
                              scene, 1, 0.03, jnp.float32)
    rng = np.random.default_rng(3)
    K = kin.kinematics(chain, jnp.asarray(rng.uniform(BRAVO7.lower, BRAVO7.upper, (7, 1, 2000, chain.n_joints)),
                                          jnp.float32))
    T_world_base = jnp.asarray(np.stack([frames.rpy_pose((x, 0.0, 0.1 * x), (np.pi, 0.0, x)) @ T_vb
                                         for x in np.linspace(-0.3, 0.3, 7)]), jnp.float32)
    group = jnp.zeros(1, jnp.int32)
    whole = np.asarray(evo.world_collides(world, group, T_world_base, K.T_base_joint))
    assert whole.any() and (~whole).any()
    per_config = world.rows.radius.shape[-1] * 2  # two boxes, no polytope, sphere or pair
    for poses in (1, 3):
        monkeypatch.setattr("uvms_jax.evo._world.TEST_BUDGET", poses * 2000 * per_config)
        np.testing.assert_array_equal(np.asarray(evo.world_collides(world, group, T_world_base, K.T_base_joint)), whole)


def test_polytopes_of_few_faces_beside_a_padded_one():
    """A cube and a half-space padded to the cube's 6 faces, read through ``n_faces``: a sphere
    collides exactly where NumPy's largest signed face distance over the unpadded faces (in the
    world) is within its radius, the padding (here a face that would cut the half-space in two)
    unread; a face count beyond the padding is refused."""
    rng = np.random.default_rng(3)
    cube = np.array([[s * a[0], s * a[1], s * a[2], -0.2] for a in np.eye(3) for s in (1.0, -1.0)])  # |x|∞ ≤ 0.2
    cube[:, 3] += cube[:, :3] @ [0.5, 0.0, 0.0]  # centred at x = 0.5
    floor = np.array([[0.0, 0.0, 1.0, 0.4]])  # z ≤ -0.4 (a seabed below)
    junk = np.array([[-1.0, 0.0, 0.0, 0.0]])  # x ≥ 0: read, it would free the half-space's x < 0
    padded = np.stack([cube, np.concatenate([floor, np.repeat(junk, 5, axis=0)])])
    n, r = 400, 0.05
    centres = rng.uniform([-0.2, -0.5, -0.7], [0.9, 0.5, 0.4], (n, 3))  # in W
    T_world_base = frames.rpy_pose((0.1, -0.2, 0.3), (0.2, -0.1, 0.8))
    rows = {"body": np.zeros((n, 1), int), "centre": ((centres - T_world_base[:3, 3]) @ T_world_base[:3, :3])[:, None],
            "radius": np.full((n, 1), r), "box_on": np.zeros((n, 1, 0), bool), "face_on": np.ones((n, 1, 2), bool),
            "ball_on": np.zeros((n, 1, 0), bool), "pair_a": np.zeros((n, 0), int), "pair_b": np.zeros((n, 0), int),
            "pair_on": np.zeros((n, 0, 0), bool), "cap_body": np.zeros((n, 0, 2), int),
            "cap_ends": np.zeros((n, 0, 2, 2, 3)), "cap_reach": np.zeros((n, 0)), "cap_on": np.zeros((n, 0), bool)}
    no_boxes = {"c": np.zeros((0, 3)), "R": np.zeros((0, 3, 3)), "half": np.zeros((0, 3)), "vehicle": np.zeros(0, bool)}
    world = evo.make_sphere_world(rows, no_boxes, padded, np.zeros((0, 4)), 0.0, 0, 0, jnp.float32, n_faces=(6, 1))
    eye = jnp.broadcast_to(jnp.eye(4, dtype=jnp.float32), (n, 1, 1, 4, 4))
    got = np.asarray(evo.world_collides(world, jnp.arange(n), jnp.asarray(T_world_base, jnp.float32), eye))[:, 0]
    depth = np.minimum(np.max(centres @ cube[:, :3].T + cube[:, 3], axis=1), centres @ floor[0, :3] + floor[0, 3])
    clear = np.abs(depth - r) > 1e-3  # away from the float32 boundary and the slack
    assert 50 < np.sum(got & clear) < np.sum(clear) - 50  # both answers occur
    np.testing.assert_array_equal(got[clear], (depth <= r)[clear])
    with pytest.raises(ValueError, match="n_faces"):
        evo.make_sphere_world(rows, no_boxes, padded, np.zeros((0, 4)), 0.0, 0, 0, n_faces=(7, 1))


def _every_kind_world(chain, rng):
    """A world of two rows holding every kind of pair: spheres on every body, boxes and
    polytopes both fixed to the vehicle (in B) and in the scene (in W, one polytope a padded
    half-space), fixed spheres, sphere pairs and capsule pairs, each row its own masks."""
    n_rows, N, A, A2, C = 2, 12, 7, 5, 3
    body = np.tile(np.arange(N) % (chain.n_joints + 1), (n_rows, 1))
    cube = np.array([[s * a[0], s * a[1], s * a[2], -0.15] for a in np.eye(3) for s in (1.0, -1.0)])
    cube[:, 3] -= cube[:, :3] @ [0.1, 0.3, -0.4]  # centred at (0.1, 0.3, -0.4)
    tilted = cube.copy()
    tilted[:, 3] -= tilted[:, :3] @ [0.3, -0.4, 0.9]
    floor = np.concatenate([[[0.0, 0.0, 1.0, -0.45]], np.repeat([[1.0, 0.0, 0.0, 0.0]], 5, axis=0)])
    mask = lambda *shape: rng.random((n_rows,) + shape) < 0.7  # noqa: E731
    rows = {"body": body, "centre": rng.uniform(-0.05, 0.05, (n_rows, N, 3)), "radius": rng.uniform(0.02, 0.05, (n_rows, N)),
            "box_on": mask(N, 4), "face_on": mask(N, 3), "ball_on": mask(N, 2),
            "pair_a": np.tile(np.arange(A), (n_rows, 1)), "pair_b": np.tile(np.arange(A, A + A2), (n_rows, 1)),
            "pair_on": mask(A, A2) & (np.abs(body[:, :A, None] - body[:, None, A:]) > 1),  # not the same or next body
            "cap_body": np.tile([[0, 3], [1, 5], [2, 6]], (n_rows, 1, 1)),
            "cap_ends": rng.uniform(-0.05, 0.05, (n_rows, C, 2, 2, 3)), "cap_reach": rng.uniform(0.04, 0.08, (n_rows, C)),
            "cap_on": mask(C)}
    T_box = [frames.rpy_pose(p, a) for p, a in (((0.3, 0.3, 0.3), (0.0, 0.0, 0.3)), ((0.2, -0.4, -0.4), (0.4, 0.0, 0.0)),
                                                 ((0.6, 0.2, 0.5), (0.0, 0.2, 1.0)), ((-0.2, -0.6, 1.3), (0.1, 0.1, 0.1)))]
    boxes = {"c": np.stack([T[:3, 3] for T in T_box]), "R": np.stack([T[:3, :3] for T in T_box]),
             "half": rng.uniform(0.05, 0.15, (4, 3)), "vehicle": np.array([True, False, False, False])}
    balls = np.array([[0.4, 0.0, 1.0, 0.1], [0.0, 0.3, 0.7, 0.15]])
    return evo.make_sphere_world(rows, boxes, np.stack([cube, tilted, floor]), balls, 0.02, 2, 1, jnp.float32,
                                 n_faces=(6, 6, 1))


def test_gpu_kernel_answers_as_the_xla_test():
    """The collision kernel (uvms_jax.evo._world_gpu), emulated, calls exactly the
    configurations colliding that the XLA test does, in a world with every kind of pair and at
    vehicle poses that move the scene's obstacles; and each kind of pair decides some
    configurations."""
    from uvms_jax.evo import _world, _world_gpu

    chain = BRAVO7.chain
    rng = np.random.default_rng(4)
    world = _every_kind_world(chain, rng)
    group = jnp.array([0, 1, 1], jnp.int32)
    T_vb = frames.rpy_pose((0.35, 0.0, -0.2), (np.pi, 0.0, 0.0))
    T_world_base = jnp.asarray(np.stack([frames.rpy_pose((x, 0.1, 1.0 - x), (0.1, 0.0, 2 * x)) @ T_vb
                                         for x in (-0.2, 0.0, 0.3)]), jnp.float32)
    q = rng.uniform(BRAVO7.lower, BRAVO7.upper, (3, 3, 100, chain.n_joints))
    K = kin.kinematics(chain, jnp.asarray(q, jnp.float32))
    xla = np.asarray(jax.jit(_world.world_collides)(world, group, T_world_base, K.T_base_joint))
    kernel = jax.jit(lambda w, *a: _world_gpu.world_collides_kernel(w, *a, interpret=True))
    np.testing.assert_array_equal(np.asarray(kernel(world, group, T_world_base, K.T_base_joint)), xla)
    assert 0.1 < xla.mean() < 0.9
    r = world.rows
    for kind in ({"box_on": r.box_on}, {"face_on": r.face_on}, {"ball_on": r.ball_on}, {"pair_on": r.pair_on},
                 {"cap_on": r.cap_on}):
        name, on = next(iter(kind.items()))
        alone = world.replace(rows=r.replace(**{n: jnp.zeros_like(getattr(r, n)) for n in
                                                ("box_on", "face_on", "ball_on", "pair_on", "cap_on") if n != name}))
        hits = np.asarray(kernel(alone, group, T_world_base, K.T_base_joint))
        assert hits.any(), name
        np.testing.assert_array_equal(hits, np.asarray(jax.jit(_world.world_collides)(alone, group, T_world_base,
                                                                                      K.T_base_joint)), err_msg=name)
