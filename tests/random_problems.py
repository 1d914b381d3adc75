"""Tests' tool: random assignment problems (any team and cluster count, unreachable pairs, many ties)."""

from __future__ import annotations

import numpy as np

from mrexplore.global_planning.protocol import AssignmentProblem
from mrexplore.preprocessing.clustering import Clusters


def random_problem(rng: np.random.Generator) -> AssignmentProblem:
    R, C = int(rng.integers(1, 9)), int(rng.integers(1, 12))
    centres = rng.integers(0, 50, size=(C, 2)).astype(np.int32)
    sizes = rng.integers(2, 40, size=C).astype(np.int32)
    dist = rng.integers(1, 60, size=(R, C)).astype(np.float64)  # whole cells: many exact ties
    dist[rng.random((R, C)) < 0.2] = np.inf
    clusters = Clusters(centres, sizes, np.repeat(centres, sizes, 0), np.repeat(np.arange(C, dtype=np.int32), sizes))
    return AssignmentProblem(
        rng.integers(0, 50, size=(R, 2)).astype(np.int32),
        clusters,
        dist,
        0.1,
        np.zeros((50, 50), np.uint8),
        current_cluster=rng.integers(-1, C, size=R),
    )
