"""Distances with bounded work on large floors: exact near each robot, from a coarse grid beyond.

Late in a mission on a whole building, cluster centres lie all over the floor and an exact field per robot
covers every passable cell: on a KTH floor at 0.05 m (4.9 M cells) 16 such fields were 0.9 s of a 1.1 s
decision. A :class:`NearFarField` keeps the exact search to a box of the exact radius around the robot and
answers farther cells from a search on a grid of square blocks, seeded with the exact distances: the
planners' costs of far clusters are estimates, the ones of near clusters and every path driven are exact.

The coarse grid is conservative: a block is passable only when all of its cells are, so no coarse path
crosses a wall, however thin, and every coarse path is a real path at least as long (an estimate is never
shorter than the true distance, up to the last block to the cell). Passages narrower than about two blocks
are closed on it; what lies only behind one reads ``inf`` there, and :func:`far_fields` searches it on
blocks half as wide, exactly where those close it too.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numba as nb
import numpy as np
from numpy.typing import NDArray
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import maximum_bipartite_matching

from mrexplore.maps.boxes import mask_box
from mrexplore.paths.distance_field import Field, descend_path, distance_fields
from mrexplore.paths.kernels import Searches, descend_to_seed, passable_crop, search_into, seeded_search
from mrexplore.paths.portals import PortalField, PortalGraph
from mrexplore.runtime.threads import map_threads
from mrexplore.types import BoolGrid, GridRC

__all__ = ["CoarseGrid", "NearFarField", "coarse_grid", "far_fields", "path_to"]

_SQRT2 = math.sqrt(2.0)
_NEIGHBOURHOOD = [(dr, dc) for dr in (-1, 0, 1) for dc in (-1, 0, 1)]


@nb.njit(cache=True, nogil=True)
def _tails(
    fine: np.ndarray, cells: np.ndarray, pooled: np.ndarray, f: int, r0: int, c0: int
) -> np.ndarray:  # pragma: no cover - numba
    """:meth:`CoarseGrid.tails` for ``cells`` ``(k, 2) int64``: one exact search per cell over the box of
    ``2 f`` cells around it (the two-queue search of :mod:`~mrexplore.paths.distance_field`)."""
    H, W = fine.shape
    h, w = pooled.shape
    k = cells.shape[0]
    out = np.full((k, 9), np.inf)
    reach = 2 * f
    side = 2 * reach + 1
    Wp = side + 2
    n = (side + 2) * Wp
    q_node = np.empty((2, n), dtype=np.int32)
    q_key = np.empty((2, n), dtype=np.float32)
    is_target = np.zeros(n, dtype=np.uint8)
    no_targets = np.zeros(0, dtype=np.int64)
    best = np.empty(n, dtype=np.float32)
    for i in range(k):
        r, c = cells[i, 0], cells[i, 1]
        if r < 0 or r >= H or c < 0 or c >= W or not fine[r, c]:
            continue
        best[:] = -1.0
        for a in range(side):
            for b in range(side):
                rr, cc = r - reach + a, c - reach + b
                if 0 <= rr < H and 0 <= cc < W and fine[rr, cc]:
                    best[(a + 1) * Wp + b + 1] = np.inf
        search_into(best, Wp, (reach + 1) * Wp + reach + 1, no_targets, False, q_node, q_key, is_target, np.inf)
        br, bc = (r - r0) // f, (c - c0) // f
        j = 0
        for dr in range(-1, 2):
            for dc in range(-1, 2):
                rr, cc = br + dr, bc + dc
                if 0 <= rr < h and 0 <= cc < w and pooled[rr, cc]:
                    mr, mc = rr * f + r0 + f // 2 - r + reach, cc * f + c0 + f // 2 - c + reach
                    if 0 <= mr < side and 0 <= mc < side:
                        v = best[(mr + 1) * Wp + mc + 1]
                        if v >= 0.0 and v < np.inf:
                            out[i, j] = v
                j += 1
    return out


@nb.njit(cache=True, nogil=True)
def _pool(passable: np.ndarray, r0: int, r1: int, c0: int, c1: int, f: int) -> np.ndarray:  # pragma: no cover
    """``(h, w) bool``: block ``(i, j)`` of rows ``r0 + i f ...`` and columns ``c0 + j f ...`` of ``passable``
    is True when every one of its cells inside ``[r0, r1) x [c0, c1)`` is, and the block lies wholly
    inside (a block cut by the box's far edge is not passable). One pass over the box, a few times faster
    than numpy's reduction over the two block axes of a reshaped copy."""
    h, w = -(-(r1 - r0) // f), -(-(c1 - c0) // f)
    out = np.ones((h, w), dtype=np.bool_)
    for i in range(h):
        rr = r0 + i * f
        for j in range(w):
            if r1 - rr < f or c1 - (c0 + j * f) < f:
                out[i, j] = False
    for r in range(r0, r1):
        i = (r - r0) // f
        for c in range(c0, c1):
            if not passable[r, c]:
                out[i, (c - c0) // f] = False
    return out


_POOL_BANDS = 2
"""Bands of block rows :meth:`CoarseGrid.of` pools on the threads (inline where one thread is allowed)."""


@dataclass(frozen=True)
class CoarseGrid:
    """The passable grid pooled into ``factor`` x ``factor`` blocks from fine cell ``(r0, c0)``: a block
    is passable when every cell of it is."""

    passable: NDArray[np.bool_]
    factor: int
    r0: int
    c0: int
    fine: NDArray[np.bool_]
    """The ``(H, W) bool`` grid it was pooled from."""
    memo: dict[tuple[int, int], NDArray[np.float64]] = field(default_factory=dict)
    """:meth:`tails` already computed, by cell."""
    _exact: list[tuple[Searches, int, int]] = field(default_factory=list, repr=False, compare=False)
    """The fine grid's searches (:meth:`exact_at`), built on first use."""
    _finer: list[CoarseGrid | None] = field(default_factory=list, repr=False, compare=False)
    """:meth:`finer`, built on first use."""
    _search: list[Searches] = field(default_factory=list, repr=False, compare=False)
    """:attr:`search`, built on first use."""
    portals: PortalGraph | None = field(default=None, repr=False, compare=False)
    """The portal graph far distances are searched on (:mod:`~mrexplore.paths.portals`), brought up to
    date with these blocks; None: each far field searches every block."""
    finer_portals: PortalGraph | None = field(default=None, repr=False, compare=False)
    """The portal graph of :meth:`finer`'s blocks, kept the same way; None: :meth:`finer`'s far fields
    search every block."""

    @classmethod
    def of(
        cls,
        passable: BoolGrid,
        factor: int,
        portals: PortalGraph | None = None,
        finer_portals: PortalGraph | None = None,
    ) -> CoarseGrid | None:
        box = mask_box(passable)
        if box is None:
            return None
        r0, r1, c0, c1 = box
        if portals is not None:
            # Blocks on the map's own lattice of sectors, so the graph kept from the last decision lines up.
            step = factor * portals.S
            r0, c0 = r0 // step * step, c0 // step * step
        grid = np.ascontiguousarray(passable)
        # Bands of whole block rows on the threads (the kernel releases the GIL; only the last band
        # meets the box's far edge, so each block is pooled as in one pass).
        rows = -(-(r1 - r0) // factor)
        cuts = [r0 + factor * (rows * k // _POOL_BANDS) for k in range(_POOL_BANDS)] + [r1]
        bands = [(a, b) for a, b in zip(cuts[:-1], cuts[1:], strict=True) if b > a]
        parts = map_threads(lambda ab: _pool(grid, ab[0], ab[1], c0, c1, factor), bands)
        pooled = parts[0] if len(parts) == 1 else np.vstack(parts)
        if portals is not None:
            portals.refresh(pooled, r0 // factor, c0 // factor)
        out = cls(pooled, factor, r0, c0, passable, portals=portals, finer_portals=finer_portals)
        if portals is None:
            out._search.append(Searches(pooled))  # every far field searches it: built before the threads
        return out

    @property
    def search(self) -> Searches:
        """Searches over the blocks, built on first use (a grid whose far fields search its portal graph
        seldom needs them)."""
        if not self._search:
            self._search.append(Searches(self.passable))
        return self._search[0]

    def tails(self, cells: NDArray[np.int64]) -> NDArray[np.float64]:
        """``(k, 9) float64``: for each cell, the exact distance from the middle of its block and of each of
        the 8 neighbours (:data:`_NEIGHBOURHOOD` order) to it, within two blocks of it; ``inf`` where that
        block is off the grid, not passable or not reached. Remembered per cell: every robot reads the same."""
        missing = [i for i, (r, c) in enumerate(cells.tolist()) if (r, c) not in self.memo]
        if missing:
            rows = _tails(self.fine, cells[missing], self.passable, self.factor, self.r0, self.c0)
            for i, row in zip(missing, rows, strict=True):
                self.memo[(int(cells[i, 0]), int(cells[i, 1]))] = row
        return np.array([self.memo[(r, c)] for r, c in cells.tolist()], dtype=np.float64).reshape(-1, 9)

    def exact_at(self, src_rc: NDArray[np.integer], cells_rc: NDArray[np.integer]) -> NDArray[np.float64]:
        """Exact distances from ``src_rc`` to ``(k, 2)`` cells of :attr:`fine`, ``(k,) float64`` (``inf`` where
        unreachable), the search stopped once it has reached them all: what
        :func:`~mrexplore.paths.distance_field.distance_fields` reads there, with one set of start values and
        queues for every call on this grid: late on a KTH floor a decision makes up to a dozen such searches
        back from cluster centres the blocks do not reach, each of which built start values and touched
        fresh queues over the 4.9 M cells before."""
        if not self._exact:
            cropped = passable_crop(self.fine)
            if cropped is None:
                return np.full(len(cells_rc), np.inf)
            crop, r0, c0 = cropped
            self._exact.append((Searches(crop), r0, c0))
        search, r0, c0 = self._exact[0]
        cells = np.asarray(cells_rc, np.int64).reshape(-1, 2)
        out = np.full(len(cells), np.inf)
        r, c = int(src_rc[0]) - r0, int(src_rc[1]) - c0
        local = cells - np.array([r0, c0])
        inside = (local[:, 0] >= 0) & (local[:, 0] < search.h) & (local[:, 1] >= 0) & (local[:, 1] < search.w)
        if not (0 <= r < search.h and 0 <= c < search.w) or not inside.any():
            return out
        targets = search.padded(local[inside, 0] * search.w + local[inside, 1])
        values = search(r, c, targets)
        out[inside] = values[local[inside, 0], local[inside, 1]]
        return out

    def finer(self) -> CoarseGrid | None:
        """The same fine grid pooled into blocks half as wide (2 cells at the least), built once and kept;
        None where that is no smaller block. A passage ``2 s - 1`` cells wide always holds a whole block of
        side ``s``: blocks of 2 close no passage 3 cells wide or more, which blocks of 3 close where it is
        under 5 and misses their alignment."""
        if not self._finer:
            self._finer.append(_finer_of(self.fine, self.factor, self.finer_portals))
        return self._finer[0]

    def centres_rc(self, blocks: NDArray[np.integer]) -> NDArray[np.int64]:
        """The fine cell at the middle of each ``(k, 2)`` block (the cell a block's distance is taken at)."""
        return np.asarray(blocks, np.int64) * self.factor + np.array([self.r0, self.c0]) + self.factor // 2


@dataclass(frozen=True)
class NearFarField:
    """Distances from one robot: exact from ``near`` where they are at most ``radius_cells``, else the
    coarse estimate: block distance times the block side, plus the exact way from the block's middle to the
    cell inside a box of two blocks around the cell, the best over the cell's block and its 8 neighbours.
    Every finite estimate is the length of a real path (exact part, whole free blocks, the last way), so
    never shorter than the true distance.

    Reads like a :class:`~mrexplore.paths.distance_field.Field` (``at``, ``value``); paths come from
    :func:`path_to`.
    """

    near: Field
    radius_cells: float
    coarse: NDArray[np.float32] | None
    """``(h, w) float32`` block distances, in blocks, on :attr:`grid`'s blocks; ``inf`` where unreachable.
    None where :attr:`portal` answers them."""
    grid: CoarseGrid
    seed_key: NDArray[np.float32] | None
    """``(h, w) float32`` the starting distance of each seed block (in blocks); ``inf`` for others (None
    with :attr:`portal`)."""
    known: dict[tuple[int, int], float] = field(default_factory=dict)
    """Distances found otherwise, for cells the coarse grid leaves at ``inf`` (:func:`far_fields`: joined
    back from the cell, on blocks half as wide, or exact); they take precedence."""
    portal: PortalField | None = None
    """The block distances searched on the grid's portal graph, where it has one."""
    finer: list[NearFarField] = field(default_factory=list)
    """The same source's field on blocks half as wide, where :func:`far_fields` searched one for cells
    these blocks leave unread: what :func:`path_to` leads a path to such a cell along."""

    def blocks(self, rr: NDArray[np.int64], cc: NDArray[np.int64]) -> NDArray[np.float64]:
        """``(k,) float64`` block distances (in blocks) at :attr:`grid`'s blocks ``(rr, cc)`` (inside it)."""
        if self.portal is not None:
            g = self.grid
            return self.portal.values(np.stack([rr + g.r0 // g.factor, cc + g.c0 // g.factor], axis=1))
        assert self.coarse is not None
        return self.coarse[rr, cc].astype(np.float64)

    def _far(self, cells: NDArray[np.int64]) -> NDArray[np.float64]:
        g, f = self.grid, self.grid.factor
        h, w = g.passable.shape
        tails = g.tails(cells)
        br = (cells[:, 0] - g.r0) // f
        bc = (cells[:, 1] - g.c0) // f
        step = np.array(_NEIGHBOURHOOD, np.int64)
        rr, cc = br[:, None] + step[None, :, 0], bc[:, None] + step[None, :, 1]  # (k, 9): block, neighbours
        ok = (rr >= 0) & (rr < h) & (cc >= 0) & (cc < w)
        d = np.full(rr.shape, np.inf)
        d[ok] = self.blocks(rr[ok], cc[ok]) * f + tails[ok]
        return d.min(axis=1) if len(cells) else np.zeros(0)

    def at(self, cells_rc: NDArray[np.integer]) -> NDArray[np.float64]:
        """Distances in cells at ``(k, 2) int`` cells, ``(k,) float64``."""
        cells = np.asarray(cells_rc, np.int64).reshape(-1, 2)
        d = self.near.at(cells)
        far = ~(d <= self.radius_cells)
        if far.any():
            d[far] = self._far(cells[far])
        if self.known:
            for i in np.flatnonzero(far):
                d[i] = self.known.get((int(cells[i, 0]), int(cells[i, 1])), d[i])
        return d

    def value(self, r: int, c: int) -> float:
        """The distance at one cell."""
        return float(self.at(np.array([[r, c]]))[0])

    def is_exact(self, r: int, c: int) -> bool:
        """Whether the distance at the cell is exact (within the radius of the exact search)."""
        return self.near.value(r, c) <= self.radius_cells


def _near_box(passable: BoolGrid, rc: NDArray[np.integer], radius: int) -> tuple[int, int, int, int]:
    """Rows and columns (half-open) of the box within ``radius`` cells of ``rc``, clipped to the grid: no
    path of at most ``radius`` cells leaves it, so a search inside it is exact up to ``radius``."""
    H, W = passable.shape
    r, c = int(rc[0]), int(rc[1])
    return max(0, r - radius), min(H, r + radius + 1), max(0, c - radius), min(W, c + radius + 1)


@dataclass(frozen=True)
class _Seeds:
    """A source's exact part and the coarse grid's blocks it reaches within the radius: the passable blocks
    whose middle cell it reaches, sorted by their distance there (stable: row-major among equals)."""

    near: Field
    blocks: NDArray[np.int64]
    """``(k, 2) int64`` the seed blocks."""
    cells: NDArray[np.float64]
    """``(k,) float64`` the exact distance from the source to each block's middle cell, in cells."""


def _seeds(passable: BoolGrid, grid: CoarseGrid, src: NDArray[np.integer], radius: int, ordered: bool = True) -> _Seeds:
    """The exact search from ``src`` up to ``radius`` cells and the blocks it seeds (:class:`_Seeds`): what a
    near/far field starts its coarse search from (:func:`_one`), and what joins a cell to the sources'
    coarse fields (:func:`_back`); unsorted with ``ordered=False`` (the portal graph sorts them by sector)."""
    r0, r1, c0, c1 = _near_box(passable, src, radius)
    # Stopped at the radius: beyond it the field reads the coarse estimate, and seeds and paths stay within.
    local = np.array([[int(src[0]) - r0, int(src[1]) - c0]])
    near = distance_fields(passable[r0:r1, c0:c1], local, limit=float(radius))[0]
    near = Field(near.values, near.r0 + r0, near.c0 + c0, (int(passable.shape[0]), int(passable.shape[1])))
    f = grid.factor
    h, w = grid.passable.shape
    blk_r0 = max(0, (r0 - grid.r0) // f)
    blk_r1 = min(h, -(-(r1 - grid.r0) // f))
    blk_c0 = max(0, (c0 - grid.c0) // f)
    blk_c1 = min(w, -(-(c1 - grid.c0) // f))
    if blk_r1 <= blk_r0 or blk_c1 <= blk_c0:
        return _Seeds(near, np.zeros((0, 2), np.int64), np.zeros(0))
    rr, cc = np.nonzero(grid.passable[blk_r0:blk_r1, blk_c0:blk_c1])
    blocks = np.stack([rr + blk_r0, cc + blk_c0], axis=1)
    d = near.at(grid.centres_rc(blocks))
    keep = d <= radius
    blocks, d = blocks[keep], d[keep]
    if not ordered:  # the portal graph sorts its seeds by sector
        return _Seeds(near, blocks, d)
    order = np.argsort((d / f).astype(np.float32), kind="stable")
    return _Seeds(near, blocks[order], d[order])


def _one(passable: BoolGrid, grid: CoarseGrid, src: NDArray[np.integer], radius: int) -> NearFarField:
    if grid.portals is not None:
        return _one_on_portals(passable, grid, grid.portals, src, radius)
    seeds = _seeds(passable, grid, src, radius)
    f = grid.factor
    h, w = grid.passable.shape
    blocks, keys = seeds.blocks, (seeds.cells / f).astype(np.float32)
    seed_key = np.full(grid.passable.shape, np.inf, dtype=np.float32)
    seed_key[blocks[:, 0], blocks[:, 1]] = keys
    s = grid.search
    q_node, q_key, _ = s.scratch()
    flat = s.padded(blocks[:, 0] * w + blocks[:, 1])
    coarse = seeded_search(s.start, s.wp, flat, keys, q_node, q_key).reshape(h + 2, w + 2)[1:-1, 1:-1]
    return NearFarField(seeds.near, float(radius), coarse, grid, seed_key)


def _one_on_portals(
    passable: BoolGrid, grid: CoarseGrid, portals: PortalGraph, src: NDArray[np.integer], radius: int
) -> NearFarField:
    """:func:`_one` on the portal graph: the exact search up to ``radius`` and the blocks it seeds
    (:func:`_seeds`), then the graph searched from the nodes those seeds reach inside their sectors: seeding
    only the nodes the exact search reaches left a robot whose exact part reaches no portal with no
    distance beyond it. A robot whose seed blocks join no node even so (single blocks in a gap that the
    sectors' lattice cuts) reads ``inf``, and :func:`far_fields` searches what it must read on the finer
    blocks."""
    seeds = _seeds(passable, grid, src, radius, ordered=False)
    f = grid.factor
    blocks = seeds.blocks + np.array([grid.r0 // f, grid.c0 // f])
    field_ = portals.search_from(blocks, seeds.cells / f)
    return NearFarField(seeds.near, float(radius), None, grid, None, portal=field_)


def _back(
    passable: BoolGrid,
    grid: CoarseGrid,
    cell: NDArray[np.int64],
    radius: int,
    sources: NDArray[np.int64],
    fields: Sequence[NearFarField],
) -> NDArray[np.float64]:
    """Distances from ``cell`` to each of ``sources`` (whose near/far fields are ``fields``), ``(n,)
    float64``, without a search over the coarse grid: exact where the cell's own exact part reaches the
    source; else the best way along the source's coarse field into a block whose middle the cell's exact
    part reaches, then exactly to the cell: a real path, as every estimate is (distances are symmetric);
    ``inf`` where there is none.

    A near/far field of the cell's own, read at the sources, would go the same ways the other way round,
    with a coarse search of its own, which late on a large floor (cluster centres in ragged, ray-lit free
    space that no block next to them reaches) adds a fifth to a decision's coarse searches."""
    seeds = _seeds(passable, grid, cell, radius)
    out = np.full(len(sources), np.inf)
    if len(seeds.blocks):
        coarse = np.stack([fl.blocks(seeds.blocks[:, 0], seeds.blocks[:, 1]) for fl in fields])
        out = np.min(coarse * grid.factor + seeds.cells[None, :], axis=1)
    exact = seeds.near.at(sources)
    inside = exact <= radius
    out[inside] = exact[inside]
    return out


def _fewest_searches(pairs: NDArray[np.bool_]) -> tuple[NDArray[np.bool_], NDArray[np.bool_]]:
    """Rows (sources) and columns (cells) of ``(n, k) bool`` ``pairs`` such that every True lies in one of
    them, as few as can be: a minimum vertex cover of the bipartite graph, by Kőnig's theorem from a
    maximum matching. Columns are taken where rows save nothing (a column's search may end early, below).

    Examples
    --------
    >>> apart = np.array([[0, 0, 1, 0], [1, 1, 1, 1], [0, 0, 1, 0]], bool)  # source 1 leaves every cell
    >>> [m.nonzero()[0].tolist() for m in _fewest_searches(apart)]  # one search from it, one back from cell 2
    [[1], [2]]
    """
    n = pairs.shape[0]
    match = maximum_bipartite_matching(csr_matrix(pairs.T.astype(np.int8)), perm_type="column")  # cell -> source
    owner = np.full(n, -1, dtype=np.int64)  # source -> the cell matched to it
    owner[match[match >= 0]] = np.flatnonzero(match >= 0)
    # Kőnig: from the unmatched cells, alternate along unmatched edges to sources and matched edges back.
    seen_cells, seen_sources = match < 0, np.zeros(n, dtype=bool)
    todo = np.flatnonzero(seen_cells).tolist()
    while todo:
        j = todo.pop()
        for i in np.flatnonzero(pairs[:, j] & ~seen_sources).tolist():
            seen_sources[i] = True
            if owner[i] >= 0 and not seen_cells[owner[i]]:
                seen_cells[owner[i]] = True
                todo.append(int(owner[i]))
    return seen_sources, pairs.any(axis=0) & ~seen_cells


def finer_side(factor: int) -> int | None:
    """The side of :meth:`CoarseGrid.finer`'s blocks for blocks of ``factor`` cells: half as wide, 2 cells
    at the least; None where that is no smaller block."""
    side = max(2, factor // 2)
    return side if side < factor else None


def _finer_of(passable: BoolGrid, factor: int, portals: PortalGraph | None = None) -> CoarseGrid | None:
    """``passable`` pooled into :func:`finer_side` blocks, on ``portals`` where given; None where that is no
    smaller block (:meth:`CoarseGrid.finer`)."""
    side = finer_side(factor)
    return CoarseGrid.of(passable, side, portals) if side is not None else None


def coarse_grid(
    passable: BoolGrid, factor: int, portals: PortalGraph | None = None, finer_portals: PortalGraph | None = None
) -> CoarseGrid | None:
    """``passable`` pooled into ``factor`` x ``factor`` blocks, for :func:`far_fields` calls on the same grid to
    share (pooling a KTH floor at 0.05 m takes about 3 ms); None where no cell is passable. ``portals``: a
    graph kept from earlier decisions on this map (:mod:`~mrexplore.paths.portals`), brought up to date
    here, which far fields then search instead of every block; ``finer_portals``: the same for the blocks
    half as wide that cells these blocks leave unread are searched on (:meth:`CoarseGrid.finer`).

    Examples
    --------
    >>> g = np.ones((4, 6), bool); g[0, 5] = False
    >>> coarse_grid(g, 2).passable.astype(int).tolist()  # the block holding the wall cell is not passable
    [[1, 1, 0], [1, 1, 1]]
    """
    if passable.dtype != np.bool_:
        passable = passable.astype(bool)
    return CoarseGrid.of(passable, factor, portals, finer_portals)


def far_fields(
    passable: BoolGrid,
    sources_rc: NDArray[np.integer],
    radius_cells: int,
    factor: int,
    must_rc: NDArray[np.integer] | None = None,
    own_rc: Sequence[NDArray[np.integer]] | None = None,
    grid: CoarseGrid | None = None,
    own_needed: Callable[[NDArray[np.float64]], NDArray[np.bool_]] | None = None,
) -> list[NearFarField]:
    """One :class:`NearFarField` per source: exact up to ``radius_cells``, blocks of ``factor`` x ``factor``
    cells beyond.

    ``must_rc`` (``(k, 2) int``, e.g. cluster centres): cells every field must answer where the exact
    search does. Where the coarse grid leaves some at ``inf`` (behind a passage it closes, or a source
    behind one), the fewest sources and cells that cover every such pair are searched: a source by one
    search that reads all the cells it leaves; a cell by an exact search of its own up to the radius,
    joined to the sources' coarse fields (:func:`_back`; distances are symmetric, its exact part goes
    through the passage; where that joins none, the same with twice the radius), and a search from it to
    the sources that still leaves at ``inf`` (the other sources read the cell's distances so found). Such
    a search is a near/far field on blocks half as wide (:meth:`CoarseGrid.finer`: with blocks of 2, no
    passage 3 cells wide or more is closed), exact where that leaves cells at ``inf`` too; its values go
    into the fields' :attr:`~NearFarField.known`. ``own_rc``: per source, cells only that source must
    answer (its current goal); where the coarse grid leaves one at ``inf``, the same search from the
    source. ``grid``: :func:`coarse_grid` of the same ``passable`` and ``factor``, shared between calls
    (built here when None). ``own_needed``, where every source has the same ``own_rc`` cells: given the
    ``(n_sources, k)`` distances the fields read there before any search of their own (``inf`` where
    unread), which of the cells still need theirs; the others are left as read (CoScan-2D's tasks beyond
    the ones it keeps, :func:`~mrexplore.global_planning.coscan.tasks_in_reach`).

    Examples
    --------
    A corridor 40 cells long, 4 wide; exact up to 10 cells, blocks of 2 beyond:

    >>> g = np.zeros((6, 44), bool); g[1:5, 2:42] = True
    >>> f = far_fields(g, np.array([[2, 2]]), radius_cells=10, factor=2)[0]
    >>> f.at(np.array([[2, 8], [2, 40]])).round(1).tolist()  # exact at 6 cells; 38 exactly, estimated 38.0
    [6.0, 38.0]
    """
    if passable.dtype != np.bool_:
        passable = passable.astype(bool)
    if factor < 1:
        raise ValueError(f"factor must be >= 1, got {factor}")
    if grid is None:
        grid = CoarseGrid.of(passable, factor)
    elif grid.factor != factor or grid.fine.shape != passable.shape:
        raise ValueError(f"grid was pooled by {grid.factor} from a {grid.fine.shape} grid; pool this one by {factor}")
    if grid is None:
        raise ValueError("far_fields needs a passable cell; use distance_fields on an empty grid")
    sources = np.asarray(sources_rc, np.int64).reshape(-1, 2)
    pooled: CoarseGrid = grid
    searches = _Searches(passable, pooled, radius_cells)
    fields = map_threads(lambda src: _one(passable, pooled, src, radius_cells), list(sources))
    if own_needed is not None and own_rc is not None and len(fields):
        own_rc = _own_needed(fields, own_rc, own_needed)
    if must_rc is not None and len(must_rc) and len(fields):
        _answer_must(searches, sources, fields, must_rc, own_rc)
    for f, src, goals in zip(fields, sources, own_rc or [], strict=False):
        mine = np.asarray(goals, np.int64).reshape(-1, 2)
        unseen = mine[~np.isfinite(f.at(mine))]
        if len(unseen):
            for cell, d in zip(unseen, searches.unjoined(src, unseen, f), strict=True):
                f.known[(int(cell[0]), int(cell[1]))] = float(d)
    return fields


class _Searches:
    """The searches :func:`far_fields` makes where the coarse grid leaves a distance at ``inf``."""

    def __init__(self, passable: BoolGrid, pooled: CoarseGrid, radius_cells: int) -> None:
        self.passable, self.pooled, self.radius_cells = passable, pooled, radius_cells
        self._finer: list[CoarseGrid | None] = []

    def exact(self, src: NDArray[np.int64], cells: NDArray[np.int64]) -> NDArray[np.float64]:
        """Exact distances from ``src`` at ``cells``: on the grid's shared searches where it was pooled
        from this very array, as every decision's grid is."""
        if self.pooled.fine is self.passable:
            return self.pooled.exact_at(src, cells)
        return distance_fields(self.passable, src[None], cells)[0].at(cells)

    def unjoined(
        self, src: NDArray[np.int64], cells: NDArray[np.int64], keep: NearFarField | None = None
    ) -> NDArray[np.float64]:
        """Distances from ``src`` at ``cells`` the grid leaves at ``inf``: a near/far field of ``src`` on
        blocks half as wide (:meth:`CoarseGrid.finer`), exact where that leaves them too: much cheaper than
        searching the floor exactly from the source, the distances so found a fraction of a percent longer
        (docs/performance.md). ``keep``: the source's own field, which keeps the finer one for paths."""
        pooled, passable = self.pooled, self.passable
        if not self._finer:
            self._finer.append(pooled.finer() if pooled.fine is passable else _finer_of(passable, pooled.factor))
        out = np.full(len(cells), np.inf)
        if self._finer[0] is not None:
            on_finer = _one(passable, self._finer[0], src, self.radius_cells)
            out = on_finer.at(cells)
            if keep is not None:
                keep.finer.append(on_finer)
        still = ~np.isfinite(out)
        if still.any():
            out[still] = self.exact(src, cells[still])
        return out


def _own_needed(
    fields: list[NearFarField],
    own_rc: Sequence[NDArray[np.integer]],
    own_needed: Callable[[NDArray[np.float64]], NDArray[np.bool_]],
) -> list[NDArray[np.int64]]:
    """Every source's own cells, filtered by ``own_needed`` on the distances the fields read there."""
    shared = np.asarray(own_rc[0], np.int64).reshape(-1, 2)
    if len(own_rc) != len(fields) or any(not np.array_equal(np.reshape(o, (-1, 2)), shared) for o in own_rc):
        raise ValueError("own_needed filters the own cells every source shares; give every source the same own_rc")
    needed = np.asarray(own_needed(np.stack([f.at(shared) for f in fields])), dtype=bool)
    return [shared[needed]] * len(fields)


def _answer_must(
    searches: _Searches,
    sources: NDArray[np.int64],
    fields: list[NearFarField],
    must_rc: NDArray[np.integer],
    own_rc: Sequence[NDArray[np.integer]] | None,
) -> None:
    """Put in every field's ``known`` the distances at ``must_rc`` its coarse search left at ``inf``."""
    passable, grid, radius_cells = searches.passable, searches.pooled, searches.radius_cells
    must = np.unique(np.asarray(must_rc, np.int64).reshape(-1, 2), axis=0)
    unread = ~np.isfinite(np.stack([f.at(must) for f in fields]))
    # Every (source, cell) pair left at inf needs a search of its own: from the source (one search for
    # all the cells it leaves) or back from the cell (below). A source standing apart from the coarse
    # grid's network (its exact radius reaches no block joined to the rest) leaves most cells at inf:
    # late on a KTH floor one robot of 8 left 17-19 of 18-20 centres, each searched back alone before. As few
    # searches as cover every pair: a minimum vertex cover of the pairs (:func:`_fewest_searches`).
    apart, back = _fewest_searches(unread)
    for i in np.flatnonzero(apart).tolist():
        cells: NDArray[np.int64] = must[unread[i]]
        if own_rc is not None and i < len(own_rc):  # its own goals in the same search
            own = np.asarray(own_rc[i], np.int64).reshape(-1, 2)
            cells = np.vstack([cells, own[~np.isfinite(fields[i].at(own))]])
        for cell, d in zip(cells, searches.unjoined(sources[i], cells, fields[i]), strict=True):
            fields[i].known[(int(cell[0]), int(cell[1]))] = float(d)
    for cell in must[back]:
        # From the cell: exact through its passage, on along the sources' own coarse fields (no search of
        # its own, :func:`_back`); a search of its own on finer blocks, or exact, if need be.
        key = (int(cell[0]), int(cell[1]))
        searched = np.array([key in f.known for f in fields])  # found already, from its source
        d = _back(passable, grid, cell, radius_cells, sources, fields)
        still = ~np.isfinite(d) & ~searched
        if still.any():
            # Ragged free space round the cell joins no block of theirs within the radius. Twice the
            # radius mostly does, at a fraction of an exact search over the floor.
            d[still] = _back(passable, grid, cell, 2 * radius_cells, sources, fields)[still]
            still &= ~np.isfinite(d)
        if still.any():
            d[still] = searches.unjoined(cell, sources[still])
        for f, v, done in zip(fields, d, searched, strict=True):
            if not done:
                f.known[key] = float(v)


def path_to(field: Field | NearFarField, passable: BoolGrid, src_rc: GridRC, goal_rc: GridRC) -> NDArray[np.int32]:
    """A shortest path from the field's source ``src_rc`` to ``goal_rc``, ``(k, 2) int32`` (empty when
    unreachable): read off an exact field, or, for a goal beyond a :class:`NearFarField`'s radius, searched
    exactly inside the corridor of blocks its coarse distances lead along (grown by one block); where the
    corridor holds no path, a search over the whole grid."""
    goal = (int(goal_rc[0]), int(goal_rc[1]))
    if isinstance(field, Field):
        return descend_path(field, passable, goal)
    if field.is_exact(*goal):
        return descend_path(field.near, passable, goal)
    g, f = field.grid, field.grid.factor
    h, w = g.passable.shape
    # The goal's block or the neighbour that explains its estimate, then down the coarse field to a seed.
    br, bc = (goal[0] - g.r0) // f, (goal[1] - g.c0) // f
    # The block the estimate came through: the least block distance plus the exact way from the block's
    # middle to the goal, as :meth:`NearFarField.at` reads it (the least block distance alone could lead
    # the corridor away from the way the estimate measured: a path 17% longer than it, found by a test).
    around = np.array([(br + dr, bc + dc) for dr, dc in _NEIGHBOURHOOD], np.int64)
    tails = g.tails(np.array([goal], np.int64))[0]
    inside = (around[:, 0] >= 0) & (around[:, 0] < h) & (around[:, 1] >= 0) & (around[:, 1] < w)
    around, tails = around[inside], tails[inside]
    values = field.blocks(around[:, 0], around[:, 1]) if len(around) else np.zeros(0)
    if len(values) and np.isfinite(values + tails).any():  # else a distance found otherwise: the least block
        values = values * f + tails
    start = (-1, -1)
    if len(values) and np.isfinite(values.min()):
        start = (int(around[np.argmin(values), 0]), int(around[np.argmin(values), 1]))
    corridor = np.zeros((h, w), dtype=bool)
    if start[0] >= 0:
        if field.portal is not None:
            off = np.array([g.r0 // f, g.c0 // f])
            ways, seed = field.portal.corridor((start[0] + int(off[0]), start[1] + int(off[1])))
            blocks = np.vstack([ways, seed[None]]) - off  # the seed last: the exact part runs back from it
            blocks = blocks[(blocks[:, 0] >= 0) & (blocks[:, 0] < h) & (blocks[:, 1] >= 0) & (blocks[:, 1] < w)]
        else:
            assert field.coarse is not None and field.seed_key is not None
            blocks = descend_to_seed(field.coarse, g.passable, field.seed_key, start[0], start[1])
        corridor[blocks[:, 0], blocks[:, 1]] = True
        # The exact part: from the seed's middle cell back to the robot.
        seed_mid = g.centres_rc(blocks[-1:])[0]
        near_path = descend_path(field.near, passable, (int(seed_mid[0]), int(seed_mid[1])))
        nb_ = (near_path.astype(np.int64) - np.array([g.r0, g.c0])) // f
        inside = (nb_[:, 0] >= 0) & (nb_[:, 0] < h) & (nb_[:, 1] >= 0) & (nb_[:, 1] < w)
        corridor[nb_[inside, 0], nb_[inside, 1]] = True
    for rc in (goal, (int(src_rc[0]), int(src_rc[1]))):
        rr, cc = (rc[0] - g.r0) // f, (rc[1] - g.c0) // f
        if 0 <= rr < h and 0 <= cc < w:
            corridor[rr, cc] = True
    if start[0] >= 0:
        path = _corridor_path(passable, g, corridor, src_rc, goal)
        if len(path):
            return path
    elif field.finer:  # a goal these blocks leave unread: along the source's field on blocks half as wide
        return path_to(field.finer[0], passable, src_rc, goal_rc)
    return descend_path(distance_fields(passable, np.array([src_rc]), np.array([goal]))[0], passable, goal)


def _corridor_path(
    passable: BoolGrid, g: CoarseGrid, corridor: NDArray[np.bool_], src_rc: GridRC, goal: tuple[int, int]
) -> NDArray[np.int32]:
    """The exact shortest path from ``src_rc`` to ``goal`` through the cells of ``corridor``'s blocks grown
    by one block; empty when there is none."""
    f = g.factor
    grown = corridor.copy()
    grown[1:] |= corridor[:-1]
    grown[:-1] |= corridor[1:]
    grown[:, 1:] |= grown[:, :-1].copy()
    grown[:, :-1] |= grown[:, 1:].copy()
    box = mask_box(grown)
    if box is None:
        return np.zeros((0, 2), np.int32)
    b0, b1, k0, k1 = box
    H, W = passable.shape
    r0, c0 = g.r0 + b0 * f, g.c0 + k0 * f
    r1, c1 = min(H, g.r0 + b1 * f), min(W, g.c0 + k1 * f)
    mask = np.repeat(np.repeat(grown[b0:b1, k0:k1], f, axis=0), f, axis=1)[: r1 - r0, : c1 - c0]
    local = passable[r0:r1, c0:c1] & mask
    src = (int(src_rc[0]) - r0, int(src_rc[1]) - c0)
    dst = (goal[0] - r0, goal[1] - c0)
    if not (0 <= src[0] < local.shape[0] and 0 <= src[1] < local.shape[1]):
        return np.zeros((0, 2), np.int32)
    if not (0 <= dst[0] < local.shape[0] and 0 <= dst[1] < local.shape[1]):
        return np.zeros((0, 2), np.int32)
    s = Searches(local, np.array([dst[0] * local.shape[1] + dst[1]], np.int64))
    d = s(*src)
    path = descend_path(Field.whole(np.ascontiguousarray(d)), local, dst)
    return path + np.array([r0, c0], np.int32) if len(path) else path
