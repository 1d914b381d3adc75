"""The worker runner: inline, in spawned local processes, results as they finish, and a deadline."""

from __future__ import annotations

import math
import time

from mrexplore.runtime.workers import JobRunner


def test_inline_and_local_workers_give_every_result() -> None:
    # a builtin: spawned workers import the job's function by name, and this test module is not importable
    with JobRunner(abs, workers=1) as inline:
        assert list(inline.run([-1, 2, -3])) == [1, 2, 3]  # inline: in order
    with JobRunner(abs, workers=2) as pool:
        assert sorted(pool.run([-1, -2, 3, -4])) == [1, 2, 3, 4]  # as they finish


def test_no_job_starts_after_the_deadline() -> None:
    with JobRunner(abs, workers=1) as inline:
        assert list(inline.run([1, 2], deadline=time.perf_counter() - 1)) == []
        assert list(inline.run([-5], deadline=math.inf)) == [5]
