"""Denoising by closing and frontier detection by multi-channel kernel convolution (paper IV-A, Fig. 3)."""

from __future__ import annotations

from dataclasses import dataclass

import numba as nb
import numpy as np
from numpy.typing import NDArray

from mrexplore.maps.boxes import cells_of, grown_slices, mask_box
from mrexplore.types import BoolGrid, CellState, StateGrid

__all__ = [
    "Frontiers",
    "close_unknown_holes",
    "closing_reach",
    "detect_frontiers",
    "redetect_frontiers",
    "FOUR_NEIGHBOUR_KERNEL",
]

FOUR_NEIGHBOUR_KERNEL = np.array([[0, 1, 0], [1, 0, 1], [0, 1, 0]], dtype=np.uint8)
"""The paper's neighbourhood: g(i-1,j), g(i+1,j), g(i,j-1), g(i,j+1) (the four :func:`detect_frontiers`
reads)."""
_FREE, _UNKNOWN, _OCCUPIED = int(CellState.FREE), int(CellState.UNKNOWN), int(CellState.OCCUPIED)
assert (_FREE, _OCCUPIED, _UNKNOWN) == (0, 1, 2)  # the bits _frontier_masks reads


@dataclass(frozen=True)
class Frontiers:
    """Frontier cells of one grid.

    Attributes
    ----------
    un_mask, occ_mask:
        ``(H, W) bool``: F_un (free cells with an unknown 4-neighbour) and F_occ (free cells with an
        occupied 4-neighbour). A cell may be in both.
    """

    un_mask: BoolGrid
    occ_mask: BoolGrid

    @property
    def un_rc(self) -> NDArray[np.int32]:
        """``(n_un, 2) int32`` F_un cells in row-major order."""
        return cells_of(self.un_mask).astype(np.int32)

    @property
    def occ_rc(self) -> NDArray[np.int32]:
        """``(n_occ, 2) int32`` F_occ cells in row-major order."""
        return cells_of(self.occ_mask).astype(np.int32)


def close_unknown_holes(state: StateGrid, size_cells: int) -> StateGrid:
    """Closing of free space (dilation, then erosion), applied only to unknown cells.

    Unknown specks inside free space (gaps between beams) become free; known obstacles are never
    overwritten, so a one-cell wall between two rooms survives (a plain closing would erase it).

    Examples
    --------
    >>> F, O, U = CellState.FREE, CellState.OCCUPIED, CellState.UNKNOWN
    >>> g = np.full((5, 5), F, np.uint8); g[2, 2] = U; g[:, 4] = O
    >>> bool(close_unknown_holes(g, 3)[2, 2] == F)
    True
    """
    if size_cells <= 1:
        return state.copy()
    free = state == CellState.FREE
    out = state.copy()
    box = _known_box(free, size_cells)
    if box is None:
        return out
    r = size_cells // 2
    # Only cells within 2r of free space can change; outside that box the dilation is empty.
    # Erosion is the dilation of the complement; beyond the grid the complement is empty (border 1, as
    # scipy's binary_erosion). Beyond a side of the box inside the grid it is not, but a cell within r of
    # such a side is more than r from free space, so its own dilation is empty and it stays unchanged.
    closed = ~_box_dilate(~_box_dilate(free[box], r), r)
    sub = out[box]
    sub[closed & (sub == CellState.UNKNOWN)] = CellState.FREE
    return out


def closing_reach(size_cells: int) -> int:
    """Cells beyond free space that a closing of ``size_cells`` reads (2 * radius + 1): grids cropped to
    the free cells' box grown by this much close exactly as the whole grid does."""
    return 2 * (size_cells // 2) + 1


def _known_box(mask: BoolGrid, size_cells: int) -> tuple[slice, slice] | None:
    """The bounding box of ``mask`` grown by the closing's reach, clipped to the grid."""
    box = mask_box(mask)
    return None if box is None else grown_slices(box, closing_reach(size_cells), mask.shape)


def _box_dilate(mask: BoolGrid, r: int) -> BoolGrid:
    """Dilation by a (2r+1)-square, separably by shifted ORs; beyond the array counts as False."""
    out = mask.copy()
    for k in range(1, r + 1):
        out[k:] |= mask[:-k]
        out[:-k] |= mask[k:]
    rows = out.copy()
    for k in range(1, r + 1):
        out[:, k:] |= rows[:, :-k]
        out[:, :-k] |= rows[:, k:]
    return out


def detect_frontiers(state: StateGrid) -> Frontiers:
    """F_un and F_occ by convolving the unknown and occupied channels with the 4-neighbour kernel.

    The grid is split into one-hot channels (free, unknown, occupied); a channel convolved with the
    kernel counts, per cell, the 4-neighbours in that state; frontiers are where that count is positive
    inside the free channel. Cells beyond the grid count as no state. Both channels are convolved in one
    compiled pass over the free cells' box (the tests hold it to ``scipy.ndimage.convolve``): the numpy
    sums of shifted channels it replaced took 8-11 ms a decision late on a 4.9 M-cell KTH floor.

    Examples
    --------
    >>> F, O, U = CellState.FREE, CellState.OCCUPIED, CellState.UNKNOWN
    >>> g = np.array([[O, O, O],
    ...               [F, F, U],
    ...               [F, F, F]], np.uint8)
    >>> f = detect_frontiers(g)
    >>> f.un_rc.tolist(), f.occ_rc.tolist()
    ([[1, 1], [2, 2]], [[1, 0], [1, 1]])
    """
    un_mask = np.zeros(state.shape, dtype=bool)
    occ_mask = np.zeros(state.shape, dtype=bool)
    box = mask_box(state == CellState.FREE)
    if box is not None:
        _frontier_masks(state, box, un_mask, occ_mask)
    return Frontiers(un_mask=un_mask, occ_mask=occ_mask)


def redetect_frontiers(state: StateGrid, box: tuple[int, int, int, int], un_mask: BoolGrid, occ_mask: BoolGrid) -> None:
    """Bring ``un_mask`` and ``occ_mask`` (:func:`detect_frontiers` of an earlier ``state``) up to date in
    place where ``state`` changed, ``box``: a cell's labels read it and its 4-neighbours, so they are redone
    in the box grown by one cell, and nowhere else can they differ.

    Examples
    --------
    >>> F, O, U = CellState.FREE, CellState.OCCUPIED, CellState.UNKNOWN
    >>> g = np.full((3, 5), F, np.uint8); g[:, 4] = U
    >>> f = detect_frontiers(g)
    >>> g[:, 4] = F; g[1, 0] = O  # the right column seen free, an obstacle on the left
    >>> redetect_frontiers(g, (0, 3, 4, 5), f.un_mask, f.occ_mask)  # the unknown column only
    >>> redetect_frontiers(g, (1, 2, 0, 1), f.un_mask, f.occ_mask)  # the obstacle
    >>> f.un_rc.tolist(), f.occ_rc.tolist()
    ([], [[0, 0], [1, 1], [2, 0]])
    """
    H, W = state.shape
    r0, r1, c0, c1 = max(box[0] - 1, 0), min(box[1] + 1, H), max(box[2] - 1, 0), min(box[3] + 1, W)
    un_mask[r0:r1, c0:c1] = False
    occ_mask[r0:r1, c0:c1] = False
    _frontier_masks(state, (r0, r1, c0, c1), un_mask, occ_mask)


@nb.njit(cache=True, nogil=True)
def _frontier_masks(
    state: np.ndarray, box: tuple[int, int, int, int], un_mask: np.ndarray, occ_mask: np.ndarray
) -> None:  # pragma: no cover - numba
    """Mark in ``un_mask`` and ``occ_mask`` (all False on entry) the free cells of ``box`` with an unknown /
    occupied 4-neighbour: the two channels' counts and their test for > 0 at once. The states' bits do
    it (free 0, occupied 1, unknown 2: the OR of the four neighbours holds bit 1 where one is unknown,
    bit 0 where one is occupied), and only frontier cells are written."""
    H, W = state.shape
    r0, r1, c0, c1 = box
    for r in range(max(r0, 1), min(r1, H - 1)):
        up, me, down = state[r - 1], state[r], state[r + 1]
        for c in range(max(c0, 1), min(c1, W - 1)):
            n = up[c] | down[c] | me[c - 1] | me[c + 1]
            if n != 0 and me[c] == _FREE:
                if n & _UNKNOWN:
                    un_mask[r, c] = True
                if n & _OCCUPIED:
                    occ_mask[r, c] = True
    for r in (0, H - 1):  # the grid's own edges: a neighbour beyond the grid counts as no state
        if r0 <= r < r1:
            for c in range(c0, c1):
                _mark_edge_cell(state, r, c, un_mask, occ_mask)
    for c in (0, W - 1):
        if c0 <= c < c1:
            for r in range(r0, r1):
                _mark_edge_cell(state, r, c, un_mask, occ_mask)


@nb.njit(cache=True, nogil=True, inline="always")
def _mark_edge_cell(
    state: np.ndarray, r: int, c: int, un_mask: np.ndarray, occ_mask: np.ndarray
) -> None:  # pragma: no cover - numba
    H, W = state.shape
    if state[r, c] != _FREE:
        return
    n = 0
    for rr, cc in ((r - 1, c), (r + 1, c), (r, c - 1), (r, c + 1)):
        if 0 <= rr < H and 0 <= cc < W:
            n |= state[rr, cc]
    un_mask[r, c] = (n & _UNKNOWN) != 0
    occ_mask[r, c] = (n & _OCCUPIED) != 0
