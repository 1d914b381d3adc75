"""Geodesic distance fields on a grid (8-connected, no corner cutting), exact, in linear time: whole fields,
fields stopped once they reach their targets, nearest fields, distance matrices and paths, built on the
two-queue search of :mod:`~mrexplore.paths.kernels`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Protocol

import numba as nb
import numpy as np
from numpy.typing import NDArray

from mrexplore.maps.boxes import Box
from mrexplore.paths.kernels import Searches, pairwise_kernel, passable_crop
from mrexplore.paths.moves import DC, DR, move_cost
from mrexplore.runtime.threads import map_threads, thread_count
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
    return np.ascontiguousarray(Searches(passable)(int(source_rc[0]), int(source_rc[1])))


def _shape_and_crop(passable: BoolGrid, box: Box | None) -> tuple[tuple[int, int], tuple[np.ndarray, int, int] | None]:
    """The grid's shape and its passable cells' box as :func:`passable_crop` gives it (None: none passable)."""
    if passable.dtype != np.bool_:
        passable = passable.astype(bool)
    return (int(passable.shape[0]), int(passable.shape[1])), passable_crop(passable, box)


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
        The passable cells' bounding box (:func:`~mrexplore.maps.boxes.mask_box`), where the caller already
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
    search = Searches(crop, None if targets_rc is None else _flat_inside(targets_rc, r0, c0, crop.shape))

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
    search = Searches(crop)
    nearest_of = search.padded(_flat_inside(nearest_of_rc, r0, c0, crop.shape))

    def one(i: int) -> Field:
        r, c = int(sources_rc[i][0]) - r0, int(sources_rc[i][1]) - c0
        if not (0 <= r < crop.shape[0] and 0 <= c < crop.shape[1]):
            return _no_field(shape)
        own = search.padded(_flat_inside(must_rc[i], r0, c0, crop.shape))
        return Field(search(r, c, np.concatenate([own, nearest_of]), n_must=len(own)), r0, c0, shape)

    return map_threads(one, list(range(len(sources_rc))))  # the kernel releases the GIL


_PAIRWISE_SPLIT = 12
"""Points from which :func:`pairwise_distances` shares its rows among the threads: from about a dozen
candidates two threads pay off, while the few candidates of most routes lose more to handing rows over
than they gain (``benchmarks/fields.py --pairwise 12``)."""


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
    cropped = passable_crop(passable)
    if cropped is None or m == 0:
        return out
    crop, r0, c0 = cropped
    r, c = pts[:, 0] - r0, pts[:, 1] - c0
    inside = (r >= 0) & (r < crop.shape[0]) & (c >= 0) & (c < crop.shape[1])
    search = Searches(crop)
    on = np.flatnonzero(inside)
    padded = search.padded(r[on] * crop.shape[1] + c[on])
    # Rows in turns over the threads where a thread's hand-off pays (row i searches until it has reached
    # the points after it, so the early rows are the long ones).
    parts = thread_count() if len(on) >= _PAIRWISE_SPLIT else 1

    def rows(first: int) -> NDArray[np.float64]:
        return pairwise_kernel(search.start, search.wp, padded, np.arange(first, len(on), parts), *search.scratch())

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
    cropped = passable_crop(passable)
    if cropped is None or len(targets) == 0:
        return out
    crop, r0, c0 = cropped
    tr, tc = targets[:, 0] - r0, targets[:, 1] - c0
    inside = (tr >= 0) & (tr < crop.shape[0]) & (tc >= 0) & (tc < crop.shape[1])
    search = Searches(crop, tr[inside] * crop.shape[1] + tc[inside])

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
