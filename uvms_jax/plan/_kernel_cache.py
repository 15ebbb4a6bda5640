"""Numba's on-disk cache of the planner's kernels, keyed by their source text rather than by
where the source lies.

Numba's own locators file a kernel's compiled code under a folder named by the hash of the
source file's absolute path, so every clone or worktree of this repository compiles all the
kernels again (about 25 s on 2 CPU cores) although the code is the same. The kernel modules
(:data:`KERNEL_FILES`) import this module before their first ``@numba.njit(cache=True)``; it puts
:class:`ContentLocator` first among Numba's locators, for those modules only:

* the folder is ``<NUMBA_CACHE_DIR>/uvms_jax_plan_<digest>``, where the digest is the SHA-256 of
  the kernel modules' source text together (one kernel calls another's, so a change in one
  must retire the compiled code of all);
* the index's freshness stamp is the same digest, so a cache written for different source is
  never read, whatever the file times say (Numba versions before 0.68 stamp the file's time
  and size, which a clone changes);
* everything else Numba keys on is kept: the function's bytecode, its signature, the target
  CPU, Numba's and Python's versions.

Other Numba functions, and a run with ``NUMBA_CACHE_DIR`` empty or
``NUMBA_CACHE_LOCATOR_CLASSES`` set, get Numba's own locators.
"""

from __future__ import annotations

import functools
import hashlib
import os
from pathlib import Path

from numba.core import caching, config

HERE = Path(__file__).resolve().parent
KERNEL_FILES = ("_rrtc.py", "_sphere_kernels.py", "_vector_kernels.py")  # every module of @njit(cache=True) kernels


@functools.cache
def kernels_digest() -> str:
    """SHA-256 (hex) of :data:`KERNEL_FILES`' names and contents, in that order."""
    h = hashlib.sha256()
    for name in KERNEL_FILES:
        data = (HERE / name).read_bytes()
        h.update(f"{name}\0{len(data)}\0".encode())
        h.update(data)
    return h.hexdigest()


# Numba 0.68 dropped the underscore of these names.
_UserProvided = getattr(caching, "UserProvidedCacheLocator", None) or caching._UserProvidedCacheLocator


def cache_folder() -> str:
    """The folder of this source's compiled kernels (whether or not it exists yet)."""
    return os.path.join(config.CACHE_DIR, f"uvms_jax_plan_{kernels_digest()[:32]}")


class ContentLocator(_UserProvided):
    """Numba cache locator of the kernel modules: a folder and a stamp by their content."""

    def __init__(self, py_func, py_file):
        self._py_file = py_file
        self._lineno = py_func.__code__.co_firstlineno
        self._cache_path = cache_folder()

    def get_source_stamp(self) -> str:
        return kernels_digest()

    @classmethod
    def from_function(cls, py_func, py_file):
        path = Path(py_file).resolve()
        if path.parent != HERE or path.name not in KERNEL_FILES:
            return None
        return super().from_function(py_func, py_file)  # None without NUMBA_CACHE_DIR or a writable folder


def _register() -> None:
    """Put :class:`ContentLocator` first among Numba's cache locators (once)."""
    impl = getattr(caching, "CacheImpl", None) or getattr(caching, "_CacheImpl")
    if ContentLocator not in impl._locator_classes:
        impl._locator_classes = [ContentLocator, *impl._locator_classes]


_register()
