"""The worker runner: inline, in spawned local processes, results as they finish, and a deadline."""

from __future__ import annotations

import math
import time

from mrexplore.workers import JobRunner


def _square(x: int) -> int:
    return x * x


def test_inline_and_local_workers_give_every_result() -> None:
    with JobRunner(_square, workers=1) as inline:
        assert list(inline.run([1, 2, 3])) == [1, 4, 9]  # inline: in order
    with JobRunner(_square, workers=2) as pool:
        assert sorted(pool.run([1, 2, 3, 4])) == [1, 4, 9, 16]  # as they finish


def test_no_job_starts_after_the_deadline() -> None:
    with JobRunner(_square, workers=1) as inline:
        assert list(inline.run([1, 2], deadline=time.perf_counter() - 1)) == []
        assert list(inline.run([5], deadline=math.inf)) == [25]
