"""uvms_jax: JAX-accelerated kinematics, dexterity, scheduling and hardware tools for UVMS."""

import os as _os
from pathlib import Path as _Path

__version__ = "0.1.0"

# Numba writes its compiled kernels' cache beside their source unless told otherwise, i.e. into
# an installed package. Unless the user chose a folder, it goes to the user's cache (read by
# Numba when it is first imported, which the package's modules do after this line).
_os.environ.setdefault("NUMBA_CACHE_DIR", str(_Path(_os.environ.get("XDG_CACHE_HOME") or _Path.home() / ".cache")
                                              / "uvms_jax" / "numba"))
