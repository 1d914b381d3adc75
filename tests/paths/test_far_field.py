"""Near/far distances: the seeded search against a plain Dijkstra, exactness near the robot, a thin wall
the coarse grid never crosses, a narrow passage it closes, paths to far goals, the search stopped at a
radius, and the pooling."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from conftest import NARROW_GAP, bool_grid, seeded_dijkstra
from hypothesis import given, settings
from hypothesis import strategies as st

import mrexplore.paths.far_field as far_field
from mrexplore.paths.astar import path_length_cells
from mrexplore.paths.distance_field import distance_fields
from mrexplore.paths.far_field import (
    Field,
    NearFarField,
    _fewest_searches,
    coarse_grid,
    far_fields,
    path_to,
)
from mrexplore.paths.kernels import Searches, seeded_search


def random_rooms(seed: int, shape: tuple[int, int] = (60, 80), walls: int = 12) -> np.ndarray:
    """Open floor cut by thin straight walls (one cell thick) at random."""
    rng = np.random.default_rng(seed)
    g = np.ones(shape, bool)
    for _ in range(walls):
        r, c = int(rng.integers(0, shape[0])), int(rng.integers(0, shape[1]))
        n = int(rng.integers(5, 30))
        if rng.random() < 0.5:
            g[r, c : c + n] = False
        else:
            g[r : r + n, c] = False
    return g


@settings(max_examples=60, deadline=None)
@given(st.integers(0, 10**6))
def test_seeded_search_equals_dijkstra_from_many_starts(seed: int) -> None:
    rng = np.random.default_rng(seed)
    g = rng.random((12, 15)) < 0.75
    free = np.argwhere(g)
    picks = free[rng.choice(len(free), size=min(len(free), int(rng.integers(1, 6))), replace=False)]
    keys = rng.uniform(0, 6, len(picks)).astype(np.float32)
    order = np.argsort(keys, kind="stable")
    s = Searches(g)
    q_node, q_key, _ = s.scratch()
    flat = s.padded(picks[order, 0] * g.shape[1] + picks[order, 1])
    got = seeded_search(s.start, s.wp, flat, keys[order], q_node, q_key).reshape(14, 17)[1:-1, 1:-1]
    want = seeded_dijkstra(g, [(int(r), int(c), float(k)) for (r, c), k in zip(picks, keys, strict=True)])
    np.testing.assert_allclose(got, want, rtol=1e-5, atol=1e-4)


@settings(max_examples=30, deadline=None)
@given(st.integers(0, 10**6))
def test_exact_within_the_radius_and_coarse_blocks_never_shorter(seed: int) -> None:
    g = random_rooms(seed)
    src = np.argwhere(g)[np.random.default_rng(seed).integers(0, np.count_nonzero(g))]
    exact = distance_fields(g, src[None])[0].full()
    f = far_fields(g, src[None], radius_cells=12, factor=3)[0]
    cells = np.argwhere(g)
    got = f.at(cells)
    e = exact[cells[:, 0], cells[:, 1]]
    near = e <= 12
    np.testing.assert_allclose(got[near], e[near], rtol=1e-6)
    # A coarse distance is a real path through whole free blocks: never shorter than the exact one at
    # the block's middle cell (the seeds are exact, every coarse move is a free straight or diagonal run).
    blocks = np.argwhere(np.isfinite(f.coarse))
    mids = f.grid.centres_rc(blocks)
    assert (f.coarse[blocks[:, 0], blocks[:, 1]] * 3 >= exact[mids[:, 0], mids[:, 1]] - 1e-3).all()


def test_a_thin_wall_is_gone_round_not_through() -> None:
    # A one-cell wall along row 6 with a door at its right end; the robot top left, the target just below.
    g = np.ones((12, 40), bool)
    g[6, :36] = False
    f = far_fields(g, np.array([[3, 2]]), radius_cells=5, factor=2)[0]
    exact = distance_fields(g, np.array([[3, 2]]))[0].value(9, 2)
    assert exact > 60  # round by the door
    assert abs(f.value(9, 2) - exact) <= 2 * 2  # within a block's diagonal, never the 6 cells through the wall


def test_a_passage_the_coarse_grid_closes_reads_inf_and_its_path_falls_back_to_an_exact_search() -> None:
    g = ~bool_grid(NARROW_GAP)
    f = far_fields(g, np.array([[0, 0]]), radius_cells=4, factor=3)[0]
    assert f.value(0, 19) == math.inf  # the one-cell gap in the wall closes every block around it
    path = path_to(f, g, (0, 0), (0, 19))
    exact = distance_fields(g, np.array([[0, 0]]))[0].value(0, 19)
    assert path[0].tolist() == [0, 0] and path[-1].tolist() == [0, 19]
    assert path_length_cells(path) == pytest.approx(exact)
    # A cell the caller must have: searched back from it exactly, once for every source.
    both = far_fields(g, np.array([[0, 0], [5, 0]]), radius_cells=4, factor=3, must_rc=np.array([[0, 19]]))
    from_below = distance_fields(g, np.array([[5, 0]]))[0].value(0, 19)
    assert [b.value(0, 19) for b in both] == [pytest.approx(exact), pytest.approx(from_below)]
    assert both[0].known and both[1].known  # read from the search back, not estimated


def test_a_source_behind_a_closed_passage_gets_one_exact_search_for_every_cell_it_leaves(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    # A wall down column 10 with a one-cell gap at row 15: robot B in the room left of it, robot A in the
    # hall right of it. Pooled by 3 the gap closes, so B's field reaches nothing in the hall.
    g = np.ones((30, 60), bool)
    g[:, 10] = False
    g[15, 10] = True
    sources = np.array([[15, 2], [15, 40]])  # B, A
    must = np.array([[3, 55], [27, 55], [15, 58]])  # hall cells beyond A's exact radius
    grid = coarse_grid(g, 3)
    assert grid is not None
    alone = far_fields(g, sources, radius_cells=4, factor=3, grid=grid)
    assert not np.isfinite(alone[0].at(must)).any() and np.isfinite(alone[1].at(must)).all()
    searches: list[int] = []
    exact_at = type(grid).exact_at

    def counted(self: object, src: np.ndarray, cells: np.ndarray) -> np.ndarray:
        searches.append(len(cells))
        return exact_at(self, src, cells)  # type: ignore[arg-type]

    monkeypatch.setattr(type(grid), "exact_at", counted)
    b, a = far_fields(g, sources, radius_cells=4, factor=3, must_rc=must, grid=grid)
    assert searches == [3]  # one search from B for its three cells, none back from each cell
    want = distance_fields(g, sources[:1])[0].at(must)
    np.testing.assert_allclose(b.at(must), want, rtol=1e-6)  # exact through the gap
    np.testing.assert_array_equal(a.at(must), alone[1].at(must))  # A keeps its own estimates


def test_a_cell_no_block_next_to_it_reaches_is_joined_to_the_robots_own_coarse_fields(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    # An open hall with a pocket of posts (one every third cell, so no 3 x 3 block there is wholly free)
    # round the cell: no block next to it is passable, and both robots, far away, leave it at inf.
    g = np.ones((30, 90), bool)
    for r in range(10, 22, 3):
        for c in range(76, 88, 3):
            g[r, c] = False
    cell, sources = np.array([[14, 80]]), np.array([[3, 3], [26, 10]])
    grid = coarse_grid(g, 3)
    assert grid is not None
    assert not np.isfinite([f.value(14, 80) for f in far_fields(g, sources, 10, 3, grid=grid)]).any()
    searches: list[str] = []
    seeded = far_field.seeded_search
    monkeypatch.setattr(far_field, "seeded_search", lambda *a: searches.append("coarse") or seeded(*a))
    monkeypatch.setattr(type(grid), "exact_at", lambda *a: searches.append("exact"))
    fields = far_fields(g, sources, 10, 3, must_rc=cell, grid=grid)
    assert searches == ["coarse", "coarse"]  # the robots' own: none from the cell, no exact search
    got = [f.value(14, 80) for f in fields]
    want = [distance_fields(g, s[None])[0].value(14, 80) for s in sources]  # straight across the hall
    np.testing.assert_allclose(got, want, rtol=1e-6)


def test_a_cell_whose_radius_joins_no_block_tries_twice_the_radius_before_an_exact_search(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    # Posts at every third row and column from column 61 on: every 3 x 3 block there holds one, so the
    # nearest passable blocks to the cell (column 70) are those of columns 57-59, 11-13 cells away. Within
    # the radius (8) the cell joins none; within twice the radius it joins the robots' fields.
    g = np.ones((30, 90), bool)
    for r in range(1, 30, 3):
        for c in range(61, 90, 3):
            g[r, c] = False
    cell, sources, radius = np.array([[15, 70]]), np.array([[3, 3], [26, 10]]), 8
    grid = coarse_grid(g, 3)
    assert grid is not None
    alone = far_fields(g, sources, radius, 3, grid=grid)
    assert not np.isfinite(far_field._back(g, grid, cell[0], radius, sources, alone)).any()
    searches: list[str] = []
    monkeypatch.setattr(type(grid), "exact_at", lambda *a: searches.append("exact"))
    fields = far_fields(g, sources, radius, 3, must_rc=cell, grid=grid)
    assert searches == []  # joined at twice the radius: no search over the floor
    got = np.array([f.value(15, 70) for f in fields])
    want = np.array([distance_fields(g, s[None])[0].value(15, 70) for s in sources])
    # A real path (never shorter) through whole free blocks: within a block's diagonal of the shortest.
    assert (got >= want - 1e-6).all() and (got <= want + 3 * math.sqrt(2)).all()


@settings(max_examples=200, deadline=None)
@given(st.integers(1, 5), st.integers(1, 6), st.integers(0, 10**6))
def test_the_searches_chosen_cover_every_pair_left_at_inf_and_are_as_few_as_can_be(n: int, k: int, seed: int) -> None:
    pairs = np.random.default_rng(seed).random((n, k)) < 0.4
    rows, cols = _fewest_searches(pairs)
    assert not (pairs & ~rows[:, None] & ~cols[None, :]).any()  # every pair searched from one end
    # The fewest: over every set of rows, the columns it leaves to search.
    fewest = min(
        len(chosen) + int(np.count_nonzero(pairs[[i for i in range(n) if i not in chosen]].any(axis=0)))
        for m in range(n + 1)
        for chosen in itertools.combinations(range(n), m)
    )
    assert rows.sum() + cols.sum() == fewest


@settings(max_examples=20, deadline=None)
@given(st.integers(0, 10**6))
def test_paths_to_far_goals_are_valid_and_near_shortest(seed: int) -> None:
    g = random_rooms(seed, (50, 70), 10)
    rng = np.random.default_rng(seed)
    free = np.argwhere(g)
    src = tuple(int(v) for v in free[rng.integers(0, len(free))])
    exact = distance_fields(g, np.array([src]))[0]
    f = far_fields(g, np.array([src]), radius_cells=8, factor=2)[0]
    for goal in free[rng.choice(len(free), 8)]:
        goal_t = (int(goal[0]), int(goal[1]))
        path = path_to(f, g, src, goal_t)
        if not np.isfinite(exact.value(*goal_t)):
            assert len(path) == 0
            continue
        assert path[0].tolist() == list(src) and path[-1].tolist() == list(goal_t)
        assert g[path[:, 0], path[:, 1]].all()
        steps = np.abs(np.diff(path.astype(int), axis=0))
        assert (steps.max(axis=1) == 1).all()
        diag = (steps == 1).all(axis=1)  # no corner cut by a diagonal step
        a, b = path[:-1][diag], path[1:][diag]
        assert g[a[:, 0], b[:, 1]].all() and g[b[:, 0], a[:, 1]].all()
        # Exact inside the corridor along the coarse way: no longer than the estimate the planners read,
        # up to the last block's diagonal (where the exact path squeezes through a gap the coarse grid
        # closes, both are longer than the shortest).
        assert path_length_cells(path) <= f.value(*goal_t) + 2 * 2 * math.sqrt(2) + 1e-4


def test_exact_fields_read_through_path_to_as_before() -> None:
    g = np.ones((5, 8), bool)
    g[0:4, 4] = False
    exact = distance_fields(g, np.array([[0, 0]]))[0]
    assert isinstance(exact, Field)
    assert path_to(exact, g, (0, 0), (0, 7)).tolist()[-1] == [0, 7]
    assert not isinstance(exact, NearFarField)


def test_a_shared_coarse_grid_gives_the_fields_a_grid_of_their_own_does() -> None:
    g = random_rooms(5)
    sources = np.argwhere(g)[[0, 500, 2000]]
    cells = np.argwhere(g)
    grid = coarse_grid(g, 3)
    assert grid is not None
    shared = far_fields(g, sources, radius_cells=12, factor=3, grid=grid)
    alone = far_fields(g, sources, radius_cells=12, factor=3)
    for a, b in zip(shared, alone, strict=True):
        np.testing.assert_array_equal(a.at(cells), b.at(cells))
    with pytest.raises(ValueError, match=r"grid was pooled by 3 from a \(60, 80\) grid; pool this one by 2"):
        far_fields(g, sources, radius_cells=12, factor=2, grid=grid)


@settings(max_examples=40, deadline=None)
@given(st.integers(0, 10**6), st.floats(0.0, 40.0))
def test_a_search_stopped_at_a_radius_keeps_every_distance_within_it(seed: int, limit: float) -> None:
    g = random_rooms(seed, (30, 40), 8)
    src = np.argwhere(g)[np.random.default_rng(seed).integers(0, np.count_nonzero(g))]
    whole = Searches(g)(int(src[0]), int(src[1]))
    stopped = Searches(g)(int(src[0]), int(src[1]), limit=limit)
    # In float64, as the kernel compares: float32 would round a limit just under 2 up to 2.0.
    within = whole.astype(np.float64) <= limit
    np.testing.assert_array_equal(stopped[within], whole[within])  # bit for bit: the same pops
    assert np.isinf(stopped[~within]).all()


@settings(max_examples=80, deadline=None)
@given(st.integers(0, 10**6), st.integers(1, 4))
def test_pooling_in_bands_of_block_rows_equals_numpy_on_padded_blocks(seed: int, factor: int) -> None:
    rng = np.random.default_rng(seed)
    g = rng.random((int(rng.integers(1, 25)), int(rng.integers(1, 25)))) < 0.9
    g[int(rng.integers(0, g.shape[0])), int(rng.integers(0, g.shape[1]))] = True
    rows, cols = np.flatnonzero(g.any(axis=1)), np.flatnonzero(g.any(axis=0))
    r0, r1, c0, c1 = int(rows[0]), int(rows[-1]) + 1, int(cols[0]), int(cols[-1]) + 1
    h, w = -(-(r1 - r0) // factor), -(-(c1 - c0) // factor)
    padded = np.zeros((h * factor, w * factor), bool)  # a block cut by the box's edge is not passable
    padded[: r1 - r0, : c1 - c0] = g[r0:r1, c0:c1]
    want = padded.reshape(h, factor, w, factor).all(axis=(1, 3))
    np.testing.assert_array_equal(coarse_grid(g, factor).passable, want)


@settings(max_examples=30, deadline=None)
@given(st.integers(0, 10**6))
def test_the_grids_shared_exact_searches_read_what_a_fresh_search_does(seed: int) -> None:
    g = random_rooms(seed)
    g[:, :3] = False  # the passable box starts off the grid's corner
    rng = np.random.default_rng(seed)
    free = np.argwhere(g)
    grid = coarse_grid(g, 3)
    assert grid is not None
    for _ in range(3):  # one set of start values and queues serves every call
        src = free[rng.integers(len(free))]
        cells = np.vstack([free[rng.choice(len(free), size=5)], [[0, 0]]])  # the last one is blocked
        want = distance_fields(g, src[None], cells)[0].at(cells)
        np.testing.assert_array_equal(grid.exact_at(src, cells), want)


def test_a_passage_four_cells_wide_is_crossed_on_blocks_half_as_wide_not_by_exact_searches(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    # A room (columns 0-29) and a hall (60-119) joined by a corridor through a thick wall, rows 19-22: every
    # 3 x 3 block of the corridor holds a wall row (blocks start at rows 18 and 21), so pooled by 3 it is
    # closed; blocks of 2 (rows 20-21) run through it. Robot B in the room leaves the hall cells at inf, and
    # a cell in the corridor's middle is joined to no block of 3 within twice the radius.
    g = np.ones((40, 120), bool)
    g[:, 30:60] = False
    g[19:23, 30:60] = True
    sources = np.array([[20, 5], [20, 100]])  # B, A
    must = np.array([[3, 115], [36, 115], [20, 118], [20, 45]])
    grid = coarse_grid(g, 3)
    assert grid is not None
    alone = far_fields(g, sources, radius_cells=4, factor=3, grid=grid)
    assert not np.isfinite(alone[0].at(must)).any() and not np.isfinite(alone[1].value(20, 45))
    searches: list[str] = []
    monkeypatch.setattr(type(grid), "exact_at", lambda *a: searches.append("exact"))
    fields = far_fields(g, sources, radius_cells=4, factor=3, must_rc=must, grid=grid)
    assert searches == []  # every pair left at inf is read on the finer blocks
    finer = grid.finer()
    assert finer is not None and finer.factor == 2
    for f, src in zip(fields, sources, strict=True):
        exact = distance_fields(g, src[None])[0].at(must)
        got = f.at(must)
        assert np.all(got >= exact - 1e-4)  # a real path: never shorter
        assert np.all(got <= exact + 2 * math.sqrt(2))  # within a finer block's diagonal
