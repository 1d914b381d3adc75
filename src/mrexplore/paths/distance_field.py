"""Geodesic distance fields on a grid (8-connected, no corner cutting), exact, in linear time (numba).

With only two edge weights (1 for straight moves, sqrt(2) for diagonal ones), Dijkstra's priority queue
can be replaced by two FIFO queues, one per weight: keys pushed into each queue are the popped key plus a
constant, and popped keys never decrease, so each queue stays sorted and the smaller front is the global
minimum. Every cell is settled once: O(cells) instead of O(cells log cells). A cell enters each queue at
most once (a later push into the same queue would carry a larger key), so each queue needs one slot per
cell.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np
from numpy.typing import NDArray

from mrexplore.boxes import mask_box
from mrexplore.paths.moves import DC, DR, move_cost
from mrexplore.threads import map_threads
from mrexplore.types import BoolGrid, GridRC

__all__ = ["distance_field", "distance_fields", "distance_matrix", "distances_at", "descend_path"]


@nb.njit(cache=True, nogil=True)
def _two_queue_dijkstra(passable: np.ndarray, sr: int, sc: int) -> np.ndarray:  # pragma: no cover - numba
    H, W = passable.shape
    # Work on a copy padded by one blocked cell: neighbours never leave the array, no bounds checks.
    Wp = W + 2
    n = (H + 2) * Wp
    free = np.zeros(n, dtype=np.bool_)
    for r in range(H):
        for c in range(W):
            free[(r + 1) * Wp + c + 1] = passable[r, c]
    best = np.full(n, np.inf, dtype=np.float32)
    out = np.full((H, W), np.inf, dtype=np.float32)
    s = (sr + 1) * Wp + sc + 1
    if not free[s]:
        return out
    straight = np.array([-Wp, Wp, -1, 1], dtype=np.int64)
    diag = np.array([-Wp - 1, -Wp + 1, Wp - 1, Wp + 1], dtype=np.int64)
    # The two orthogonal cells a diagonal move passes between (no corner cutting).
    side_a = np.array([-1, 1, -1, 1], dtype=np.int64)
    side_b = np.array([-Wp, -Wp, Wp, Wp], dtype=np.int64)
    q_node = np.empty((2, H * W + 1), dtype=np.int64)
    q_key = np.empty((2, H * W + 1), dtype=np.float32)
    h0 = t0 = h1 = t1 = 0
    sqrt2 = np.float32(math.sqrt(2.0))
    one = np.float32(1.0)
    best[s] = 0.0
    q_node[0, 0] = s
    q_key[0, 0] = 0.0
    t0 = 1
    while h0 < t0 or h1 < t1:
        if h1 >= t1 or (h0 < t0 and q_key[0, h0] <= q_key[1, h1]):
            u = q_node[0, h0]
            du = q_key[0, h0]
            h0 += 1
        else:
            u = q_node[1, h1]
            du = q_key[1, h1]
            h1 += 1
        if du > best[u]:
            continue  # stale: u was settled with a smaller key
        nd = du + one
        for k in range(4):
            v = u + straight[k]
            if free[v] and nd < best[v]:
                best[v] = nd
                q_node[0, t0] = v
                q_key[0, t0] = nd
                t0 += 1
        nd = du + sqrt2
        for k in range(4):
            v = u + diag[k]
            if free[v] and nd < best[v] and free[u + side_a[k]] and free[u + side_b[k]]:
                best[v] = nd
                q_node[1, t1] = v
                q_key[1, t1] = nd
                t1 += 1
    for r in range(H):
        for c in range(W):
            out[r, c] = best[(r + 1) * Wp + c + 1]
    return out


def distance_field(passable: BoolGrid, source_rc: GridRC) -> NDArray[np.float32]:
    """Shortest 8-connected path length, in cells, from ``source_rc`` to every cell.

    Parameters
    ----------
    passable:
        ``(H, W) bool``; True where a robot may drive.
    source_rc:
        Start cell ``(row, col)``.

    Returns
    -------
    ``(H, W) float32``: path length in cells (straight 1, diagonal sqrt(2)); ``inf`` where unreachable.
    All ``inf`` when the source is not passable.

    Examples
    --------
    >>> g = np.ones((5, 5), bool); g[1:4, 2] = False
    >>> d = distance_field(g, (2, 0))
    >>> float(d[2, 4])  # around the wall: 2 diagonals up, 2 straight, 2 diagonals down... shortest is 4 + 2*sqrt(2)
    6.828427...
    """
    if passable.dtype != np.bool_:
        passable = passable.astype(bool)
    return _two_queue_dijkstra(np.ascontiguousarray(passable), int(source_rc[0]), int(source_rc[1]))


def _crop(passable: BoolGrid) -> tuple[np.ndarray, int, int] | None:
    """The passable cells' bounding box as a contiguous crop, with its first row and column; None when
    nothing is passable."""
    box = mask_box(passable)
    if box is None:
        return None
    r0, r1, c0, c1 = box
    return np.ascontiguousarray(passable[r0:r1, c0:c1]), r0, c0


def distance_fields(passable: BoolGrid, sources_rc: NDArray[np.integer]) -> list[NDArray[np.float32]]:
    """One :func:`distance_field` per source, computed on the passable bounding box, on the shared threads.

    Returns
    -------
    One ``(H, W) float32`` field per row of ``sources_rc`` (``(n, 2) int``).
    """
    if passable.dtype != np.bool_:
        passable = passable.astype(bool)
    cropped = _crop(passable)
    if cropped is None:
        return [np.full(passable.shape, np.inf, dtype=np.float32) for _ in range(len(sources_rc))]
    crop, r0, c0 = cropped
    r1, c1 = r0 + crop.shape[0], c0 + crop.shape[1]

    def one(src: NDArray[np.integer]) -> NDArray[np.float32]:
        out = np.full(passable.shape, np.inf, dtype=np.float32)
        r, c = int(src[0]) - r0, int(src[1]) - c0
        if 0 <= r < crop.shape[0] and 0 <= c < crop.shape[1]:
            out[r0:r1, c0:c1] = _two_queue_dijkstra(crop, r, c)
        return out

    return map_threads(one, list(sources_rc))  # the kernel releases the GIL


def distance_matrix(
    passable: BoolGrid, sources_rc: NDArray[np.integer], targets_rc: NDArray[np.integer]
) -> NDArray[np.float64]:
    """Geodesic distances from every source to every target, ``(n_sources, n_targets) float64`` in cells
    (``inf`` where unreachable): :func:`distance_fields` read at the targets, without building a whole-map
    field per source (on a large map, filling those cost more than the searches).

    Examples
    --------
    >>> g = np.ones((3, 3), bool); g[1, 1] = False
    >>> distance_matrix(g, np.array([[0, 0]]), np.array([[0, 2], [2, 2], [1, 1]])).tolist()
    [[2.0, 4.0, inf]]
    """
    if passable.dtype != np.bool_:
        passable = passable.astype(bool)
    sources = np.asarray(sources_rc, dtype=np.int64).reshape(-1, 2)
    targets = np.asarray(targets_rc, dtype=np.int64).reshape(-1, 2)
    out = np.full((len(sources), len(targets)), np.inf)
    cropped = _crop(passable)
    if cropped is None or len(targets) == 0:
        return out
    crop, r0, c0 = cropped
    tr, tc = targets[:, 0] - r0, targets[:, 1] - c0
    inside = (tr >= 0) & (tr < crop.shape[0]) & (tc >= 0) & (tc < crop.shape[1])

    def row(src: NDArray[np.int64]) -> NDArray[np.float64]:
        d = np.full(len(targets), np.inf)
        r, c = int(src[0]) - r0, int(src[1]) - c0
        if 0 <= r < crop.shape[0] and 0 <= c < crop.shape[1]:
            d[inside] = _two_queue_dijkstra(crop, r, c)[tr[inside], tc[inside]]
        return d

    rows = map_threads(row, list(sources))
    if rows:
        out[:] = np.stack(rows)
    return out


@nb.njit(cache=True, nogil=True)
def _descend(field: np.ndarray, passable: np.ndarray, gr: int, gc: int) -> np.ndarray:  # pragma: no cover
    H, W = field.shape
    if not np.isfinite(field[gr, gc]):
        return np.zeros((0, 2), dtype=np.int32)
    n = 1
    cap = H * W
    out = np.empty((cap, 2), dtype=np.int32)
    out[0, 0] = gr
    out[0, 1] = gc
    r = gr
    c = gc
    while field[r, c] > 0.0 and n < cap:
        best = field[r, c]
        br = -1
        bc = -1
        for d in range(8):
            step = move_cost(passable, r, c, d)
            if step < 0:
                continue
            rr = r + DR[d]
            cc = c + DC[d]
            # Follow a neighbour whose distance plus the move explains ours: it lies on a shortest path.
            if field[rr, cc] + step <= field[r, c] + 1e-4 and field[rr, cc] < best:
                best = field[rr, cc]
                br = rr
                bc = cc
        if br < 0:
            return np.zeros((0, 2), dtype=np.int32)
        r = br
        c = bc
        out[n, 0] = r
        out[n, 1] = c
        n += 1
    return out[:n][::-1].copy()


def descend_path(field: NDArray[np.float32], passable: BoolGrid, goal_rc: GridRC) -> NDArray[np.int32]:
    """Shortest path from a field's source to ``goal_rc``, read off the field (no search).

    Returns
    -------
    ``(k, 2) int32`` cells from the source to the goal inclusive; ``(0, 2)`` if the goal is unreachable.

    Examples
    --------
    >>> g = np.ones((3, 4), bool); g[0:2, 1] = False  # both diagonals around it would cut its corner
    >>> descend_path(distance_field(g, (0, 0)), g, (0, 2)).tolist()
    [[0, 0], [1, 0], [2, 0], [2, 1], [2, 2], [1, 2], [0, 2]]
    """
    return _descend(field, np.ascontiguousarray(passable, dtype=bool), int(goal_rc[0]), int(goal_rc[1]))


def distances_at(field: NDArray[np.float32], cells_rc: NDArray[np.integer]) -> NDArray[np.float64]:
    """Look up a field at ``(k, 2) int`` cells: ``(k,) float64`` distances in cells."""
    if len(cells_rc) == 0:
        return np.zeros(0, dtype=np.float64)
    return field[cells_rc[:, 0], cells_rc[:, 1]].astype(np.float64)
