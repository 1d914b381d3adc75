"""Predictors that need no learning, the yardsticks of a learned map predictor.

A predictor maps the team's three-state belief to ``p_free``, ``(H, W) float32``: the probability that each
cell is free (known cells keep their state: 1 free, 0 occupied; the wall probability of an unknown cell is
``1 - p_free``).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from mrexplore.types import CellState, StateGrid

__all__ = ["known_p_free", "predict_all_free", "predict_extended_walls", "extend_walls"]

MIN_WALL_M = 0.5
"""A straight run of occupied cells at least this long is a wall that may go on into unknown space."""
REACH_M = 5.0
"""How far a wall is extended into unknown space at most."""


def known_p_free(state: StateGrid) -> NDArray[np.float32]:
    """``p_free`` of the known cells (1 free, 0 occupied), NaN where unknown."""
    p = np.full(state.shape, np.nan, np.float32)
    p[state == CellState.FREE] = 1.0
    p[state == CellState.OCCUPIED] = 0.0
    return p


def predict_all_free(state: StateGrid, resolution_m: float) -> NDArray[np.float32]:
    """Every unknown cell free (what a planner assumes that reads the frontiers alone).

    Examples
    --------
    >>> F, O, U = CellState.FREE, CellState.OCCUPIED, CellState.UNKNOWN
    >>> predict_all_free(np.array([[F, O, U]], np.uint8), 0.1).tolist()
    [[1.0, 0.0, 1.0]]
    """
    p = known_p_free(state)
    p[np.isnan(p)] = 1.0
    return p


def _extend_lines(
    occupied: NDArray[np.bool_], unknown: NDArray[np.bool_], min_run: int, reach: int
) -> NDArray[np.bool_]:
    """Along each row: a run of at least ``min_run`` occupied cells whose next cell is unknown goes on through
    unknown cells, ``reach`` at most, until a known cell."""
    out = np.zeros_like(occupied)
    H, W = occupied.shape
    for r in range(H):
        row = occupied[r]
        if not row.any():
            continue
        edges = np.diff(np.concatenate([[0], row.astype(np.int8), [0]]))
        starts, ends = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)  # run [start, end)
        for s, e in zip(starts, ends, strict=True):
            if e - s < min_run:
                continue
            c = e  # east
            while c < W and c - e < reach and unknown[r, c]:
                out[r, c] = True
                c += 1
            c = s - 1  # west
            while c >= 0 and s - 1 - c < reach and unknown[r, c]:
                out[r, c] = True
                c -= 1
    return out


def extend_walls(
    state: StateGrid, resolution_m: float, min_wall_m: float = MIN_WALL_M, reach_m: float = REACH_M
) -> NDArray[np.bool_]:
    """``(H, W) bool`` unknown cells on the straight extension of a seen wall: a row or column run of occupied
    cells at least ``min_wall_m`` long, continued into unknown space for ``reach_m`` at most, up to the first
    known cell (rooms close: walls run straight on behind what was seen).

    Examples
    --------
    >>> F, O, U = CellState.FREE, CellState.OCCUPIED, CellState.UNKNOWN
    >>> g = np.array([[O, O, O, U, U, F],
    ...               [F, F, F, U, U, U]], np.uint8)
    >>> extend_walls(g, 1.0, min_wall_m=3, reach_m=5).astype(int).tolist()  # the wall goes on to the free cell
    [[0, 0, 0, 1, 1, 0], [0, 0, 0, 0, 0, 0]]
    """
    occupied, unknown = state == CellState.OCCUPIED, state == CellState.UNKNOWN
    min_run = max(2, math.ceil(min_wall_m / resolution_m - 1e-9))
    reach = max(1, round(reach_m / resolution_m))
    rows = _extend_lines(occupied, unknown, min_run, reach)
    cols = _extend_lines(occupied.T, unknown.T, min_run, reach).T
    return rows | cols


def predict_extended_walls(state: StateGrid, resolution_m: float) -> NDArray[np.float32]:
    """Unknown cells on a seen wall's straight extension are walls (:func:`extend_walls`), the others free."""
    p = predict_all_free(state, resolution_m)
    p[extend_walls(state, resolution_m)] = 0.0
    return p
