"""The procedural floor plan: closed, connected, seeded."""

from __future__ import annotations

import numpy as np
import pytest

from mrexplore.maps.floorplan import FloorplanSpec, generate_floorplan
from mrexplore.maps.ground_truth import free_components
from mrexplore.types import MrExploreError


@pytest.mark.parametrize("seed", range(8))
def test_every_room_reachable_and_outer_wall_closed(seed: int) -> None:
    occ = generate_floorplan(FloorplanSpec(seed=seed), 0.1)
    _, n = free_components(occ)
    assert n == 1
    assert occ[0].all() and occ[-1].all() and occ[:, 0].all() and occ[:, -1].all()
    assert 0.6 < (~occ).mean() < 0.95


def test_same_seed_same_plan_other_seed_other_plan() -> None:
    a = generate_floorplan(FloorplanSpec(seed=4), 0.05)
    assert np.array_equal(a, generate_floorplan(FloorplanSpec(seed=4), 0.05))
    assert not np.array_equal(a, generate_floorplan(FloorplanSpec(seed=5), 0.05))


def test_bad_spec_is_refused() -> None:
    with pytest.raises(MrExploreError, match="floor plan must be > 4 m a side, got 3.0 x 12.0"):
        FloorplanSpec(width_m=3.0)
