"""Closing and frontier detection on hand-checked ASCII maps."""

from __future__ import annotations

import numpy as np
from conftest import cells, state_grid

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
