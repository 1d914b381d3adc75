"""Denoising by closing and frontier detection by multi-channel kernel convolution (paper IV-A, Fig. 3)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from mrexplore.boxes import cells_of, grown_slices, mask_box
from mrexplore.types import BoolGrid, CellState, StateGrid

__all__ = ["Frontiers", "close_unknown_holes", "closing_reach", "detect_frontiers", "FOUR_NEIGHBOUR_KERNEL"]

FOUR_NEIGHBOUR_KERNEL = np.array([[0, 1, 0], [1, 0, 1], [0, 1, 0]], dtype=np.uint8)
"""The paper's neighbourhood: g(i-1,j), g(i+1,j), g(i,j-1), g(i,j+1)."""


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
    inside the free channel. Cells beyond the grid count as no state.

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
    free = state == CellState.FREE
    un_mask = np.zeros(state.shape, dtype=bool)
    occ_mask = np.zeros(state.shape, dtype=bool)
    box = _known_box(free, 1)  # frontiers are free cells: only the free box (+1 for its neighbours) matters
    if box is None:
        return Frontiers(un_mask=un_mask, occ_mask=occ_mask)
    sub, sub_free = state[box], free[box]
    for s, out in ((CellState.UNKNOWN, un_mask), (CellState.OCCUPIED, occ_mask)):
        out[box] = sub_free & (_convolve_kernel(sub == s, FOUR_NEIGHBOUR_KERNEL) > 0)
    return Frontiers(un_mask=un_mask, occ_mask=occ_mask)


def _convolve_kernel(channel: BoolGrid, kernel: NDArray[np.uint8]) -> NDArray[np.uint8]:
    """``channel`` convolved with a 3 x 3 0/1 kernel, zero beyond the grid: a sum of shifted copies
    (as ``scipy.ndimage.convolve(mode="constant")``, several times faster for so small a kernel)."""
    ch = channel.astype(np.uint8)
    out = np.zeros(ch.shape, dtype=np.uint8)
    H, W = ch.shape
    for dr in (-1, 0, 1):
        for dc in (-1, 0, 1):
            if kernel[1 + dr, 1 + dc]:  # out[r] += ch[r - dr]: the kernel flipped, as a convolution
                out[max(dr, 0) : H + min(dr, 0), max(dc, 0) : W + min(dc, 0)] += ch[
                    max(-dr, 0) : H + min(-dr, 0), max(-dc, 0) : W + min(-dc, 0)
                ]
    return out
