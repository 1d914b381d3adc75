"""Closing and frontier detection on hand-checked ASCII maps."""

from __future__ import annotations

import numpy as np
from conftest import cells, state_grid
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy import ndimage

from mrexplore.preprocessing.frontiers import close_unknown_holes, detect_frontiers
from mrexplore.types import CellState


def test_frontiers_exact_on_ascii_map() -> None:
    grid = state_grid("""
        #######
        #....??
        #.#..??
        #....#?
        #######
    """)
    f = detect_frontiers(grid)
    assert f.un_rc.tolist() == cells("""
        .......
        ....x..
        ....x..
        .......
        .......
    """)  # (3,4) touches the wall at (3,5), not the unknown at (3,6)
    # Free cells with an occupied 4-neighbour (walls around, the pillar at (2,2), the wall at (3,5)).
    assert f.occ_rc.tolist() == cells("""
        .......
        .xxxx..
        .x.x...
        .xxxx..
        .......
    """)


def test_cells_beyond_the_grid_are_no_frontier() -> None:
    f = detect_frontiers(state_grid("..\n.."))
    assert not f.un_mask.any() and not f.occ_mask.any()


def test_closing_fills_unknown_specks_but_keeps_thin_walls() -> None:
    grid = state_grid("""
        .......
        ...?...
        .......
        ###.###
        .......
    """)
    closed = close_unknown_holes(grid, 3)
    assert closed[1, 3] == CellState.FREE  # a speck between beams
    assert np.array_equal(closed[3], grid[3])  # the one-cell wall survives
    assert not detect_frontiers(closed).un_mask.any()


def test_closing_leaves_large_unknown_alone() -> None:
    grid = state_grid("""
        ...??
        ...??
        ...??
    """)
    assert np.array_equal(close_unknown_holes(grid, 3), grid)


def _scipy_closing(state: np.ndarray, size: int) -> np.ndarray:
    structure = np.ones((size, size), dtype=bool)
    free = state == CellState.FREE
    closed = ndimage.binary_erosion(ndimage.binary_dilation(free, structure), structure, border_value=1)
    out = state.copy()
    out[closed & (state == CellState.UNKNOWN)] = CellState.FREE
    return out


@settings(max_examples=300, deadline=None)
@given(st.integers(0, 10**6), st.integers(1, 30), st.integers(1, 30), st.booleans())
def test_closing_and_frontiers_equal_scipy(seed: int, h: int, w: int, one_room: bool) -> None:
    # The shifted-slice morphology and convolution (cropped to the free box) against scipy.ndimage.
    rng = np.random.default_rng(seed)
    grid = rng.choice(np.array([CellState.FREE, CellState.OCCUPIED, CellState.UNKNOWN], np.uint8), (h, w))
    if one_room:  # mostly unknown: the crop is much smaller than the grid
        grid[:] = CellState.UNKNOWN
        r, c = rng.integers(0, h), rng.integers(0, w)
        grid[r : r + rng.integers(1, 8), c : c + rng.integers(1, 8)] = CellState.FREE
    for size in (1, 3, 5):
        np.testing.assert_array_equal(close_unknown_holes(grid, size), _scipy_closing(grid, size))
    f = detect_frontiers(grid)
    free = grid == CellState.FREE
    kernel = np.array([[0, 1, 0], [1, 0, 1], [0, 1, 0]])
    for mask, s in ((f.un_mask, CellState.UNKNOWN), (f.occ_mask, CellState.OCCUPIED)):
        count = ndimage.convolve((grid == s).astype(np.uint8), kernel, mode="constant", cval=0)
        np.testing.assert_array_equal(mask, free & (count > 0))
