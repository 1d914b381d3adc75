"""NCM's candidates: frontier cells clear of obstacles, pooled to 0.4 m nodes, on ASCII maps."""

from __future__ import annotations

import numpy as np
from conftest import cells, state_grid

from mrexplore.global_planning.ncm_nodes import ncm_frontier, pool_nodes
from mrexplore.preprocessing.frontiers import detect_frontiers
from mrexplore.types import CellState

# 0.1 m cells: a room whose right side opens on unknown space; an obstacle stub in the middle.
ROOM = """
    ##########
    #........?
    #........?
    #....#...?
    #........?
    #........?
    #........?
    #........?
    ##########
"""


def test_frontier_keeps_clear_of_obstacles() -> None:
    g = state_grid(ROOM)
    f = ncm_frontier(g, detect_frontiers(g), resolution_m=0.1, clearance_m=0.2)
    # F_un is column 8, rows 1-7; rows 1 and 7 lie 0.1 m from the outer wall, row 2 and 6 0.2 m: dropped.
    assert np.argwhere(f).tolist() == [[3, 8], [4, 8], [5, 8]]
    assert np.argwhere(ncm_frontier(g, detect_frontiers(g), 0.1, 0.0)).tolist() == [[r, 8] for r in range(1, 8)]


def test_pooling_gives_one_node_per_block_nearest_its_centre() -> None:
    frontier = np.zeros((9, 10), bool)
    marked = cells(
        """
        ..........
        ........x.
        ........x.
        ........x.
        ........x.
        ........x.
        ........x.
        ........x.
        ..........
        """
    )
    for r, c in marked:
        frontier[r, c] = True
    # 0.4 m blocks of 4 x 4 cells: rows 0-3, 4-7 and 8; the frontier of column 8 falls in blocks (0, 2)
    # and (1, 2); block centres at row 1.5 and 5.5, column 9.5: cells (1, 8) / (2, 8) tie, the first wins.
    assert pool_nodes(frontier, 0.1, 0.4).tolist() == [[1, 8], [5, 8]]
    assert pool_nodes(frontier, 0.1, 0.1).tolist() == marked  # a block per cell: every cell is a node
    assert pool_nodes(np.zeros((5, 5), bool), 0.1).shape == (0, 2)


def test_clearance_matches_a_distance_transform_of_the_whole_grid() -> None:
    """The frontier-only test drops exactly the cells a Euclidean distance transform of the grid puts within
    the clearance of an obstacle, on 200 random grids, cell sizes and clearances."""
    import math

    from scipy import ndimage

    rng = np.random.default_rng(0)
    states = [CellState.FREE, CellState.OCCUPIED, CellState.UNKNOWN]
    for _ in range(200):
        H, W = rng.integers(3, 30, 2)
        g = rng.choice(states, size=(H, W), p=[0.6, 0.15, 0.25]).astype(np.uint8)
        res, clearance = float(rng.choice([0.05, 0.07, 0.1, 0.2])), float(rng.choice([0.0, 0.05, 0.15, 0.2, 0.3]))
        f = detect_frontiers(g)
        occupied = g == CellState.OCCUPIED
        want = f.un_mask.copy()
        if math.ceil(clearance / res - 1e-9) > 0 and occupied.any():
            want &= ~(ndimage.distance_transform_edt(~occupied) <= clearance / res + 1e-9)
        assert np.array_equal(ncm_frontier(g, f, res, clearance), want)
