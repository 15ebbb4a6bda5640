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
