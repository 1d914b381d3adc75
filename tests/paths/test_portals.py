"""The portal graph: where portals go, distances against a plain Dijkstra over the blocks, the graph kept
across changes equal to one built afresh, the way back to a seed, and far fields searched on it."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import bool_grid, seeded_dijkstra
from hypothesis import given, settings
from hypothesis import strategies as st

from mrexplore.config import GlobalPlanningConfig
from mrexplore.paths.distance_field import distance_fields
from mrexplore.paths.far_field import coarse_grid, far_fields, path_to
from mrexplore.paths.portals import PortalGraph
from mrexplore.types import MrExploreError

# Two sectors of 4 x 4 blocks side by side; the border between them is columns 3 | 4.
TWO_SECTORS = """
    ........
    ...#....
    ...##...
    ........
"""


def graph_of(blocks: np.ndarray, sector: int, spacing: int) -> PortalGraph:
    g = PortalGraph(blocks.shape, sector, spacing)
    g.refresh(blocks, 0, 0)
    return g


def node_blocks(g: PortalGraph, slot: int) -> list[list[int]]:
    return sorted(g.nodes[slot, : g.n_nodes[slot]].tolist())


def test_one_portal_per_short_opening_at_its_middle_and_edges_across_the_border() -> None:
    g = graph_of(~bool_grid(TWO_SECTORS), 4, 2)
    # Passable pairs across columns 3 | 4: row 0 (a run of 1) and row 3 (a run of 1); rows 1 and 2 hold walls.
    assert node_blocks(g, 0) == [[0, 3], [3, 3]]
    assert node_blocks(g, 1) == [[0, 4], [3, 4]]
    k = node_blocks(g, 0).index([0, 3])
    right = int(g.node_at[0, 4])
    assert right in g.inter[0, k].tolist()  # the step across the border, one block long


def test_a_long_opening_gets_a_portal_per_spacing() -> None:
    g = graph_of(np.ones((4, 8), bool), 4, 2)
    # An open border of 4 blocks with portals every 2: the middles of its two halves, rows 1 and 3.
    assert node_blocks(g, 0) == [[1, 3], [3, 3]]
    # Inside the sector the two nodes are 2 blocks apart (a straight way).
    assert g.intra[0, 0, 1] == pytest.approx(2.0)


def test_a_corridor_through_sectors_is_exact() -> None:
    blocks = np.zeros((12, 12), bool)
    blocks[5, :] = True  # one block wide: every way crosses each border at the portal
    g = graph_of(blocks, 4, 3)
    src = g.node_at[5, 3]  # the node at the first border
    assert src >= 0
    field = g.search(np.array([src]), np.zeros(1))
    got = field.values(np.array([[5, c] for c in range(12)]))
    np.testing.assert_allclose(got, np.abs(np.arange(12) - 3.0))


def random_blocks(seed: int, shape: tuple[int, int] = (14, 17)) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return rng.random(shape) < 0.8


@settings(max_examples=60, deadline=None)
@given(st.integers(0, 10**6), st.sampled_from([(3, 1), (4, 2), (5, 3)]))
def test_distances_are_real_ways_and_reach_what_the_blocks_reach(seed: int, sk: tuple[int, int]) -> None:
    """From one node, a portal distance is never shorter than the plain Dijkstra's over the blocks
    (every one is the length of a real way) and is finite exactly where that one is."""
    blocks = random_blocks(seed)
    g = graph_of(blocks, *sk)
    valid = np.flatnonzero(np.arange(g.max_nodes)[None, :] < g.n_nodes[:, None])
    if not len(valid):
        return
    u = int(valid[np.random.default_rng(seed).integers(len(valid))])
    r, c = g.nodes[u // g.max_nodes, u % g.max_nodes]
    want = seeded_dijkstra(blocks, [(int(r), int(c), 0.0)])
    every = np.argwhere(np.ones(blocks.shape, bool))
    got = g.search(np.array([u]), np.zeros(1)).values(every).reshape(blocks.shape)
    assert (np.isfinite(got) == np.isfinite(want)).all()
    fin = np.isfinite(want)
    assert (got[fin] >= want[fin] - 1e-3).all()


@settings(max_examples=60, deadline=None)
@given(st.integers(0, 10**6), st.integers(1, 30))
def test_the_graph_kept_across_changes_is_the_graph_built_afresh(seed: int, flips: int) -> None:
    rng = np.random.default_rng(seed)
    before = random_blocks(seed)
    after = before.copy()
    for _ in range(flips):
        after[rng.integers(0, after.shape[0]), rng.integers(0, after.shape[1])] ^= True
    kept = graph_of(before, 4, 2)
    kept.refresh(after, 0, 0)
    fresh = graph_of(after, 4, 2)
    np.testing.assert_array_equal(kept.n_nodes, fresh.n_nodes)
    np.testing.assert_array_equal(kept.node_at, fresh.node_at)
    for slot, n in enumerate(fresh.n_nodes):
        np.testing.assert_array_equal(kept.nodes[slot, :n], fresh.nodes[slot, :n])
        np.testing.assert_array_equal(kept.intra[slot, :n, :n], fresh.intra[slot, :n, :n])
        np.testing.assert_array_equal(kept.inter[slot, :n], fresh.inter[slot, :n])


@settings(max_examples=40, deadline=None)
@given(st.integers(0, 10**6))
def test_the_way_back_is_a_way_of_the_distance_read(seed: int) -> None:
    blocks = random_blocks(seed)
    g = graph_of(blocks, 4, 2)
    valid = np.flatnonzero(np.arange(g.max_nodes)[None, :] < g.n_nodes[:, None])
    if not len(valid):
        return
    rng = np.random.default_rng(seed)
    u = int(valid[rng.integers(len(valid))])
    field = g.search(np.array([u]), np.zeros(1))
    free = np.argwhere(blocks)
    reached = free[np.isfinite(field.values(free))]
    goal = tuple(int(x) for x in reached[rng.integers(len(reached))])
    way, seed_block = field.corridor(goal)
    assert tuple(way[0]) == goal
    assert tuple(way[-1]) == tuple(seed_block) == tuple(g.nodes[u // g.max_nodes, u % g.max_nodes])
    assert blocks[way[:, 0], way[:, 1]].all()
    steps = np.abs(np.diff(way, axis=0))
    assert (steps.max(axis=1) == 1).all()  # 8-adjacent blocks, no repeats
    for (r0, c0), (r1, c1) in zip(way[:-1], way[1:], strict=True):
        if r0 != r1 and c0 != c1:  # a diagonal step passes between two free blocks
            assert blocks[r0, c1] and blocks[r1, c0]
    length = float(np.where(steps.sum(axis=1) == 2, np.sqrt(2.0), 1.0).sum())
    assert length == pytest.approx(float(field.values(np.array([goal]))[0]), abs=1e-3)


def rooms(seed: int) -> np.ndarray:
    """Open floor cut by thin walls, one cell thick, at random."""
    rng = np.random.default_rng(seed)
    g = np.ones((90, 120), bool)
    for _ in range(14):
        r, c, n = int(rng.integers(0, 90)), int(rng.integers(0, 120)), int(rng.integers(10, 50))
        if rng.random() < 0.5:
            g[r, c : c + n] = False
        else:
            g[r : r + n, c] = False
    return g


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_far_fields_on_portals_are_real_paths_and_paths_reach_far_goals(seed: int) -> None:
    passable = rooms(seed)
    graph = PortalGraph((45, 60), 4, 2)
    grid = coarse_grid(passable, 2, graph)
    assert grid is not None and grid.portals is graph
    free = np.argwhere(passable)
    rng = np.random.default_rng(seed)
    src = free[rng.integers(len(free))]
    goals = free[rng.choice(len(free), 12, replace=False)]
    field = far_fields(passable, src[None], 8, 2, goals, None, grid)[0]
    assert field.portal is not None
    exact = distance_fields(passable, src[None])[0].at(goals)
    got = field.at(goals)
    assert (np.isfinite(got) == np.isfinite(exact)).all()
    assert (got[np.isfinite(exact)] >= exact[np.isfinite(exact)] - 1e-3).all()
    for goal in goals[np.isfinite(exact)]:
        path = path_to(field, passable, tuple(src), tuple(goal))
        assert tuple(path[0]) == tuple(src) and tuple(path[-1]) == tuple(goal)
        assert passable[path[:, 0], path[:, 1]].all()


def test_the_sector_side_is_checked() -> None:
    with pytest.raises(MrExploreError, match="portal_sector_blocks must be 0 or >= 2, got 1"):
        GlobalPlanningConfig(portal_sector_blocks=1)


def test_a_robot_whose_exact_part_reaches_no_portal_reads_far_cells_through_its_own_blocks() -> None:
    # An open floor in sectors of 8 blocks of 2 cells (16 cells); the robot stands in the middle of one,
    # 8 cells from every border, and its exact part reaches 3 cells: no portal. Its seed blocks reach the
    # sector's portals inside the sector, so far cells read a real way, never shorter than the exact one.
    # It bends at the portals (two per border here): the diagonal to (60, 60) reads 11.5% over the exact.
    passable = np.ones((64, 64), bool)
    graph = PortalGraph((32, 32), 8, 4)
    grid = coarse_grid(passable, 2, graph)
    assert grid is not None
    src = np.array([24, 24])
    goals = np.array([[60, 60], [2, 50], [40, 5]])
    field = far_fields(passable, src[None], 3, 2, None, None, grid)[0]
    exact = distance_fields(passable, src[None])[0].at(goals)
    got = field.at(goals)
    assert np.isfinite(got).all()
    assert (got >= exact - 1e-3).all() and (got <= exact * 1.15).all()


def test_cells_the_blocks_close_off_are_read_on_the_finer_blocks_portal_graph() -> None:
    # A room and a hall joined through a thick wall by a corridor 4 cells wide at rows 9-12: blocks of 3
    # on the sectors' lattice (rows 9-11 and 12-14) hold no whole block of it, so the far field searches
    # the corridor's cells on blocks of 2, on their own portal graph, and no exact search runs.
    passable = np.zeros((30, 90), bool)
    passable[1:29, 1:30] = True
    passable[1:29, 60:89] = True
    passable[9:13, 30:60] = True
    coarse, finer = PortalGraph((10, 30), 4, 2), PortalGraph((15, 45), 4, 2)
    grid = coarse_grid(passable, 3, coarse, finer)
    assert grid is not None
    src, goal = np.array([[15, 10]]), np.array([[15, 80]])
    exact_searches = []
    plain = grid.exact_at
    object.__setattr__(grid, "exact_at", lambda *a: exact_searches.append(a) or plain(*a))
    field = far_fields(passable, src, 5, 3, goal, None, grid)[0]
    want = distance_fields(passable, src)[0].at(goal)[0]
    assert field.value(15, 80) >= want - 1e-3 and field.value(15, 80) <= want * 1.1
    assert not exact_searches
    assert grid.finer() is not None and grid.finer().portals is finer
    assert finer.n_nodes.sum() > 0  # brought up to date when first used
