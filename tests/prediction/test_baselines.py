"""The predictors that need no learning and the scores of a prediction, on hand-drawn maps."""

from __future__ import annotations

import numpy as np
from conftest import bool_grid, cells, state_grid

from mrexplore.prediction.baselines import extend_walls, predict_all_free, predict_extended_walls
from mrexplore.prediction.quality import near_frontier, score

# A room seen from its west half: its north and south walls run on into the unknown east half.
BELIEF = """
    ##########??????
    #.........??????
    #.........??????
    #.........??????
    ##########??????
"""
TRUTH = """
    ################
    #..............#
    #..............#
    #..............#
    ################
"""


def test_walls_run_on_straight_into_the_unknown_and_nothing_else_does() -> None:
    state = state_grid(BELIEF)
    walls = extend_walls(state, resolution_m=1.0, min_wall_m=3, reach_m=4)
    assert cells("\n".join("".join(r) for r in np.where(walls, "x", "."))) == [
        [0, 10], [0, 11], [0, 12], [0, 13], [4, 10], [4, 11], [4, 12], [4, 13],
    ]  # fmt: skip
    p = predict_extended_walls(state, 1.0)  # the default 5 m reach: 5 cells on, the sixth left free
    assert p[0, 10:].tolist() == [0.0] * 5 + [1.0] and p[2, 10:].tolist() == [1.0] * 6 and p[2, 0] == 0.0


def test_the_frontier_band_holds_unknown_cells_within_the_radius() -> None:
    state = state_grid(BELIEF)
    band = near_frontier(state, resolution_m=1.0, radius_m=2.0)
    # F_un: column 9 of rows 1-3; the unknown cells within 2 m of one ((0, 11) is sqrt(5) m from (1, 9))
    assert cells("\n".join("".join(r) for r in np.where(band, "x", "."))) == [
        [0, 10], [1, 10], [1, 11], [2, 10], [2, 11], [3, 10], [3, 11], [4, 10],
    ]  # fmt: skip


def test_extending_the_walls_scores_better_than_all_free_on_the_room() -> None:
    state, truth_free = state_grid(BELIEF), ~bool_grid(TRUTH)
    band = near_frontier(state, 1.0, 6.0)
    free = score(predict_all_free(state, 1.0), truth_free, band)
    walls = score(predict_extended_walls(state, 1.0), truth_free, band)
    # 28 unknown cells within 6 m ((0, 15) and (4, 15) lie farther): 13 wall (the two walls' 10 cells on,
    # the east wall's 3), 15 free
    assert free.cells == walls.cells == 28
    assert (free.accuracy, free.iou) == (15 / 28, 15 / 28)
    # the two walls predicted; the east wall, which no seen wall leads to, predicted free
    assert (walls.accuracy, walls.iou) == (25 / 28, 15 / 18)
