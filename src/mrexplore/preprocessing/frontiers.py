"""Denoising by closing and frontier detection by multi-channel kernel convolution (paper IV-A, Fig. 3)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy import ndimage

from mrexplore.types import BoolGrid, CellState, StateGrid

__all__ = ["Frontiers", "close_unknown_holes", "detect_frontiers", "FOUR_NEIGHBOUR_KERNEL"]

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
        return np.argwhere(self.un_mask).astype(np.int32)

    @property
    def occ_rc(self) -> NDArray[np.int32]:
        """``(n_occ, 2) int32`` F_occ cells in row-major order."""
        return np.argwhere(self.occ_mask).astype(np.int32)


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
    structure = np.ones((size_cells, size_cells), dtype=bool)
    free = state == CellState.FREE
    closed = ndimage.binary_erosion(ndimage.binary_dilation(free, structure), structure, border_value=1)
    out = state.copy()
    out[closed & (state == CellState.UNKNOWN)] = CellState.FREE
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
    channels = {s: (state == s).astype(np.uint8) for s in (CellState.UNKNOWN, CellState.OCCUPIED)}
    counts = {s: ndimage.convolve(ch, FOUR_NEIGHBOUR_KERNEL, mode="constant", cval=0) for s, ch in channels.items()}
    return Frontiers(un_mask=free & (counts[CellState.UNKNOWN] > 0), occ_mask=free & (counts[CellState.OCCUPIED] > 0))
