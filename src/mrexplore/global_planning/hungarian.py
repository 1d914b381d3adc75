"""Minimum-cost robot-to-cluster matching (Hungarian algorithm), with unreachable pairs and spare robots."""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import linear_sum_assignment

from mrexplore.global_planning.protocol import UNASSIGNED

__all__ = ["match_min_cost"]


def match_min_cost(cost: NDArray[np.floating]) -> NDArray[np.int64]:
    """Assign each robot (row) a cluster (column) minimising the total cost; ``inf`` marks impossible pairs.

    Every cluster is used once before any is shared: when robots outnumber clusters, the columns are
    repeated and each repetition costs more than any first use, so spare robots join the cluster that
    suits them best only after every cluster has one robot. A robot with no finite cost gets
    :data:`UNASSIGNED`.

    Examples
    --------
    >>> match_min_cost(np.array([[1.0, 5.0], [2.0, 3.0]])).tolist()
    [0, 1]
    >>> match_min_cost(np.array([[1.0], [2.0], [np.inf]])).tolist()  # more robots than clusters
    [0, 0, -1]
    """
    cost = np.asarray(cost, dtype=np.float64)
    n_r, n_c = cost.shape
    out = np.full(n_r, UNASSIGNED, dtype=np.int64)
    if n_r == 0 or n_c == 0:
        return out
    finite = np.isfinite(cost)
    if not finite.any():
        return out
    span = float(cost[finite].max() - cost[finite].min()) + 1.0
    big = span * (n_r + 1) * 4.0
    reps = math.ceil(n_r / n_c)
    # Copy j of every column costs j * big more, so copies are used only when columns run out.
    tiled = np.concatenate([np.where(finite, cost, np.inf) + j * big for j in range(reps)], axis=1)
    impossible = big * (reps + 1) * 4.0
    tiled = np.where(np.isfinite(tiled), tiled - cost[finite].min(), impossible)
    rows, cols = linear_sum_assignment(tiled)
    for r, c in zip(rows, cols, strict=True):
        if finite[r, c % n_c]:
            out[r] = c % n_c
    return out
