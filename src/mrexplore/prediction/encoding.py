"""The team's belief as the map predictor's input, and its prediction back on the planning grid: the belief
pooled onto the predictor's cells (three channels, the share of free, occupied and unknown planning cells
under each), the box of the known cells, and the grid of free probabilities that keeps what is known."""

from __future__ import annotations

import math

import numba as nb
import numpy as np
from numpy.typing import NDArray

from mrexplore.types import CellState, StateGrid

__all__ = ["IN_CHANNELS", "POOL_LEVELS", "pool_factor", "belief_channels", "known_box", "fill_p_free"]

POOL_LEVELS = 2
"""Max-pooling levels of the U-Net: the predictor's grid is padded to a multiple of ``2 ** POOL_LEVELS``."""
IN_CHANNELS = 3
"""Share of free, occupied and unknown planning cells under each predictor cell."""


def pool_factor(resolution_m: float, cell_m: float) -> int:
    """Planning cells per predictor cell along a side: ``cell_m / resolution_m`` rounded, at least 1.

    Examples
    --------
    >>> pool_factor(0.1, 0.2), pool_factor(0.05, 0.2), pool_factor(0.25, 0.2)
    (2, 4, 1)
    """
    return max(1, round(cell_m / resolution_m))


def belief_channels(state: StateGrid, factor: int) -> NDArray[np.float32]:
    """``(3, h, w) float32``: the share of free, occupied and unknown cells of ``state`` in each
    ``factor x factor`` block; the grid is padded with unknown cells at its bottom and right to a multiple of
    ``factor * 2 ** POOL_LEVELS``.

    Examples
    --------
    >>> F, O, U = CellState.FREE, CellState.OCCUPIED, CellState.UNKNOWN
    >>> x = belief_channels(np.array([[F, O], [F, U]], np.uint8), 2)
    >>> x.shape, x[:, 0, 0].tolist(), x[:, 0, 1].tolist()  # one block of 2 x 2, then padding
    ((3, 4, 4), [0.5, 0.25, 0.25], [0.0, 0.0, 1.0])
    """
    H, W = state.shape
    step = factor * 2**POOL_LEVELS
    Hp, Wp = math.ceil(H / step) * step, math.ceil(W / step) * step
    counts = _block_counts(np.ascontiguousarray(state, np.uint8), factor, Hp // factor, Wp // factor)
    return (counts / float(factor * factor)).astype(np.float32)


_UNKNOWN = int(CellState.UNKNOWN)
_OCCUPIED = int(CellState.OCCUPIED)


@nb.njit(cache=True, nogil=True)
def _block_counts(state: np.ndarray, factor: int, h: int, w: int) -> np.ndarray:  # pragma: no cover - numba
    """``(3, h, w) float64``: free, occupied and unknown cells of each ``factor x factor`` block, the cells
    beyond ``state`` counted unknown, in one pass over the grid."""
    out = np.zeros((3, h, w))
    out[2] = factor * factor
    for r in range(state.shape[0]):
        for c in range(state.shape[1]):
            s = state[r, c]  # the channel is the state's value: free 0, occupied 1, unknown 2
            if s != _UNKNOWN:
                out[s, r // factor, c // factor] += 1.0
                out[2, r // factor, c // factor] -= 1.0
    return out


@nb.njit(cache=True, nogil=True)
def known_box(state: np.ndarray) -> tuple[int, int, int, int]:  # pragma: no cover - numba
    """First and last row, first and last column holding a known cell (``(H, -1, W, -1)`` when none does)."""
    H, W = state.shape
    rmin, rmax, cmin, cmax = H, -1, W, -1
    for r in range(H):
        for c in range(W):
            if state[r, c] != _UNKNOWN:
                rmin, rmax = min(rmin, r), max(rmax, r)
                cmin, cmax = min(cmin, c), max(cmax, c)
    return rmin, rmax, cmin, cmax


@nb.njit(cache=True, nogil=True)
def fill_p_free(
    state: np.ndarray, p: np.ndarray, factor: int, r0: int, c0: int, r1: int, c1: int
) -> np.ndarray:  # pragma: no cover - numba
    """``(H, W) float32``: 1 on free cells, 0 on occupied ones, on unknown cells inside rows ``r0:r1`` and
    columns ``c0:c1`` the probability ``p`` of the predictor cell over them (``p[0, 0]`` over ``(r0, c0)``),
    1 on unknown cells outside."""
    H, W = state.shape
    out = np.empty((H, W), np.float32)
    for r in range(H):  # known cells, and unknown ones outside the box (1)
        for c in range(W):
            out[r, c] = 0.0 if state[r, c] == _OCCUPIED else 1.0
    row = np.empty(c1 - c0, np.float32)
    for r in range(r0, r1):
        if (r - r0) % factor == 0:  # the box's row of p, each cell repeated ``factor`` times
            pr = (r - r0) // factor
            for c in range(c1 - c0):
                row[c] = p[pr, c // factor]
        srow, orow = state[r, c0:c1], out[r, c0:c1]
        for c in range(c1 - c0):
            if srow[c] == _UNKNOWN:
                orow[c] = row[c]
    return out
