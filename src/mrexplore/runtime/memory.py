"""Peak resident memory of this process over a stretch of work (one episode, say).

On Linux the kernel's high-water mark (``VmHWM``) can be reset by writing ``5`` to
``/proc/self/clear_refs``, so the peak of one episode is read exactly, not sampled. Where that is not
possible, the peak is the process's whole-life peak (``ru_maxrss``), an upper bound.
"""

from __future__ import annotations

import resource
import sys

__all__ = ["reset_peak", "peak_mb"]


def reset_peak() -> bool:
    """Start a new peak at the current resident size; False where the kernel does not allow it."""
    try:
        with open("/proc/self/clear_refs", "w") as f:
            f.write("5")
    except OSError:
        return False
    return True


def peak_mb() -> float:
    """Peak resident memory in MB (10^6 bytes) since the last :func:`reset_peak` (or the process's start).

    Examples
    --------
    >>> reset_peak() in (True, False) and peak_mb() > 0
    True
    """
    try:
        with open("/proc/self/status") as f:
            for line in f:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1]) * 1024 / 1e6
    except OSError:
        pass
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss  # KiB on Linux, bytes on macOS
    return rss / 1e6 if sys.platform == "darwin" else rss * 1024 / 1e6
