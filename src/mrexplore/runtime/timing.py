"""Timing hooks: wall-clock milliseconds by phase of a mission and of a decision, recorded only where a
benchmark hands in a :class:`PhaseTimes` (ordinary runs pass None and pay nothing)."""

from __future__ import annotations

import time
from collections import defaultdict
from collections.abc import Iterator
from contextlib import AbstractContextManager, contextmanager, nullcontext

__all__ = ["PhaseTimes", "timed"]


class PhaseTimes:
    """Milliseconds of each run of each phase, in the order they ran.

    Examples
    --------
    >>> times = PhaseTimes()
    >>> with timed(times, "assignment"):
    ...     pass
    >>> list(times.ms), len(times.ms["assignment"])
    (['assignment'], 1)
    """

    def __init__(self) -> None:
        self.ms: defaultdict[str, list[float]] = defaultdict(list)

    @contextmanager
    def phase(self, name: str) -> Iterator[None]:
        t = time.perf_counter()
        try:
            yield
        finally:
            self.ms[name].append((time.perf_counter() - t) * 1e3)


def timed(times: PhaseTimes | None, name: str) -> AbstractContextManager[None]:
    """``times.phase(name)``, or nothing where ``times`` is None."""
    return nullcontext() if times is None else times.phase(name)
