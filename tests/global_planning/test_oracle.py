"""The full-knowledge yardstick: greedy viewpoint cover and the routes cut from one tour."""

from __future__ import annotations

import numpy as np
from conftest import bool_grid

from mrexplore.global_planning.oracle import greedy_cover, plan_oracle_routes, viewpoint_footprints
from mrexplore.global_planning.tours import split_tour
from mrexplore.maps.ground_truth import explorable_region

# Two rooms joined by a corridor; with a 3-cell sensor no single cell sees both rooms.
ROOMS = """
    ##################
    #.....######.....#
    #.....######.....#
    #................#
    #.....######.....#
    #.....######.....#
    ##################
"""


def test_cover_sees_every_explorable_cell_and_routes_share_the_viewpoints() -> None:
    occ = bool_grid(ROOMS)
    starts = np.array([[3, 1], [3, 2]])
    explorable = explorable_region(occ, starts)
    plan = plan_oracle_routes(occ, explorable, starts, range_cells=3.0, ray_oversampling=1.0, spacing_cells=1)
    footprints, n = viewpoint_footprints(occ, explorable, plan.viewpoints_rc, 3.0, 1.0)
    seen = np.zeros(n, bool)
    for f in footprints:
        seen[f] = True
    assert seen.all()
    routed = np.vstack([r for r in plan.routes if len(r)])
    assert sorted(map(tuple, routed.tolist())) == sorted(map(tuple, plan.viewpoints_rc.tolist()))
    assert len(plan.routes) == 2


def test_greedy_cover_stops_when_nothing_new() -> None:
    assert greedy_cover([np.array([0, 1], np.int32), np.array([1], np.int32)], 3) == [0]
    assert greedy_cover([], 0) == []


def test_split_never_worse_than_one_robot() -> None:
    rng = np.random.default_rng(1)
    for _ in range(50):
        m = int(rng.integers(1, 12))
        d_start, legs = rng.uniform(0, 10, m), rng.uniform(0, 10, m - 1)
        pieces = split_tour(d_start, legs, 3)
        cost = max(d_start[i] + legs[i : j - 1].sum() for i, j in pieces)
        assert len(pieces) <= 3 and pieces[0][0] == 0 and pieces[-1][1] == m
        assert all(a[1] == b[0] for a, b in zip(pieces, pieces[1:], strict=False))
        assert cost <= d_start[0] + legs.sum() + 1e-9
