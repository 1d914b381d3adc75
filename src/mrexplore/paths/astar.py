"""A* shortest path on a grid (8-connected, no corner cutting, octile heuristic), in numba."""

from __future__ import annotations

import math

import numba as nb
import numpy as np
from numpy.typing import NDArray

from mrexplore.paths.moves import DC, DR, move_cost
from mrexplore.types import BoolGrid, GridRC

__all__ = ["astar_path", "path_length_cells"]


@nb.njit(cache=True, inline="always")
def _octile(r: int, c: int, gr: int, gc: int) -> float:  # pragma: no cover - numba
    dr = abs(r - gr)
    dc = abs(c - gc)
    return max(dr, dc) + (math.sqrt(2.0) - 1.0) * min(dr, dc)


@nb.njit(cache=True)
def _heap_push(keys: np.ndarray, vals: np.ndarray, size: int, key: float, val: int) -> int:  # pragma: no cover
    i = size
    keys[i] = key
    vals[i] = val
    while i > 0:
        p = (i - 1) >> 1
        if keys[p] <= keys[i]:
            break
        keys[p], keys[i] = keys[i], keys[p]
        vals[p], vals[i] = vals[i], vals[p]
        i = p
    return size + 1


@nb.njit(cache=True)
def _heap_pop(keys: np.ndarray, vals: np.ndarray, size: int) -> int:  # pragma: no cover - numba
    size -= 1
    keys[0] = keys[size]
    vals[0] = vals[size]
    i = 0
    while True:
        left = 2 * i + 1
        if left >= size:
            break
        m = left
        if left + 1 < size and keys[left + 1] < keys[left]:
            m = left + 1
        if keys[i] <= keys[m]:
            break
        keys[m], keys[i] = keys[i], keys[m]
        vals[m], vals[i] = vals[i], vals[m]
        i = m
    return size


@nb.njit(cache=True, nogil=True)
def _astar(passable: np.ndarray, sr: int, sc: int, gr: int, gc: int) -> np.ndarray:  # pragma: no cover
    H, W = passable.shape
    empty = np.zeros((0, 2), dtype=np.int32)
    if not passable[sr, sc] or not passable[gr, gc]:
        return empty
    n = H * W
    g = np.full(n, np.inf, dtype=np.float64)
    parent = np.full(n, -1, dtype=np.int32)
    closed = np.zeros(n, dtype=np.bool_)
    cap = 8 * n + 1
    keys = np.empty(cap, dtype=np.float64)
    vals = np.empty(cap, dtype=np.int32)
    s = sr * W + sc
    goal = gr * W + gc
    g[s] = 0.0
    size = _heap_push(keys, vals, 0, _octile(sr, sc, gr, gc), s)
    found = False
    while size > 0:
        u = vals[0]
        size = _heap_pop(keys, vals, size)
        if closed[u]:
            continue
        closed[u] = True
        if u == goal:
            found = True
            break
        r = u // W
        c = u - r * W
        for d in range(8):
            step = move_cost(passable, r, c, d)
            if step < 0:
                continue
            rr = r + DR[d]
            cc = c + DC[d]
            v = rr * W + cc
            nd = g[u] + step
            if nd < g[v] - 1e-12:
                g[v] = nd
                parent[v] = u
                size = _heap_push(keys, vals, size, nd + _octile(rr, cc, gr, gc), v)
    if not found:
        return empty
    count = 1
    v = goal
    while v != s:
        v = parent[v]
        count += 1
    out = np.empty((count, 2), dtype=np.int32)
    v = goal
    for i in range(count - 1, -1, -1):
        out[i, 0] = v // W
        out[i, 1] = v - (v // W) * W
        if i > 0:
            v = parent[v]
    return out


def astar_path(passable: BoolGrid, start_rc: GridRC, goal_rc: GridRC) -> NDArray[np.int32]:
    """Shortest path from ``start_rc`` to ``goal_rc`` over passable cells.

    Returns
    -------
    ``(k, 2) int32`` cells from start to goal inclusive; ``(0, 2)`` when the goal is unreachable.

    Examples
    --------
    >>> g = np.ones((3, 3), bool); g[1, 1] = False
    >>> astar_path(g, (0, 0), (2, 2)).tolist()[0], len(astar_path(g, (0, 0), (2, 2)))
    ([0, 0], 5)
    """
    if passable.dtype != np.bool_:
        passable = passable.astype(bool)
    return _astar(np.ascontiguousarray(passable), int(start_rc[0]), int(start_rc[1]), int(goal_rc[0]), int(goal_rc[1]))


def path_length_cells(path_rc: NDArray[np.integer]) -> float:
    """Length of a cell path in cells (straight 1, diagonal sqrt(2))."""
    if len(path_rc) < 2:
        return 0.0
    steps = np.abs(np.diff(path_rc.astype(np.int64), axis=0))
    diag = (steps[:, 0] == 1) & (steps[:, 1] == 1)
    return float(np.count_nonzero(~diag) + math.sqrt(2.0) * np.count_nonzero(diag))
