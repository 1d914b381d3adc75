"""Explorable region: reachable free space plus the obstacles 4-adjacent to it."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import bool_grid

from mrexplore.maps.ground_truth import explorable_region
from mrexplore.types import MrExploreError


def test_explorable_region_by_hand() -> None:
    occ = bool_grid("""
        #####
        #..##
        #####
        #.#.#
        #####
    """)
    got = explorable_region(occ, np.array([[1, 1]]))
    want = bool_grid(
        """
        .xx..
        xxxx.
        .xx..
        .....
        .....
    """,
        true="x",
    )
    assert np.array_equal(got, want)


def test_start_in_wall_refused() -> None:
    with pytest.raises(MrExploreError, match="a start lies inside a wall"):
        explorable_region(bool_grid("##\n#."), np.array([[0, 0]]))
