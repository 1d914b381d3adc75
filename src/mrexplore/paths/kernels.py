"""The numba kernels the distance modules share: the two-queue Dijkstra search with its target marks and
limits, the seeded search, the descent back to a seed, and the reusable per-grid searches.

With only two edge weights (1 for straight moves, sqrt(2) for diagonal ones), Dijkstra's priority queue
can be replaced by two FIFO queues, one per weight: keys pushed into each queue are the popped key plus a
constant, and popped keys never decrease, so each queue stays sorted and the smaller front is the global
minimum. Every cell is settled once: O(cells) instead of O(cells log cells). A cell enters each queue at
most once (a later push into the same queue would carry a larger key), so each queue needs one slot per
cell. The names are public inside the package: :mod:`~mrexplore.paths.distance_field`,
:mod:`~mrexplore.paths.far_field` and :mod:`~mrexplore.paths.portals` build on them.
"""

from __future__ import annotations

import math
import threading

import numba as nb
import numpy as np
from numpy.typing import NDArray

from mrexplore.maps.boxes import Box, mask_box
from mrexplore.types import BoolGrid

__all__ = [
    "MUST",
    "ANY",
    "BLOCKED",
    "NO_TARGETS",
    "Searches",
    "passable_crop",
    "descend_to_seed",
    "pairwise_kernel",
    "relax",
    "search_into",
    "seeded_search",
    "start_values",
    "two_queue_dijkstra",
    "unsettle",
]


MUST = np.uint8(1)
"""A search's target mark (:func:`search_into`): a cell the search must settle."""
ANY = np.uint8(2)
"""A search's target mark: one of the cells of which the search must settle the nearest."""

BLOCKED = np.float32(-1.0)
"""What a blocked cell holds during a search: ``nd < best[v]`` is then false for it, so one array
answers both "passable?" and "improved?" (one memory stream instead of two: faster on a large floor,
``benchmarks/fields.py``)."""


@nb.njit(cache=True, nogil=True)
def start_values(passable: np.ndarray) -> np.ndarray:  # pragma: no cover - numba
    """``passable`` flattened with a border of one blocked cell (neighbours never leave the array), as
    a search starts it: ``inf`` where passable, ``BLOCKED`` elsewhere."""
    H, W = passable.shape
    Wp = W + 2
    start = np.full((H + 2) * Wp, BLOCKED, dtype=np.float32)
    for r in range(H):
        for c in range(W):
            if passable[r, c]:
                start[(r + 1) * Wp + c + 1] = np.inf
    return start


@nb.njit(cache=True, nogil=True, inline="always")
def relax(
    best: np.ndarray, Wp: int, u: int, du: float | np.float32, q_node: np.ndarray, q_key: np.ndarray, t0: int, t1: int
) -> tuple[int, int]:  # pragma: no cover - numba
    """Relax the 8 neighbours of the settled padded cell ``u`` (at ``du``): straight moves (1) go to queue
    0, diagonal ones (sqrt 2) to queue 1, each queue's keys increasing as they are pushed. Returns the
    queues' new lengths."""
    zero = np.float32(0.0)
    b_up, b_down, b_left, b_right = best[u - Wp], best[u + Wp], best[u - 1], best[u + 1]
    nd = du + np.float32(1.0)
    for v, bv in ((u - Wp, b_up), (u + Wp, b_down), (u - 1, b_left), (u + 1, b_right)):
        if nd < bv:  # false for a blocked cell (BLOCKED) and for one already as near
            best[v] = nd
            q_node[0, t0] = v
            q_key[0, t0] = nd
            t0 += 1
    # A diagonal move needs both orthogonal cells it passes between (no corner cutting).
    up, down, left, right = b_up >= zero, b_down >= zero, b_left >= zero, b_right >= zero
    nd = du + np.float32(math.sqrt(2.0))
    ul, ur, dl, dr = up and left, up and right, down and left, down and right
    for v, ok in ((u - Wp - 1, ul), (u - Wp + 1, ur), (u + Wp - 1, dl), (u + Wp + 1, dr)):
        if ok and nd < best[v]:
            best[v] = nd
            q_node[1, t1] = v
            q_key[1, t1] = nd
            t1 += 1
    return t0, t1


@nb.njit(cache=True, nogil=True, inline="always")
def unsettle(
    best: np.ndarray, q_node: np.ndarray, h0: int, t0: int, h1: int, t1: int, bound: float | np.float32
) -> None:  # pragma: no cover - numba
    """A search that stops early: keys pop in order, so cells at ``bound`` or less are final; the cells still
    queued ``q_node[0, h0:t0]``, ``q_node[1, h1:t1]`` beyond it are not, and read ``inf``."""
    inf = np.float32(np.inf)
    for j in range(h0, t0):
        v = q_node[0, j]
        if best[v] > bound:
            best[v] = inf
    for j in range(h1, t1):
        v = q_node[1, j]
        if best[v] > bound:
            best[v] = inf


@nb.njit(cache=True, nogil=True)
def search_into(  # noqa: C901 - numba kernel
    best: np.ndarray,
    Wp: int,
    s: int,
    targets: np.ndarray,
    stop_early: bool,
    q_node: np.ndarray,
    q_key: np.ndarray,
    is_target: np.ndarray,
    limit: float = np.inf,
    n_must: int = -1,
) -> tuple[int, int]:  # pragma: no cover - numba
    """The search from passable padded cell ``s``, in place on ``best`` (a copy of the start values,
    :func:`start_values`, row length ``Wp``): finite distances where settled; blocked cells keep
    ``BLOCKED``. Returns the two queues' lengths: ``q_node[0, :t0]`` and ``q_node[1, :t1]`` hold every cell
    the search changed except ``s`` itself, so a caller can restore ``best`` without a pass over the grid.

    ``q_node``, ``q_key`` (``(2, passable cells + 1)``) and ``is_target`` (``uint8``, all 0, one per padded
    cell) are the caller's scratch, reused from search to search: allocating them afresh per search cost
    more in page faults than the search itself on a large floor. ``is_target`` is left all 0 again.

    ``limit``: the search ends at the first cell farther than it; cells within it are final (keys pop in
    order), farther ones read ``inf`` (a search that is read only within a radius).

    ``n_must`` (with ``stop_early``): only ``targets[:n_must]`` must all be settled; of ``targets[n_must:]``
    the nearest is enough. The search then ends once it has the musts and one of the others, and the others
    at that same distance are final too (every cell nearer was settled and relaxed before it). -1: every
    target must be settled.
    """
    inf = np.float32(np.inf)
    zero = np.float32(0.0)
    # Targets (padded flat indices): with stop_early, the search ends once every passable must is settled
    # and, where some of the others are passable, the first of them.
    remaining = 0
    waiting = False  # some "nearest of" target is passable and not settled yet
    if stop_early:
        musts = targets.shape[0] if n_must < 0 else n_must
        for j in range(musts):
            v = targets[j]
            if best[v] >= zero and (is_target[v] & MUST) == 0:
                is_target[v] |= MUST
                remaining += 1
        for j in range(musts, targets.shape[0]):
            v = targets[j]
            if best[v] >= zero:
                is_target[v] |= ANY
                waiting = True
    best[s] = 0.0
    h0 = t0 = h1 = t1 = 0
    if not (stop_early and remaining == 0 and not waiting):  # else nothing to reach
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
        if du > limit:
            best[u] = inf
            unsettle(best, q_node, h0, t0, h1, t1, limit)
            break
        if stop_early and is_target[u] != 0:
            if is_target[u] & MUST:
                remaining -= 1
            if is_target[u] & ANY:
                waiting = False
            is_target[u] = 0
            if remaining == 0 and not waiting:
                unsettle(best, q_node, h0, t0, h1, t1, du)
                break
        t0, t1 = relax(best, Wp, u, du, q_node, q_key, t0, t1)
    if stop_early:
        for v in targets:
            is_target[v] = 0  # targets never settled (unreachable) stay marked otherwise
    return t0, t1


@nb.njit(cache=True, nogil=True)
def two_queue_dijkstra(
    start: np.ndarray,
    Wp: int,
    s: int,
    targets: np.ndarray,
    stop_early: bool,
    q_node: np.ndarray,
    q_key: np.ndarray,
    is_target: np.ndarray,
    limit: float = np.inf,
    n_must: int = -1,
) -> np.ndarray:  # pragma: no cover - numba
    """Distances from padded cell ``s`` over the padded flat grid ``start`` (:func:`start_values`, row
    length ``Wp``); ``inf`` where unreachable or blocked, or farther than ``limit``. Scratch and ``n_must``
    as :func:`search_into`."""
    inf = np.float32(np.inf)
    best = start.copy()
    if best[s] < np.float32(0.0):
        best[:] = inf
        return best
    search_into(best, Wp, s, targets, stop_early, q_node, q_key, is_target, limit, n_must)
    for i in range(best.shape[0]):
        if best[i] < np.float32(0.0):
            best[i] = inf
    return best


@nb.njit(cache=True, nogil=True)
def pairwise_kernel(  # noqa: C901 - numba kernel
    start: np.ndarray,
    Wp: int,
    points: np.ndarray,
    rows: np.ndarray,
    q_node: np.ndarray,
    q_key: np.ndarray,
    is_target: np.ndarray,
) -> np.ndarray:  # pragma: no cover - numba
    """``(m, m) float64``: each row i of ``rows`` holds the distances from padded cell ``points[i]`` to the
    later points, each search stopped once it has reached them; ``inf`` elsewhere. One array serves every
    search and is restored from the queues after each (:func:`search_into`): a copy of the grid and a pass
    over it per search, and a thread hand-off per row, cost more than the short searches between a
    cluster's candidates.

    A search that runs out before reaching its targets has settled its source's whole component: every
    point it reached is labelled with it, and later searches leave out the points of other components,
    which they could not reach either. In a route's box late on a KTH floor the candidates often lie in
    several pieces of free space (joined only outside the box), and each search from the first piece
    used to search all of it again for the points of the others."""
    m = points.shape[0]
    out = np.full((m, m), np.inf)
    best = start.copy()
    zero = np.float32(0.0)
    inf = np.float32(np.inf)
    label = np.full(m, -1, dtype=np.int64)  # each point's component, named by the search that settled it all
    chosen = np.empty(m, dtype=np.int64)
    for i in rows:
        if i >= m - 1:
            continue
        s = points[i]
        if start[s] < zero:
            continue
        # The later points that may share i's component: those of its own (all of them reachable), or,
        # where i lies in no settled component, those in none either.
        k = 0
        for j in range(i + 1, m):
            if label[j] == label[i]:
                chosen[k] = points[j]
                k += 1
        if k == 0:
            continue
        t0, t1 = search_into(best, Wp, s, chosen[:k], True, q_node, q_key, is_target, np.inf)
        for j in range(i + 1, m):
            d = best[points[j]]
            if d >= zero:  # blocked targets keep BLOCKED
                out[i, j] = d
        ran_out = False
        for j in range(k):
            if start[chosen[j]] >= zero and best[chosen[j]] == inf:
                ran_out = True
        if ran_out:
            for j in range(m):
                d = best[points[j]]
                if d >= zero and d < inf:
                    label[j] = i
        best[s] = start[s]
        for j in range(t0):
            best[q_node[0, j]] = start[q_node[0, j]]
        for j in range(t1):
            best[q_node[1, j]] = start[q_node[1, j]]
    return out


NO_TARGETS = np.zeros(0, dtype=np.int64)


@nb.njit(cache=True, nogil=True)
def seeded_search(
    start: np.ndarray, Wp: int, seeds: np.ndarray, seed_keys: np.ndarray, q_node: np.ndarray, q_key: np.ndarray
) -> np.ndarray:  # pragma: no cover - numba
    """Distances over the padded flat grid ``start`` (:func:`start_values`, row length ``Wp``) from many
    sources, each with its own starting distance: ``seeds`` (padded flat indices) sorted by ``seed_keys``.

    The two-queue search of :mod:`~mrexplore.paths.distance_field` with a third queue, the seeds: all three
    stay sorted (the seeds from the start, the others because keys pop in order), so the smallest of the
    three fronts is the global minimum and the result is Dijkstra's. ``inf`` where unreachable or blocked.
    """
    inf = np.float32(np.inf)
    zero = np.float32(0.0)
    best = start.copy()
    ns = seeds.shape[0]
    for j in range(ns):
        s = seeds[j]
        if best[s] >= zero and seed_keys[j] < best[s]:
            best[s] = seed_keys[j]
    hs = h0 = t0 = h1 = t1 = 0
    while hs < ns or h0 < t0 or h1 < t1:
        which = -1
        du = inf
        if hs < ns:
            which, du = 2, seed_keys[hs]
        if h0 < t0 and (which < 0 or q_key[0, h0] < du):
            which, du = 0, q_key[0, h0]
        if h1 < t1 and (which < 0 or q_key[1, h1] < du):
            which, du = 1, q_key[1, h1]
        if which == 2:
            u = seeds[hs]
            hs += 1
        elif which == 0:
            u = q_node[0, h0]
            h0 += 1
        else:
            u = q_node[1, h1]
            h1 += 1
        if best[u] < zero or du > best[u]:
            continue  # blocked seed, or stale: settled with a smaller key
        t0, t1 = relax(best, Wp, u, du, q_node, q_key, t0, t1)
    for i in range(best.shape[0]):
        if best[i] < zero:
            best[i] = inf
    return best


@nb.njit(cache=True, nogil=True)
def descend_to_seed(
    field: np.ndarray, passable: np.ndarray, seed_key: np.ndarray, gr: int, gc: int
) -> np.ndarray:  # pragma: no cover - numba
    """Blocks from ``(gr, gc)`` down ``field`` to the first block whose value its seed explains
    (``seed_key``, ``inf`` for blocks that are no seed); ``(k, 2) int32``, the goal's block first; empty
    when the goal's block is unreachable."""
    H, W = field.shape
    out = np.empty((H * W, 2), dtype=np.int32)
    if not np.isfinite(field[gr, gc]):
        return out[:0]
    r, c, n = gr, gc, 0
    while True:
        out[n, 0] = r
        out[n, 1] = c
        n += 1
        here = field[r, c]
        if seed_key[r, c] <= here + 1e-4 or n >= H * W:
            break
        br, bc, best = -1, -1, here
        for dr in range(-1, 2):
            for dc in range(-1, 2):
                if dr == 0 and dc == 0:
                    continue
                rr, cc = r + dr, c + dc
                if rr < 0 or rr >= H or cc < 0 or cc >= W or not passable[rr, cc]:
                    continue
                step = 1.0
                if dr != 0 and dc != 0:
                    if not passable[r, cc] or not passable[rr, c]:
                        continue
                    step = math.sqrt(2.0)
                if field[rr, cc] + step <= here + 1e-4 and field[rr, cc] < best:
                    br, bc, best = rr, cc, field[rr, cc]
        if br < 0:
            break
        r, c = br, bc
    return out[:n].copy()


class Searches:
    """Searches from many sources over one grid: its padded start values built once, each thread's queues and
    target marks allocated once and reused (:func:`two_queue_dijkstra`)."""

    def __init__(self, passable: np.ndarray, targets: NDArray[np.int64] | None = None) -> None:
        self.h, self.w = int(passable.shape[0]), int(passable.shape[1])
        self.wp = self.w + 2
        self.start = start_values(np.ascontiguousarray(passable))
        self.cap = int(np.count_nonzero(passable)) + 1
        if targets is None:
            self.targets, self.stop_early = NO_TARGETS, False
        else:
            self.targets = self.padded(targets)
            self.stop_early = True
        self._scratch = threading.local()

    def scratch(self) -> tuple[NDArray[np.int32], NDArray[np.float32], NDArray[np.uint8]]:
        """This thread's queues and target marks (:func:`search_into`), allocated on first use."""
        arrays = getattr(self._scratch, "arrays", None)
        if arrays is None:
            arrays = (
                np.empty((2, self.cap), dtype=np.int32),
                np.empty((2, self.cap), dtype=np.float32),
                np.zeros(self.start.shape[0], dtype=np.uint8),
            )
            self._scratch.arrays = arrays
        return arrays

    def padded(self, flat: NDArray[np.int64]) -> NDArray[np.int64]:
        """Flat indices of the grid as flat indices of the padded grid."""
        return (flat // self.w + 1) * self.wp + flat % self.w + 1

    def __call__(
        self, r: int, c: int, targets: NDArray[np.int64] | None = None, limit: float = math.inf, n_must: int = -1
    ) -> NDArray[np.float32]:
        """``(h, w) float32`` distances from cell ``(r, c)`` of the grid (a view without the padding);
        ``targets`` (padded flat indices, :meth:`padded`), where given, replace the grid's for this search,
        ``n_must`` as :func:`search_into`; cells farther than ``limit`` read ``inf``."""
        scratch = self.scratch()
        s = (r + 1) * self.wp + c + 1
        if targets is None:
            best = two_queue_dijkstra(self.start, self.wp, s, self.targets, self.stop_early, *scratch, limit)
        else:
            best = two_queue_dijkstra(self.start, self.wp, s, targets, True, *scratch, limit, n_must)
        return best.reshape((self.h + 2, self.wp))[1:-1, 1:-1]


def passable_crop(passable: BoolGrid, box: Box | None = None) -> tuple[np.ndarray, int, int] | None:
    """The passable cells' bounding box (``box`` where the caller has it) as a contiguous crop, with its
    first row and column; None when nothing is passable."""
    box = mask_box(passable) if box is None else box
    if box is None:
        return None
    r0, r1, c0, c1 = box
    return np.ascontiguousarray(passable[r0:r1, c0:c1]), r0, c0
