"""The sparse frontier map a robot sends instead of its grid (paper IV-A): F_un and F_occ with neighbour codes.

A robot's free space is its boundary (the free cells with a non-free 4-neighbour: exactly F_un ∪ F_occ)
plus the interior those cells enclose. The message lists the boundary cells, each with a one-byte
*neighbour code* saying which of its 4 neighbours are unknown (bits 0-3) and which occupied (bits 4-7), in
the order up, down, left, right. The label the paper sends is in the code: F_un is a non-zero low nibble,
F_occ a non-zero high nibble. With the code, the centre's fill may step out of a boundary cell towards
every neighbour the code does not flag, so one seed per free component rebuilds the component exactly,
thin corridors and rooms behind doors included (the paper seeds only at the robot's position and stops at
boundary cells, which loses every room reached through a passage too thin to hold an interior cell).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from mrexplore.maps.boxes import Box
from mrexplore.preprocessing.scanline_fill import coded_cells, neighbour_codes_kernel, pick_seeds
from mrexplore.types import CellState, GridRC, StateGrid  # noqa: F401 - CellState: the examples use it

__all__ = [
    "SparseFrontierMap",
    "DIRECTIONS",
    "neighbour_codes",
    "component_seeds",
    "sparse_frontier_map",
    "coded_frontier_map",
    "changed_since",
    "changed_in_box",
    "apply_delta",
    "FULL",
]

DIRECTIONS = ((-1, 0), (1, 0), (0, -1), (0, 1))
"""Neighbour order of a code's bits: up, down, left, right (bit d: unknown, bit 4 + d: occupied)."""
FULL = -1
"""``base_round`` of a full map (not a delta)."""


@dataclass(frozen=True)
class SparseFrontierMap:
    """One robot's message for one communication round.

    Attributes
    ----------
    robot, round:
        Sender and its round number (>= 0).
    shape:
        ``(H, W)`` of the shared map grid the indices refer to.
    position_rc:
        The robot's cell (the paper's s_ri).
    cells:
        ``(n,) int64`` strictly increasing row-major indices. A full map lists every boundary cell; a delta
        lists the cells whose code changed since ``base_round``.
    codes:
        ``(n,) uint8`` neighbour code of each listed cell; in a delta, 0 means "no longer boundary".
    seeds:
        ``(m,) int64`` strictly increasing row-major indices, one free cell per free component that has
        interior cells (the robot's own cell seeds its component).
    base_round:
        :data:`FULL`, or the acknowledged round a delta applies to.
    """

    robot: int
    round: int
    shape: tuple[int, int]
    position_rc: GridRC
    cells: NDArray[np.int64] = field(repr=False)
    codes: NDArray[np.uint8] = field(repr=False)
    seeds: NDArray[np.int64] = field(repr=False)
    base_round: int = FULL

    @property
    def is_delta(self) -> bool:
        return self.base_round != FULL

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, SparseFrontierMap):
            return NotImplemented
        return (
            (self.robot, self.round, self.shape, self.position_rc, self.base_round)
            == (other.robot, other.round, other.shape, other.position_rc, other.base_round)
            and np.array_equal(self.cells, other.cells)
            and np.array_equal(self.codes, other.codes)
            and np.array_equal(self.seeds, other.seeds)
        )

    def code_grid(self) -> NDArray[np.uint8]:
        """``(H, W) uint8`` the codes painted on an empty grid (a full map's boundary)."""
        grid = np.zeros(self.shape, dtype=np.uint8)
        grid.ravel()[self.cells] = self.codes
        return grid


def neighbour_codes(state: StateGrid) -> NDArray[np.uint8]:
    """Neighbour code of every free cell (0 for interior and non-free cells); cells beyond the grid count
    as no state, like :func:`~mrexplore.preprocessing.frontiers.detect_frontiers`.

    Examples
    --------
    >>> F, O, U = CellState.FREE, CellState.OCCUPIED, CellState.UNKNOWN
    >>> g = np.array([[O, O, O],
    ...               [F, F, U],
    ...               [F, F, F]], np.uint8)
    >>> neighbour_codes(g).tolist()  # (1,1): occupied up (bit 4), unknown right (bit 3)
    [[0, 0, 0], [16, 24, 0], [0, 0, 1]]
    """
    return neighbour_codes_kernel(np.ascontiguousarray(state, dtype=np.uint8))


def component_seeds(
    state: StateGrid, codes: NDArray[np.uint8], position_rc: GridRC, n_free: int | None = None
) -> NDArray[np.int64]:
    """One seed per 4-connected free component of ``state`` that has an interior cell (code 0): the
    robot's cell for its own component, the first interior cell in row-major order for the others,
    sorted. Components made of boundary cells only need none: every one of their cells is in the message.
    ``n_free``: the number of free cells of ``state``, where the caller keeps it (saves a pass when the
    robot's component holds them all)."""
    r, c = position_rc
    inside = 0 <= r < state.shape[0] and 0 <= c < state.shape[1]
    position = r * state.shape[1] + c if inside else -1
    return np.sort(pick_seeds(codes, state, position, -1 if n_free is None else n_free, np.zeros(1, np.int64)))


def sparse_frontier_map(
    state: StateGrid,
    robot: int,
    round_: int,
    position_rc: GridRC,
    origin_rc: GridRC = (0, 0),
    shape: tuple[int, int] | None = None,
) -> SparseFrontierMap:
    """Build a robot's full message from its (closed) grid.

    Parameters
    ----------
    state:
        ``(h, w) uint8`` the robot's closed grid, or a window of it: with ``origin_rc`` (the window's first
        cell in the map) and ``shape`` (the map's), the message indexes the whole map. A window must hold
        every free cell of the robot with a margin of one cell (beyond a window counts as no state).
    position_rc:
        The robot's cell in the map.

    Examples
    --------
    >>> F, O = CellState.FREE, CellState.OCCUPIED
    >>> g = np.full((5, 5), O, np.uint8); g[1:4, 1:4] = F
    >>> m = sparse_frontier_map(g, 0, 0, (2, 2))
    >>> len(m.cells), m.seeds.tolist()  # 8 boundary cells around one interior cell, the robot's
    (8, [12])
    >>> big = np.full((7, 7), O, np.uint8); big[2:5, 2:5] = F
    >>> whole = sparse_frontier_map(big, 0, 0, (3, 3))
    >>> sparse_frontier_map(big[1:6, 1:6], 0, 0, (3, 3), origin_rc=(1, 1), shape=(7, 7)) == whole
    True
    """
    return coded_frontier_map(state, neighbour_codes(state), robot, round_, position_rc, origin_rc, shape)


def coded_frontier_map(
    state: StateGrid,
    codes: NDArray[np.uint8],
    robot: int,
    round_: int,
    position_rc: GridRC,
    origin_rc: GridRC = (0, 0),
    shape: tuple[int, int] | None = None,
    cells: NDArray[np.int64] | None = None,
    n_free: int | None = None,
    seeds: NDArray[np.int64] | None = None,
) -> SparseFrontierMap:
    """:func:`sparse_frontier_map` from a grid whose neighbour codes (``(h, w) uint8``, those of
    :func:`neighbour_codes` on the whole map, cut to the window) the robot already holds; ``cells``, the
    map indices of the cells with a code (sorted), ``n_free``, the free cells, and ``seeds``, the window's
    :func:`component_seeds`, where it keeps them."""
    shape = state.shape if shape is None else shape
    r0, c0 = origin_rc
    r, c = int(position_rc[0]), int(position_rc[1])
    if cells is None:
        cells, values = coded_cells(codes, r0, c0, shape[1])
    else:
        values = codes[cells // shape[1] - r0, cells % shape[1] - c0]
    if seeds is None:
        seeds = component_seeds(state, codes, (r - r0, c - c0), n_free)
    return SparseFrontierMap(
        robot, round_, shape, (r, c), cells, values, _to_map(seeds, state.shape[1], r0, c0, shape[1])
    )


def _to_map(local: NDArray[np.int64], w: int, r0: int, c0: int, width: int) -> NDArray[np.int64]:
    """Row-major indices in a window of width ``w`` at ``(r0, c0)`` as indices in the map (order kept)."""
    return (local // w + r0) * width + (local % w + c0)


def changed_since(
    previous: NDArray[np.uint8],
    current: SparseFrontierMap,
    base_round: int,
    window: tuple[slice, slice] | None = None,
) -> SparseFrontierMap:
    """The delta of a full map ``current`` against the code grid ``previous`` acknowledged at ``base_round``:
    only the cells whose code changed (RACER-style incremental sharing); seeds are always sent whole.

    ``window``: compare only there, when both maps have every boundary cell inside it."""
    if window is None:
        window = (slice(0, current.shape[0]), slice(0, current.shape[1]))
    rows, cols = window
    h, w = rows.stop - rows.start, cols.stop - cols.start
    width = current.shape[1]
    now = np.zeros((h, w), dtype=np.uint8)
    now[current.cells // width - rows.start, current.cells % width - cols.start] = current.codes
    local = np.flatnonzero(now != previous[window]).astype(np.int64)
    return SparseFrontierMap(
        current.robot,
        current.round,
        current.shape,
        current.position_rc,
        _to_map(local, w, rows.start, cols.start, width),
        now.ravel()[local],
        current.seeds,
        base_round,
    )


def changed_in_box(
    previous: NDArray[np.uint8], codes: NDArray[np.uint8], current: SparseFrontierMap, base_round: int, box: Box
) -> SparseFrontierMap:
    """:func:`changed_since` when the sender holds its whole code grid ``codes`` ``(H, W) uint8`` and knows
    that no code changed since ``base_round`` outside ``box``: compares there alone (same message)."""
    rows, cols = slice(box[0], box[1]), slice(box[2], box[3])
    now = codes[rows, cols]
    local = np.flatnonzero(now != previous[rows, cols]).astype(np.int64)
    return SparseFrontierMap(
        current.robot,
        current.round,
        current.shape,
        current.position_rc,
        _to_map(local, now.shape[1], box[0], box[2], current.shape[1]),
        now.ravel()[local],
        current.seeds,
        base_round,
    )


def apply_delta(codes: NDArray[np.uint8], delta: SparseFrontierMap) -> None:
    """Write a delta's codes into the receiver's code grid of that robot, in place."""
    np.put(codes, delta.cells, delta.codes)
