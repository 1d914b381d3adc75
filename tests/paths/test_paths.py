"""Distance fields and A*: hand-checked grids and a plain Dijkstra reference."""

from __future__ import annotations

import math

import numpy as np
import pytest
from conftest import bool_grid, seeded_dijkstra
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from mrexplore.paths.astar import astar_path, path_length_cells
from mrexplore.paths.distance_field import (
    descend_path,
    distance_field,
    distance_fields,
    distance_matrix,
    distances_at,
    nearest_fields,
    pairwise_distances,
)


def reference_dijkstra(passable: np.ndarray, src: tuple[int, int]) -> np.ndarray:
    """Plain heapq Dijkstra from one cell (all ``inf`` from a blocked one)."""
    return seeded_dijkstra(passable, [(src[0], src[1], 0.0)])


def test_field_by_hand_and_no_corner_cutting() -> None:
    free = ~bool_grid("""
        ....
        .#..
        ..#.
        ....
    """)
    d = distance_field(free, (0, 0))
    assert d[0, 3] == 3.0  # straight along the top row
    # (0,1) -> (1,2) would cut the corner of the wall at (1,1): forbidden, so go (0,2) -> (1,2).
    assert d[1, 2] == pytest.approx(3.0)
    # (1,0) -> (2,1) would cut (1,1) as well: down the left column instead.
    assert d[2, 1] == pytest.approx(3.0)
    # (3,3): down to (2,0), diagonal to (3,1) (sides (2,1) and (3,0) free), then right twice.
    assert d[3, 3] == pytest.approx(4 + math.sqrt(2))


def test_unreachable_is_inf_and_blocked_source_all_inf() -> None:
    free = ~bool_grid("""
        .#.
        .#.
    """)
    d = distance_field(free, (0, 0))
    assert d[1, 0] == 1.0 and np.isinf(d[0, 2])
    assert np.isinf(distance_field(free, (0, 1))).all()


@settings(max_examples=60, deadline=None)
@given(arrays(np.bool_, st.tuples(st.integers(1, 14), st.integers(1, 14)), elements=st.booleans()), st.data())
def test_field_matches_reference_dijkstra(passable: np.ndarray, data: st.DataObject) -> None:
    src = (data.draw(st.integers(0, passable.shape[0] - 1)), data.draw(st.integers(0, passable.shape[1] - 1)))
    np.testing.assert_allclose(distance_field(passable, src), reference_dijkstra(passable, src), rtol=1e-6)


@settings(max_examples=60, deadline=None)
@given(arrays(np.bool_, st.tuples(st.integers(2, 14), st.integers(2, 14)), elements=st.booleans()), st.data())
def test_astar_is_optimal_and_valid(passable: np.ndarray, data: st.DataObject) -> None:
    H, W = passable.shape
    a = (data.draw(st.integers(0, H - 1)), data.draw(st.integers(0, W - 1)))
    b = (data.draw(st.integers(0, H - 1)), data.draw(st.integers(0, W - 1)))
    path = astar_path(passable, a, b)
    ref = reference_dijkstra(passable, a)[b]
    if not np.isfinite(ref):
        assert path.shape == (0, 2)
        return
    assert path[0].tolist() == list(a) and path[-1].tolist() == list(b)
    assert passable[path[:, 0], path[:, 1]].all()
    steps = np.diff(path, axis=0)
    assert (np.abs(steps).max(axis=1) == 1).all()
    for (r, c), (dr, dc) in zip(path[:-1], steps, strict=True):
        if dr and dc:
            assert passable[r, c + dc] and passable[r + dr, c]
    assert path_length_cells(path) == pytest.approx(ref)


def walled_grid(rng: np.random.Generator, max_side: int) -> tuple[np.ndarray, np.ndarray]:
    """A random grid, 70% passable, its top row blocked (the passable box is smaller than the grid), and
    all its cells."""
    passable = rng.random((int(rng.integers(2, max_side)), int(rng.integers(2, max_side)))) < 0.7
    passable[0, :] = False
    return passable, np.argwhere(np.ones_like(passable))


@settings(max_examples=50, deadline=None)
@given(st.integers(0, 10**6))
def test_distance_matrix_equals_fields_read_at_targets(seed: int) -> None:
    rng = np.random.default_rng(seed)
    passable, cells = walled_grid(rng, 25)
    sources = cells[rng.integers(0, len(cells), 4)]
    targets = cells[rng.integers(0, len(cells), 6)]
    expected = np.stack([distances_at(f, targets) for f in distance_fields(passable, sources)])
    np.testing.assert_array_equal(distance_matrix(passable, sources, targets), expected)


@settings(deadline=None)  # the first example compiles the kernel where numba's cache is cold (CI)
@given(st.integers(0, 10**6))
def test_pairwise_distances_equal_the_reference_both_ways(seed: int) -> None:
    rng = np.random.default_rng(seed)
    passable, cells = walled_grid(rng, 20)
    points = cells[rng.integers(0, len(cells), int(rng.integers(0, 7)))]  # walls and repeats too
    got = pairwise_distances(passable, points)
    want = np.array([[reference_dijkstra(passable, tuple(a))[tuple(b)] for b in points] for a in points])
    np.testing.assert_allclose(got, want.reshape(got.shape), rtol=1e-6)
    np.testing.assert_array_equal(got, got.T)


@settings(max_examples=50, deadline=None)
@given(st.integers(0, 10**6))
def test_pairwise_searches_sharing_one_array_equal_fresh_fields_bit_for_bit(seed: int) -> None:
    # Every search after the first starts from the array the one before restored from its queues.
    rng = np.random.default_rng(seed)
    passable, cells = walled_grid(rng, 30)
    points = cells[rng.integers(0, len(cells), 12)]
    fresh = np.stack([distances_at(f, points) for f in distance_fields(passable, points)])
    got = pairwise_distances(passable, points)
    upper = np.triu_indices(len(points), 1)
    np.testing.assert_array_equal(got[upper], fresh[upper])  # i's search read at j (float32 sums by direction)


@settings(max_examples=80, deadline=None)
@given(st.integers(0, 10**6))
def test_fields_stopped_at_their_targets_are_exact_up_to_them(seed: int) -> None:
    rng = np.random.default_rng(seed)
    passable = rng.random((int(rng.integers(2, 25)), int(rng.integers(2, 25)))) < 0.7
    cells = np.argwhere(np.ones_like(passable))
    sources = cells[rng.integers(0, len(cells), 3)]
    targets = cells[rng.integers(0, len(cells), int(rng.integers(0, 5)))]
    for whole, stopped in zip(
        distance_fields(passable, sources), distance_fields(passable, sources, targets), strict=True
    ):
        full, part = whole.full(), stopped.full()
        np.testing.assert_array_equal(stopped.at(targets), whole.at(targets))
        finite = np.isfinite(part)
        np.testing.assert_array_equal(part[finite], full[finite])  # what it holds is exact
        # and it holds every cell no farther than the farthest reachable target
        reach = whole.at(targets)
        reach = reach[np.isfinite(reach)]
        if len(reach):
            assert finite[full <= reach.max()].all()
        for t in targets:
            assert (
                descend_path(stopped, passable, tuple(t)).tolist() == descend_path(whole, passable, tuple(t)).tolist()
            )


@settings(max_examples=80, deadline=None)
@given(st.integers(0, 10**6))
def test_fields_stopped_at_the_nearest_candidate_hold_it_its_ties_and_the_musts(seed: int) -> None:
    rng = np.random.default_rng(seed)
    passable = rng.random((int(rng.integers(2, 25)), int(rng.integers(2, 25)))) < 0.7
    cells = np.argwhere(np.ones_like(passable))
    sources = cells[rng.integers(0, len(cells), 3)]
    candidates = cells[rng.integers(0, len(cells), int(rng.integers(0, 6)))]
    musts = [cells[rng.integers(0, len(cells), int(rng.integers(0, 3)))] for _ in sources]
    whole_fields = distance_fields(passable, sources)
    for whole, stopped, must in zip(
        whole_fields, nearest_fields(passable, sources, candidates, musts), musts, strict=True
    ):
        full, part = whole.full(), stopped.full()
        finite = np.isfinite(part)
        np.testing.assert_array_equal(part[finite], full[finite])  # what it holds is exact
        np.testing.assert_array_equal(stopped.at(must), whole.at(must))
        d = whole.at(candidates)
        if np.isfinite(d).any():
            nearest = d == d.min()
            np.testing.assert_array_equal(stopped.at(candidates)[nearest], d[nearest])  # ties included
            assert not np.isfinite(stopped.at(candidates)[d > d.min()]).any() or len(must)  # no farther
            np.testing.assert_array_equal(np.argmin(stopped.at(candidates)), np.argmin(d))
            for t in candidates[nearest]:
                assert (
                    descend_path(stopped, passable, tuple(t)).tolist()
                    == descend_path(whole, passable, tuple(t)).tolist()
                )
        else:
            assert not np.isfinite(stopped.at(candidates)).any()


def test_a_field_stops_at_the_nearest_candidate_or_at_its_own_cells_beyond() -> None:
    corridor = np.ones((1, 9), bool)
    none = np.zeros((0, 2), int)
    cands = np.array([[0, 0], [0, 6], [0, 2]])
    f = nearest_fields(corridor, np.array([[0, 4]]), cands, [none])[0]
    assert f.full()[0].tolist() == [math.inf, math.inf, 2, 1, 0, 1, 2, math.inf, math.inf]
    f = nearest_fields(corridor, np.array([[0, 4]]), cands, [np.array([[0, 7]])])[0]  # its goal, 3 cells away
    assert f.full()[0].tolist() == [math.inf, 3, 2, 1, 0, 1, 2, 3, math.inf]
    blocked = corridor.copy()
    blocked[0, 3] = blocked[0, 5] = False  # nothing reachable: the search runs out, as a whole one does
    f = nearest_fields(blocked, np.array([[0, 4]]), cands, [none])[0]
    assert f.full()[0].tolist() == [math.inf] * 4 + [0] + [math.inf] * 4
    with pytest.raises(ValueError, match="must_rc has 0 entries for 1 sources; give one per source"):
        nearest_fields(corridor, np.array([[0, 4]]), cands, [])


def test_a_field_stops_at_its_farthest_target() -> None:
    corridor = np.ones((1, 8), bool)
    f = distance_fields(corridor, np.array([[0, 0]]), np.array([[0, 3], [0, 2]]))[0]
    assert f.full()[0].tolist() == [0, 1, 2, 3, *[math.inf] * 4]


def test_astar_reuses_its_arrays_without_leaking_between_calls() -> None:
    # Grids of one cell count share the scratch arrays (stamped by call); shapes differ, results must not.
    wide = ~bool_grid("""
        ......
        .####.
        ......
        ......
    """)
    tall = np.ones((6, 4), bool)
    tall[1:5, 1] = False
    first = astar_path(wide, (0, 0), (3, 5)).tolist()
    assert astar_path(tall, (0, 0), (5, 0)).tolist() == [[0, 0], [1, 0], [2, 0], [3, 0], [4, 0], [5, 0]]
    assert astar_path(wide, (1, 0), (1, 5)).tolist()[-1] == [1, 5]
    assert astar_path(wide, (0, 0), (3, 5)).tolist() == first
    assert astar_path(tall, (0, 2), (2, 1)).tolist() == []  # a wall cell: no path, whatever came before


def test_pairwise_distances_across_pieces_of_free_space() -> None:
    """Points in three pieces of free space, in turns: inf between pieces, exact within each, whichever
    search settles a piece first (the kernel leaves out the points of pieces already settled)."""
    free = ~bool_grid("""
        ..#..#..
        ..#..#..
        ..#..#..
    """)
    points = np.array([[0, 0], [0, 3], [2, 6], [2, 1], [2, 4], [0, 7]])
    d = pairwise_distances(free, points)
    piece = np.array([0, 1, 2, 0, 1, 2])
    apart = piece[:, None] != piece[None, :]
    assert np.isinf(d[apart]).all()
    # within each piece: one diagonal and one straight move (2 rows down, 1 column across)
    assert d[0, 3] == d[1, 4] == d[2, 5] == pytest.approx(1 + math.sqrt(2))


def test_a_path_is_read_off_a_field_beyond_float32_precision() -> None:
    """A band three cells wide along a 3,000-cell diagonal: the only shortest path is the diagonal itself.
    Past 2,048 cells a float32 distance is rounded by more than the strict 1e-4 test allows, and reading
    the path back used to give none at all (a KTH floor at 0.05 m then idled a team for 12,000 steps)."""
    n = 3000
    i = np.arange(n)
    free = np.zeros((n, n), dtype=bool)
    for k in (-1, 0, 1):
        keep = (i + k >= 0) & (i + k < n)
        free[i[keep], i[keep] + k] = True
    field = distance_field(free, (0, 0))
    assert field[n - 1, n - 1] == pytest.approx((n - 1) * math.sqrt(2), rel=1e-4)  # float32 sums drift
    path = descend_path(field, free, (n - 1, n - 1))
    assert path.tolist() == [[k, k] for k in range(n)]
