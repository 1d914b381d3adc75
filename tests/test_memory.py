"""The episode's peak memory: follows an allocation, and starts again at a reset."""

from __future__ import annotations

import numpy as np
import pytest

from mrexplore.runtime.memory import peak_mb, reset_peak


def test_peak_follows_an_allocation_and_starts_again_at_a_reset() -> None:
    if not reset_peak():
        pytest.skip("this kernel does not let a process reset its peak memory (/proc/self/clear_refs)")
    before = peak_mb()
    block = np.ones(200_000_000, dtype=np.uint8)  # 200 MB, every page touched
    del block
    high = peak_mb()
    assert high >= before + 190
    assert reset_peak()
    assert peak_mb() <= high - 150  # the block is gone, and so is its peak
