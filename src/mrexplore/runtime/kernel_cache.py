"""Whether numba's compiled kernels are cached yet: the first run compiles them (a minute or two on two
cores) and says so, later runs load them in a moment."""

from __future__ import annotations

import os
import sys
from pathlib import Path

__all__ = ["kernels_cached", "say_if_compiling", "compiled_this_run", "COMPILING"]

COMPILING = "compiling kernels, first run only (a minute or two on two cores; later runs load them at once)"
_compiling = False
_SENTINEL = "lidar.*.nbi"
"""The index numba writes beside the simulator's LiDAR kernels, which every mission compiles first."""


def kernels_cached() -> bool:
    """True where numba's cache holds the simulator's kernels: in the package's own folder, or, where that
    is not writable, in numba's user-wide cache (``$NUMBA_CACHE_DIR``, else ``~/.cache/numba``)."""
    pkg = Path(__file__).parents[1]  # the package: runtime/ is one of its folders
    if any((pkg / "sim" / "__pycache__").glob(_SENTINEL)):
        return True
    user = Path(os.environ.get("NUMBA_CACHE_DIR") or Path.home() / ".cache" / "numba")
    return user.is_dir() and any(user.rglob(_SENTINEL))


def say_if_compiling(prog: str = "mrexplore") -> bool:
    """Print the one-line notice on stderr where the kernels are not cached yet; True where it did."""
    global _compiling
    if kernels_cached():
        return False
    print(f"{prog}: {COMPILING}", file=sys.stderr, flush=True)
    _compiling = True
    return True


def compiled_this_run() -> bool:
    """Whether this process found the kernels uncached (:func:`say_if_compiling`): its timings include
    compiling them."""
    return _compiling
