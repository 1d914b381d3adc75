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
    with pytest.raises(MrExploreError, match=r"floor plan needs clutter_prob in \[0, 1\], got 1.5"):
        FloorplanSpec(clutter_prob=1.5)
    with pytest.raises(MrExploreError, match="floor plan needs corridor_m >= 0 and 0 < fill <= 1"):
        FloorplanSpec(fill=0.0)


def test_outline_drops_outer_rooms_until_the_fill_and_keeps_the_rest_connected() -> None:
    from mrexplore.maps.floorplan import _outline

    # a 3 x 2 grid of 4 m rooms in a 12 x 8 m building: every room is on the building's edge
    rooms = [(4.0 * c, 4.0 * r, 4.0 * c + 4, 4.0 * r + 4) for r in range(2) for c in range(3)]
    adjacent = [(0, 1), (1, 2), (3, 4), (4, 5), (0, 3), (1, 4), (2, 5)]
    spec = FloorplanSpec(width_m=12.0, height_m=8.0, fill=0.5)
    for seed in range(20):
        keep = _outline(np.random.default_rng(seed), spec, rooms, adjacent, corridor_ix=-1)
        assert sum(keep) == 3  # 3 of 6 equal rooms leave exactly half
        alive = {i for i in range(6) if keep[i]}
        links = [(i, j) for i, j in adjacent if i in alive and j in alive]
        assert len(links) >= 2  # three rooms joined by two walls at least: connected
    # the corridor (here room 1) is never dropped, nor are the last three rooms
    keep = _outline(np.random.default_rng(0), FloorplanSpec(width_m=12.0, height_m=8.0, fill=0.1), rooms, adjacent, 1)
    assert keep[1] and sum(keep) == 3


def test_corridor_runs_the_building_long_side() -> None:
    spec = FloorplanSpec(seed=2, width_m=20.0, height_m=10.0, corridor_m=1.5)
    occ = generate_floorplan(spec, 0.1)
    inner = ~occ[:, 3:-3]  # inside the outer walls
    assert inner.all(axis=1).sum() >= 12  # at least 1.2 m of rows free from end to end: the corridor
    assert free_components(occ)[1] == 1


def test_clutter_keeps_a_metre_from_walls() -> None:
    from scipy import ndimage

    plain = FloorplanSpec(seed=5, width_m=14.0, height_m=10.0, max_room_m=8.0, min_room_m=4.0)
    cluttered = FloorplanSpec(**{**plain.__dict__, "clutter_prob": 1.0})
    a, b = generate_floorplan(plain, 0.1), generate_floorplan(cluttered, 0.1)
    blocks = b & ~a
    assert blocks.any() and not (a & ~b).any()  # only blocks were added
    clearance_m = ndimage.distance_transform_edt(~a) * 0.1
    assert clearance_m[blocks].min() >= 1.0 - 0.1  # a cell of rounding
    assert free_components(b)[1] == 1


@pytest.mark.parametrize("seed", range(40))
def test_varied_plans_are_closed_connected_and_differ_in_size(seed: int) -> None:
    spec = FloorplanSpec.varied(seed)
    occ = generate_floorplan(spec, 0.1)
    assert free_components(occ)[1] == 1
    assert occ[0].all() and occ[-1].all() and occ[:, 0].all() and occ[:, -1].all()
    assert 60 * 0.5 <= (~occ).sum() * 0.01 <= 500
    assert 4.5 <= spec.width_m <= 36 and 4.5 <= spec.height_m <= 36


def test_varied_plans_spread() -> None:
    sizes = [FloorplanSpec.varied(s).width_m * FloorplanSpec.varied(s).height_m for s in range(200)]
    assert min(sizes) < 80 and max(sizes) > 400
    assert sum(FloorplanSpec.varied(s).corridor_m > 0 for s in range(200)) > 40
