"""The planner's Numba kernels are cached by content: a copy of the package in another folder
(a fresh clone) reads the kernels an identical copy compiled, and a copy whose kernel source
differs compiles its own. Numba's own hit and miss counters are the oracle."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numba
import numpy as np

from uvms_jax import plan as P
from uvms_jax.plan import _rrtc, _sphere_kernels, _vector_kernels
from uvms_jax.robot import load_arm

PLAN = Path(__file__).resolve().parents[2] / "uvms_jax" / "plan"
FILES = ("_kernel_cache.py", "_rrtc.py", "_sphere_kernels.py", "_vector_kernels.py")
# Compiles one small kernel of the copy at argv[1] and prints Numba's cache counters and folder.
PROBE = """
import json, numpy as np
from uvms_jax.plan import _sphere_kernels as k
k._dot(np.ones(3), np.ones(3))
print(json.dumps({"hits": sum(k._dot.stats.cache_hits.values()), "misses": sum(k._dot.stats.cache_misses.values()),
                  "folder": k._dot._cache.cache_path}))
"""


def _copy(root: Path) -> Path:
    """The kernel modules alone in a package ``uvms_jax.plan`` under ``root``."""
    (root / "uvms_jax" / "plan").mkdir(parents=True)
    (root / "uvms_jax" / "__init__.py").write_text("")
    (root / "uvms_jax" / "plan" / "__init__.py").write_text("")
    for name in FILES:
        shutil.copy(PLAN / name, root / "uvms_jax" / "plan" / name)
    return root


def _probe(root: Path, cache: Path) -> dict:
    env = {**os.environ, "PYTHONPATH": str(root), "NUMBA_CACHE_DIR": str(cache)}
    env.pop("NUMBA_CACHE_LOCATOR_CLASSES", None)
    out = subprocess.run([sys.executable, "-c", PROBE], env=env, cwd=root, capture_output=True, text=True, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def test_identical_copy_reads_the_cache_and_changed_source_does_not(tmp_path):
    cache = tmp_path / "numba"
    a, b, c = (_copy(tmp_path / name) for name in "abc")
    with open(c / "uvms_jax" / "plan" / "_rrtc.py", "a") as f:  # another kernel module than the probed one
        f.write("\n# changed\n")
    first, same, changed = _probe(a, cache), _probe(b, cache), _probe(c, cache)
    assert (first["hits"], first["misses"]) == (0, 1)
    assert (same["hits"], same["misses"]) == (1, 0) and same["folder"] == first["folder"]
    assert (changed["hits"], changed["misses"]) == (0, 1) and changed["folder"] != first["folder"]
    assert Path(first["folder"]).parent == cache


def _signatures() -> dict:
    """Every compiled kernel's compiled signatures, by module and name."""
    return {(m.__name__, name): len(f.signatures) for m in (_rrtc, _sphere_kernels, _vector_kernels)
            for name, f in vars(m).items() if isinstance(f, numba.core.registry.CPUDispatcher)}


def test_warm_kernels_leaves_nothing_to_compile_for_another_world():
    """After warm_kernels(arm), a checker of another world (other shapes, an opening, a margin)
    and a query on it compile no kernel: what the pipeline compiles ahead is what planning uses."""
    arm = load_arm("bravo7")
    P.warm_kernels(arm)
    before = _signatures()
    world = P.World((P.Obstacle("post", "cylinder", (0.5, 0.0, 0.2), dims=(0.05, 0.4)),
                     P.Obstacle("ball", "sphere", (0.0, 0.5, 0.3), dims=(0.08,)),
                     P.Obstacle("bar", "capsule", (-0.4, -0.3, 0.1), dims=(0.03, 0.3)),
                     P.Obstacle("plate", "box", (0.0, 0.0, -0.5), dims=(1.0, 1.0, 0.02))))
    start = np.clip(np.zeros(arm.n_joints), arm.lower, arm.upper)
    goal = np.clip(start + 0.3, arm.lower, arm.upper)
    P.plan_query(arm, world, start, goal, budget_s=0.5, margin=0.005)
    assert _signatures() == before
