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
import threading
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Protocol

import numba as nb
import numpy as np
from numpy.typing import NDArray

from mrexplore.boxes import Box, mask_box
from mrexplore.paths.moves import DC, DR, move_cost
from mrexplore.threads import map_threads, thread_count
from mrexplore.types import BoolGrid, GridRC

__all__ = [
    "Field",
    "FieldLike",
    "DistanceLookup",
    "Distances",
    "distance_field",
    "distance_fields",
    "nearest_fields",
    "distance_matrix",
    "pairwise_distances",
    "distances_at",
    "descend_path",
]


@dataclass(frozen=True)
class Field:
    """A distance field kept on the box it was computed on (the passable cells' bounding box): filling a
    whole-map array per robot cost more than the searches on a large floor at 0.05 m.

    ``values`` covers rows ``r0 : r0 + h`` and columns ``c0 : c0 + w`` of a grid of ``shape``; every cell
    outside the box is unreachable (``inf``).

    Examples
    --------
    >>> f = Field(np.array([[0.0, 1.0]], np.float32), 2, 3, (4, 6))
    >>> f.at(np.array([[2, 4], [0, 0]])).tolist(), f.value(2, 3)
    ([1.0, inf], 0.0)
    """

    values: NDArray[np.float32]
    r0: int
    c0: int
    shape: tuple[int, int]

    @classmethod
    def whole(cls, values: NDArray[np.float32]) -> Field:
        """A field that covers its whole grid."""
        return cls(values, 0, 0, (int(values.shape[0]), int(values.shape[1])))

    def at(self, cells_rc: NDArray[np.integer]) -> NDArray[np.float64]:
        """The field at ``(k, 2) int`` cells: ``(k,) float64`` distances in cells (``inf`` off the box)."""
        cells = np.asarray(cells_rc).reshape(-1, 2)
        r = cells[:, 0] - self.r0
        c = cells[:, 1] - self.c0
        h, w = self.values.shape
        inside = (r >= 0) & (r < h) & (c >= 0) & (c < w)
        if inside.all():
            return self.values[r, c].astype(np.float64)
        out = np.full(len(cells), np.inf)
        out[inside] = self.values[r[inside], c[inside]]
        return out

    def value(self, r: int, c: int) -> float:
        """The field at one cell."""
        rr, cc = int(r) - self.r0, int(c) - self.c0
        if 0 <= rr < self.values.shape[0] and 0 <= cc < self.values.shape[1]:
            return float(self.values[rr, cc])
        return math.inf

    def full(self) -> NDArray[np.float32]:
        """The field as a whole-grid ``(H, W) float32`` array."""
        out = np.full(self.shape, np.inf, dtype=np.float32)
        h, w = self.values.shape
        out[self.r0 : self.r0 + h, self.c0 : self.c0 + w] = self.values
        return out


FieldLike = Field | NDArray[np.float32]
"""A :class:`Field` or a whole-grid ``(H, W) float32`` array."""


class DistanceLookup(Protocol):
    """What reads distances from one source at cells: a :class:`Field`, or a
    :class:`~mrexplore.paths.far_field.NearFarField` whose far values are estimates."""

    def at(self, cells_rc: NDArray[np.integer]) -> NDArray[np.float64]: ...

    def value(self, r: int, c: int) -> float: ...


Distances = DistanceLookup | NDArray[np.float32]
"""A :class:`DistanceLookup` or a whole-grid ``(H, W) float32`` array (:func:`distances_at` reads both)."""


def _as_field(field: FieldLike) -> Field:
    return field if isinstance(field, Field) else Field.whole(field)


_MUST = np.uint8(1)
"""A search's target mark (:func:`_search_into`): a cell the search must settle."""
_ANY = np.uint8(2)
"""A search's target mark: one of the cells of which the search must settle the nearest."""

_BLOCKED = np.float32(-1.0)
"""What a blocked cell holds during a search: ``nd < best[v]`` is then false for it, so one array
answers both "passable?" and "improved?" (one memory stream instead of two: 1.4x faster on a large
floor, ``perf/bench_fields.py``)."""


@nb.njit(cache=True, nogil=True)
def _start_values(passable: np.ndarray) -> np.ndarray:  # pragma: no cover - numba
    """``passable`` flattened with a border of one blocked cell (neighbours never leave the array), as
    a search starts it: ``inf`` where passable, ``_BLOCKED`` elsewhere."""
    H, W = passable.shape
    Wp = W + 2
    start = np.full((H + 2) * Wp, _BLOCKED, dtype=np.float32)
    for r in range(H):
        for c in range(W):
            if passable[r, c]:
                start[(r + 1) * Wp + c + 1] = np.inf
    return start


@nb.njit(cache=True, nogil=True, inline="always")
def _relax(
    best: np.ndarray, Wp: int, u: int, du: float | np.float32, q_node: np.ndarray, q_key: np.ndarray, t0: int, t1: int
) -> tuple[int, int]:  # pragma: no cover - numba
    """Relax the 8 neighbours of the settled padded cell ``u`` (at ``du``): straight moves (1) go to queue
    0, diagonal ones (sqrt 2) to queue 1, each queue's keys increasing as they are pushed. Returns the
    queues' new lengths."""
    zero = np.float32(0.0)
    b_up, b_down, b_left, b_right = best[u - Wp], best[u + Wp], best[u - 1], best[u + 1]
    nd = du + np.float32(1.0)
    for v, bv in ((u - Wp, b_up), (u + Wp, b_down), (u - 1, b_left), (u + 1, b_right)):
        if nd < bv:  # false for a blocked cell (_BLOCKED) and for one already as near
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
def _unsettle(
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
def _search_into(
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
    :func:`_start_values`, row length ``Wp``): finite distances where settled; blocked cells keep
    ``_BLOCKED``. Returns the two queues' lengths: ``q_node[0, :t0]`` and ``q_node[1, :t1]`` hold every cell
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
            if best[v] >= zero and (is_target[v] & _MUST) == 0:
                is_target[v] |= _MUST
                remaining += 1
        for j in range(musts, targets.shape[0]):
            v = targets[j]
            if best[v] >= zero:
                is_target[v] |= _ANY
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
            _unsettle(best, q_node, h0, t0, h1, t1, limit)
            break
        if stop_early and is_target[u] != 0:
            if is_target[u] & _MUST:
                remaining -= 1
            if is_target[u] & _ANY:
                waiting = False
            is_target[u] = 0
            if remaining == 0 and not waiting:
                _unsettle(best, q_node, h0, t0, h1, t1, du)
                break
        t0, t1 = _relax(best, Wp, u, du, q_node, q_key, t0, t1)
    if stop_early:
        for v in targets:
            is_target[v] = 0  # targets never settled (unreachable) stay marked otherwise
    return t0, t1


@nb.njit(cache=True, nogil=True)
def _two_queue_dijkstra(
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
    """Distances from padded cell ``s`` over the padded flat grid ``start`` (:func:`_start_values`, row
    length ``Wp``); ``inf`` where unreachable or blocked, or farther than ``limit``. Scratch and ``n_must``
    as :func:`_search_into`."""
    inf = np.float32(np.inf)
    best = start.copy()
    if best[s] < np.float32(0.0):
        best[:] = inf
        return best
    _search_into(best, Wp, s, targets, stop_early, q_node, q_key, is_target, limit, n_must)
    for i in range(best.shape[0]):
        if best[i] < np.float32(0.0):
            best[i] = inf
    return best


@nb.njit(cache=True, nogil=True)
def _pairwise_kernel(
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
    search and is restored from the queues after each (:func:`_search_into`): a copy of the grid and a pass
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
        t0, t1 = _search_into(best, Wp, s, chosen[:k], True, q_node, q_key, is_target, np.inf)
        for j in range(i + 1, m):
            d = best[points[j]]
            if d >= zero:  # blocked targets keep _BLOCKED
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


_NO_TARGETS = np.zeros(0, dtype=np.int64)


@nb.njit(cache=True, nogil=True)
def _seeded_search(
    start: np.ndarray, Wp: int, seeds: np.ndarray, seed_keys: np.ndarray, q_node: np.ndarray, q_key: np.ndarray
) -> np.ndarray:  # pragma: no cover - numba
    """Distances over the padded flat grid ``start`` (:func:`_start_values`, row length ``Wp``) from many
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
        t0, t1 = _relax(best, Wp, u, du, q_node, q_key, t0, t1)
    for i in range(best.shape[0]):
        if best[i] < zero:
            best[i] = inf
    return best


@nb.njit(cache=True, nogil=True)
def _descend_to_seed(
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


class _Searches:
    """Searches from many sources over one grid: its padded start values built once, each thread's queues and
    target marks allocated once and reused (:func:`_two_queue_dijkstra`)."""

    def __init__(self, passable: np.ndarray, targets: NDArray[np.int64] | None = None) -> None:
        self.h, self.w = int(passable.shape[0]), int(passable.shape[1])
        self.wp = self.w + 2
        self.start = _start_values(np.ascontiguousarray(passable))
        self.cap = int(np.count_nonzero(passable)) + 1
        if targets is None:
            self.targets, self.stop_early = _NO_TARGETS, False
        else:
            self.targets = self.padded(targets)
            self.stop_early = True
        self._scratch = threading.local()

    def scratch(self) -> tuple[NDArray[np.int32], NDArray[np.float32], NDArray[np.uint8]]:
        """This thread's queues and target marks (:func:`_search_into`), allocated on first use."""
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
        ``n_must`` as :func:`_search_into`; cells farther than ``limit`` read ``inf``."""
        scratch = self.scratch()
        s = (r + 1) * self.wp + c + 1
        if targets is None:
            best = _two_queue_dijkstra(self.start, self.wp, s, self.targets, self.stop_early, *scratch, limit)
        else:
            best = _two_queue_dijkstra(self.start, self.wp, s, targets, True, *scratch, limit, n_must)
        return best.reshape((self.h + 2, self.wp))[1:-1, 1:-1]


def _flat_inside(targets_rc: NDArray[np.integer], r0: int, c0: int, shape: tuple[int, ...]) -> NDArray[np.int64]:
    """Flat indices into a crop of ``shape`` at ``(r0, c0)`` of the targets that lie inside it."""
    t = np.asarray(targets_rc, dtype=np.int64).reshape(-1, 2)
    r, c = t[:, 0] - r0, t[:, 1] - c0
    inside = (r >= 0) & (r < shape[0]) & (c >= 0) & (c < shape[1])
    return r[inside] * shape[1] + c[inside]


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
    return np.ascontiguousarray(_Searches(passable)(int(source_rc[0]), int(source_rc[1])))


def _crop(passable: BoolGrid, box: Box | None = None) -> tuple[np.ndarray, int, int] | None:
    """The passable cells' bounding box (``box`` where the caller has it) as a contiguous crop, with its
    first row and column; None when nothing is passable."""
    box = mask_box(passable) if box is None else box
    if box is None:
        return None
    r0, r1, c0, c1 = box
    return np.ascontiguousarray(passable[r0:r1, c0:c1]), r0, c0


def _shape_and_crop(passable: BoolGrid, box: Box | None) -> tuple[tuple[int, int], tuple[np.ndarray, int, int] | None]:
    """The grid's shape and its passable cells' box as :func:`_crop` gives it (None: none passable)."""
    if passable.dtype != np.bool_:
        passable = passable.astype(bool)
    return (int(passable.shape[0]), int(passable.shape[1])), _crop(passable, box)


def _no_field(shape: tuple[int, int]) -> Field:
    """The field of a source off the passable box: unreachable everywhere."""
    return Field(np.full((0, 0), np.inf, dtype=np.float32), 0, 0, shape)


def distance_fields(
    passable: BoolGrid,
    sources_rc: NDArray[np.integer],
    targets_rc: NDArray[np.integer] | None = None,
    box: Box | None = None,
    limit: float = math.inf,
) -> list[Field]:
    """One distance field per source (as :func:`distance_field`), computed and kept on the passable
    cells' bounding box, on the shared threads.

    Parameters
    ----------
    targets_rc:
        ``(k, 2) int`` the only cells the caller will read (and paths to them): each search stops once it
        has reached all of them. Every finite value is then exact; cells farther from the source than
        every target read ``inf``. None: every cell.
    box:
        The passable cells' bounding box (:func:`~mrexplore.boxes.mask_box`), where the caller already
        has it (a pass over a 4.9 M-cell grid costs milliseconds); None: found here.
    limit:
        Each search stops at this path length (cells); farther cells read ``inf`` (a field read only
        within a radius, as a near/far field's exact part is).

    Returns
    -------
    One :class:`Field` per row of ``sources_rc`` (``(n, 2) int``).

    Examples
    --------
    >>> g = np.zeros((4, 5), bool); g[1, 1:4] = True
    >>> f = distance_fields(g, np.array([[1, 1]]))[0]
    >>> (f.r0, f.c0, f.values.shape), f.full()[1].tolist()
    ((1, 1, (1, 3)), [inf, 0.0, 1.0, 2.0, inf])
    """
    shape, cropped = _shape_and_crop(passable, box)
    if cropped is None:
        return [_no_field(shape) for _ in range(len(sources_rc))]
    crop, r0, c0 = cropped
    search = _Searches(crop, None if targets_rc is None else _flat_inside(targets_rc, r0, c0, crop.shape))

    def one(src: NDArray[np.integer]) -> Field:
        r, c = int(src[0]) - r0, int(src[1]) - c0
        if 0 <= r < crop.shape[0] and 0 <= c < crop.shape[1]:
            return Field(search(r, c, limit=limit), r0, c0, shape)
        return _no_field(shape)

    return map_threads(one, list(sources_rc))  # the kernel releases the GIL


def nearest_fields(
    passable: BoolGrid,
    sources_rc: NDArray[np.integer],
    nearest_of_rc: NDArray[np.integer],
    must_rc: Sequence[NDArray[np.integer]],
    box: Box | None = None,
) -> list[Field]:
    """One distance field per source (as :func:`distance_fields`), each search stopped once it has reached
    that source's own ``must_rc`` cells and the nearest of ``nearest_of_rc``: all a caller needs that reads
    only each source's nearest candidate (and its own cells).

    Every finite value is exact; the candidates as near as the nearest (ties) are among them, the farther
    ones read ``inf``, as does every cell farther from the source than all it had to reach. Paths to the
    cells reached are read off as from a whole field. ``must_rc``: ``(k_i, 2) int`` per source (empty for
    none); ``nearest_of_rc`` empty: each search stops once it has its own cells alone.

    Examples
    --------
    >>> g = np.ones((1, 9), bool)
    >>> f = nearest_fields(g, np.array([[0, 4]]), np.array([[0, 0], [0, 6], [0, 2]]), [np.zeros((0, 2), int)])[0]
    >>> f.at(np.array([[0, 0], [0, 6], [0, 2]])).tolist()  # the two at 2 cells, not the one at 4
    [inf, 2.0, 2.0]
    """
    if len(must_rc) != len(sources_rc):
        raise ValueError(f"must_rc has {len(must_rc)} entries for {len(sources_rc)} sources; give one per source")
    shape, cropped = _shape_and_crop(passable, box)
    if cropped is None:
        return [_no_field(shape) for _ in range(len(sources_rc))]
    crop, r0, c0 = cropped
    search = _Searches(crop)
    nearest_of = search.padded(_flat_inside(nearest_of_rc, r0, c0, crop.shape))

    def one(i: int) -> Field:
        r, c = int(sources_rc[i][0]) - r0, int(sources_rc[i][1]) - c0
        if not (0 <= r < crop.shape[0] and 0 <= c < crop.shape[1]):
            return _no_field(shape)
        own = search.padded(_flat_inside(must_rc[i], r0, c0, crop.shape))
        return Field(search(r, c, np.concatenate([own, nearest_of]), n_must=len(own)), r0, c0, shape)

    return map_threads(one, list(range(len(sources_rc))))  # the kernel releases the GIL


_PAIRWISE_SPLIT = 12
"""Points from which :func:`pairwise_distances` shares its rows among the threads: 30 candidates in 12 m
boxes of the largest HouseExpo map at 0.05 m took 6.6 ms on two threads against 11.9 on one, 12 took 2.2
against 3.8 (``perf/bench_fields.py --pairwise 12``); the fewer candidates of the routes of an 8-robot
mission there took longer split from 4 points on (3.4 ms a decision against 2.8,
``perf/decision_split.py --strategy hier``)."""


def pairwise_distances(passable: BoolGrid, points_rc: NDArray[np.integer]) -> NDArray[np.float64]:
    """Geodesic distances between every pair of points, ``(m, m) float64`` in cells, symmetric, ``inf`` where
    unreachable: the search from point i stops once it has reached points i+1 .. m-1 and gives row i's
    later entries, so each pair is searched once and the later searches are short.

    Examples
    --------
    >>> g = np.ones((3, 6), bool); g[0:2, 2] = False  # a wall from the top; no corner cutting round it
    >>> pairwise_distances(g, np.array([[0, 0], [0, 5], [2, 2]])).round(3).tolist()
    [[0.0, 7.243, 3.414], [7.243, 0.0, 3.828], [3.414, 3.828, 0.0]]
    """
    if passable.dtype != np.bool_:
        passable = passable.astype(bool)
    pts = np.asarray(points_rc, dtype=np.int64).reshape(-1, 2)
    m = len(pts)
    out = np.full((m, m), np.inf)
    cropped = _crop(passable)
    if cropped is None or m == 0:
        return out
    crop, r0, c0 = cropped
    r, c = pts[:, 0] - r0, pts[:, 1] - c0
    inside = (r >= 0) & (r < crop.shape[0]) & (c >= 0) & (c < crop.shape[1])
    search = _Searches(crop)
    on = np.flatnonzero(inside)
    padded = search.padded(r[on] * crop.shape[1] + c[on])
    # Rows in turns over the threads where a thread's hand-off pays (row i searches until it has reached
    # the points after it, so the early rows are the long ones).
    parts = thread_count() if len(on) >= _PAIRWISE_SPLIT else 1

    def rows(first: int) -> NDArray[np.float64]:
        return _pairwise_kernel(search.start, search.wp, padded, np.arange(first, len(on), parts), *search.scratch())

    upper = np.minimum.reduce(map_threads(rows, list(range(parts))))
    out[np.ix_(on, on)] = np.minimum(upper, upper.T)
    on = on[crop[r[on], c[on]]]  # a point on a wall is reached by nothing, not even itself
    out[on, on] = 0.0
    return out


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
    search = _Searches(crop, tr[inside] * crop.shape[1] + tc[inside])

    def row(src: NDArray[np.int64]) -> NDArray[np.float64]:
        d = np.full(len(targets), np.inf)
        r, c = int(src[0]) - r0, int(src[1]) - c0
        if 0 <= r < crop.shape[0] and 0 <= c < crop.shape[1]:
            d[inside] = search(r, c)[tr[inside], tc[inside]]
        return d

    rows = map_threads(row, list(sources))
    if rows:
        out[:] = np.stack(rows)
    return out


_EXPLAINS_SLACK = 1e-4
"""How far a neighbour's distance plus the move may exceed a cell's distance and still explain it."""
_FLOAT32_ULPS = 2.0**-22
"""Relative slack of the fallback test: two units in the last place of a float32 distance. Searches add
in float32, so a stored distance is off its neighbour's plus the move by up to half a unit in the last
place: beyond 2,048 cells that exceeds ``_EXPLAINS_SLACK`` (a diagonal of 3,000 cells found no path, and
on a KTH floor at 0.05 m robots 140-210 m from their goals got none, decision after decision)."""


@nb.njit(cache=True, nogil=True, inline="always")
def _explaining_neighbour(
    field: np.ndarray, passable: np.ndarray, r: int, c: int, slack: float
) -> tuple[int, int]:  # pragma: no cover - numba
    """The neighbour of lowest distance whose distance plus the move is within ``slack`` of ``(r, c)``'s:
    it lies on a shortest path; ``(-1, -1)`` for none."""
    best = field[r, c]
    br = -1
    bc = -1
    for d in range(8):
        step = move_cost(passable, r, c, d)
        if step < 0:
            continue
        rr = r + DR[d]
        cc = c + DC[d]
        if field[rr, cc] + step <= field[r, c] + slack and field[rr, cc] < best:
            best = field[rr, cc]
            br = rr
            bc = cc
    return br, bc


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
        br, bc = _explaining_neighbour(field, passable, r, c, _EXPLAINS_SLACK)
        if br < 0:
            # Only where the strict test finds no neighbour, so every path it reads stays as it was.
            br, bc = _explaining_neighbour(field, passable, r, c, _EXPLAINS_SLACK + abs(field[r, c]) * _FLOAT32_ULPS)
        if br < 0:
            return np.zeros((0, 2), dtype=np.int32)
        r = br
        c = bc
        out[n, 0] = r
        out[n, 1] = c
        n += 1
    return out[:n][::-1].copy()


def descend_path(field: FieldLike, passable: BoolGrid, goal_rc: GridRC) -> NDArray[np.int32]:
    """Shortest path from a field's source to ``goal_rc``, read off the field (no search); ``passable`` is
    the whole grid the field was computed on.

    Returns
    -------
    ``(k, 2) int32`` cells from the source to the goal inclusive; ``(0, 2)`` if the goal is unreachable.

    Examples
    --------
    >>> g = np.ones((3, 4), bool); g[0:2, 1] = False  # both diagonals around it would cut its corner
    >>> descend_path(distance_field(g, (0, 0)), g, (0, 2)).tolist()
    [[0, 0], [1, 0], [2, 0], [2, 1], [2, 2], [1, 2], [0, 2]]
    """
    f = _as_field(field)
    h, w = f.values.shape
    r, c = int(goal_rc[0]) - f.r0, int(goal_rc[1]) - f.c0
    if not (0 <= r < h and 0 <= c < w):
        return np.zeros((0, 2), dtype=np.int32)
    box = np.ascontiguousarray(passable[f.r0 : f.r0 + h, f.c0 : f.c0 + w], dtype=bool)
    path = _descend(f.values, box, r, c)
    path += np.array([f.r0, f.c0], dtype=np.int32)
    return path


def distances_at(field: Distances, cells_rc: NDArray[np.integer]) -> NDArray[np.float64]:
    """Look up a field at ``(k, 2) int`` cells: ``(k,) float64`` distances in cells (``inf`` where
    unreachable)."""
    if len(cells_rc) == 0:
        return np.zeros(0, dtype=np.float64)
    if isinstance(field, np.ndarray):
        return Field.whole(field).at(cells_rc)
    return field.at(cells_rc)
