"""The docking fitness is a sum of registered terms: the default terms are eq. 15 of the paper,
``a·M_a − b·D`` inside Wd, on both problems (closed-form and numerical IK), and a term added
from outside the package (here, in this file alone) steers a docking GA."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from uvms_jax import evo, kin
from uvms_jax.settings import SettingsError, from_mapping

# eq. 15 by hand in the problem's dtype rounds like the sum of the two weighed terms, except
# where XLA fuses a multiply into the add (one rounding fewer): a few units in the last place
# of the larger product.
ULPS = 4
N_POSES = 64
HEIGHT_WEIGHT = 100.0  # × z [m]: up to 30 over the box, well above a·M_a − b·D (a few units)


def _eq15(a, b, M_a, D, feasible, dtype) -> tuple[np.ndarray, np.ndarray]:
    """``a·M_a − b·D`` inside Wd, 0 outside, in ``dtype``, and its rounding allowance."""
    a, b, M_a, D = (np.asarray(v, dtype=dtype) for v in (a, b, M_a, D))
    scale = np.maximum(np.abs(a * M_a), np.abs(b * D))
    return np.where(feasible, a * M_a - b * D, 0.0), ULPS * np.finfo(dtype).eps * scale


def _random_poses(problem, n: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return rng.uniform(np.asarray(problem.pose_low), np.asarray(problem.pose_high), size=(n, 4))


@pytest.fixture(scope="module")
def paper_scene():
    return evo.SceneSettings()


@pytest.fixture(scope="module")
def paper_problem(paper_scene):
    return evo.docking_problem(paper_scene, "float64")


def test_default_terms_are_eq_15_on_the_paper_problem(paper_scene, paper_problem):
    got = evo.evaluate(paper_problem, _random_poses(paper_problem, N_POSES, 0))
    feasible = np.asarray(got.feasible)
    assert 0 < feasible.sum() < N_POSES  # both branches of eq. 15 are seen
    want, tol = _eq15(paper_scene.a, paper_scene.b, got.M_a, got.D, feasible, np.float64)
    np.testing.assert_array_less(np.abs(np.asarray(got.fitness) - want), tol + np.finfo(np.float64).tiny)


def test_default_terms_are_eq_15_on_an_arm_problem():
    """The numerical-IK problem's objective, from a random per-seed manipulability ``w``."""
    a, b = 300.0, 0.5
    problem = evo.make_arm_docking_problem(
        chain=kin.docking_arm(0.1, 0.4, 0.4), T_vehicle_base=np.eye(4), T_world_tool=np.stack([np.eye(4)] * 3),
        low=(-1.0, -1.0, -0.5, -np.pi), high=(1.0, 1.0, 0.5, np.pi), p_dock=(0.1, 0.0, -0.2),
        p_i=(-2.0, -1.0, 1.0), a=a, b=b, link_radius=0.05,
        vehicle_boxes=(np.eye(4)[None], np.array([[0.2, 0.2, 0.2]])),
        scene_boxes=(np.eye(4)[None], np.array([[0.3, 0.3, 0.3]])), n_seeds=2, dtype=jnp.float32)
    rng = np.random.default_rng(1)
    pose = _random_poses(problem, N_POSES, 1).astype(np.float32)
    w = rng.uniform(0.0, 0.05, (N_POSES, 3, 2)).astype(np.float32)
    got = jax.jit(evo.arm_terms)(problem, jnp.asarray(pose), jnp.asarray(w))
    feasible = np.asarray(got.feasible)
    assert 0 < feasible.sum() < N_POSES  # the hull meets the scene box at some poses
    np.testing.assert_array_equal(np.asarray(got.M_a), w.max(axis=-1).min(axis=-1))  # eq. 1
    want, tol = _eq15(a, b, got.M_a, got.D, feasible, np.float32)
    np.testing.assert_array_less(np.abs(np.asarray(got.fitness) - want), tol + np.finfo(np.float32).tiny)


@pytest.fixture
def height():
    """A term that favours high poses: ``z`` [m]."""
    term = evo.register_fitness_term("height", lambda x: x.pose[..., 2])
    yield term
    evo.FITNESS_TERMS.pop("height")


def _tiny_ga(height_weight: float):
    """A small GA on the paper's scene with the ``height`` term weighed ``height_weight``. The
    weights are the objective's data, not its program: every weight runs one compiled GA."""
    scene = from_mapping(evo.SceneSettings, {"terms": [{"name": "height", "weight": height_weight}]})
    problem = evo.docking_problem(scene, "float64")
    ga_settings = from_mapping(evo.GASettings, {"population_size": 16, "max_generations": 25, "eval_chunk": None,
                                                "bits": {"x": 6, "y": 6, "z": 4, "psi": 4}})
    codec, ga, params = evo.make_ga(ga_settings, problem)
    return problem, evo.run_ga(jax.random.key(0), problem, codec, ga, params)


def test_a_term_registered_outside_the_package_changes_the_docking_result(paper_problem, height):
    # Weighed 0 the term adds exactly 0 to every fitness (f + 0·z = f): the GA of eq. 15 alone.
    _, base = _tiny_ga(0.0)
    problem, tall = _tiny_ga(HEIGHT_WEIGHT)
    assert problem.objective.names == ("manipulability", "distance", "height")
    top = float(problem.pose_high[2])
    assert float(tall.best_x[2]) == pytest.approx(top)  # the term's weight outweighs eq. 15
    assert float(base.best_x[2]) < top
    # The new fitness is eq. 15 plus the weighed term, and it is what the GA maximised.
    terms = evo.evaluate(paper_problem, tall.best_x[None])
    want = float(terms.fitness[0]) + HEIGHT_WEIGHT * float(tall.best_x[2])
    assert float(tall.best_fitness) == pytest.approx(want, rel=1e-12)


def test_the_registry_refuses_clashes_and_unknown_names(height):
    with pytest.raises(ValueError, match="already registered"):
        evo.register_fitness_term("height", lambda x: x.D)
    with pytest.raises(ValueError, match="identifier"):
        evo.register_fitness_term("not a name", lambda x: x.D)
    with pytest.raises(SettingsError, match="terms.*'tallness'"):
        from_mapping(evo.SceneSettings, {"terms": [{"name": "tallness"}]})
    with pytest.raises(SettingsError, match="weighed by the scene's a or b"):
        from_mapping(evo.SceneSettings, {"terms": [{"name": "distance", "weight": 2.0}]})
    with pytest.raises(SettingsError, match="named twice"):
        from_mapping(evo.SceneSettings, {"terms": [{"name": "height"}, {"name": "height", "weight": 2.0}]})
    with pytest.raises(ValueError, match="unknown fitness terms"):
        evo.make_objective({"tallness": 1.0})
