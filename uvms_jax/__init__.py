"""uvms_jax: JAX-accelerated kinematics, dexterity, scheduling and hardware tools for UVMS."""

import os as _os
import sys as _sys
from pathlib import Path as _Path

__version__ = "0.1.0"

# Numba writes its compiled kernels' cache beside their source unless told otherwise, i.e. into
# an installed package. Unless the user chose a folder, it goes to the user's cache: through the
# environment for a Numba imported later, through its config where Numba was imported first
# (the package's kernels are decorated after this line, when the cache folder is read).
_os.environ.setdefault("NUMBA_CACHE_DIR", str(_Path(_os.environ.get("XDG_CACHE_HOME") or _Path.home() / ".cache")
                                              / "uvms_jax" / "numba"))
if "numba" in _sys.modules and not _sys.modules["numba"].config.CACHE_DIR:
    _sys.modules["numba"].config.CACHE_DIR = _os.environ["NUMBA_CACHE_DIR"]
