"""CoScan-2D: task sampling, Lloyd clustering with split and merge (traced by hand), 2-opt tours."""

from __future__ import annotations

import itertools

import numpy as np
from conftest import state_grid
from hypothesis import given, settings
from hypothesis import strategies as st

from mrexplore.global_planning.coscan import cap_tasks, lloyd_clusters, sample_tasks, tour_length, two_opt_tour
from mrexplore.strategies import make_strategy


def line(xs: list[float], robots: list[float]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Tasks on a corridor: geodesic distance is |x - x'|."""
    x = np.asarray(xs, dtype=np.float64)
    return (
        np.stack([np.zeros_like(x), x], axis=1),
        np.abs(x[:, None] - x[None, :]),
        np.abs(np.asarray(robots, dtype=np.float64)[:, None] - x[None, :]),
    )


def test_lloyd_splits_a_cluster_wider_than_delta() -> None:
    # One robot at -1, tasks 0..5, delta 2. It 1: one cluster, mean 2.5 snaps to x=2 (first of a tie);
    # x=5 lies 3 > 2 away: split. It 2: {0..3} -> x=1, {4, 5} -> x=4. It 3: {0, 1, 2} and {3, 4, 5}
    # keep centroids x=1 and x=4: settled.
    pts, d, dr = line([0, 1, 2, 3, 4, 5], [-1])
    res = lloyd_clusters(pts, d, dr, delta_cells=2)
    assert res.labels.tolist() == [0, 0, 0, 1, 1, 1]
    assert res.centroids.tolist() == [1, 4] and res.iterations == 3


def test_lloyd_merges_a_singleton_within_delta_when_clusters_outnumber_robots() -> None:
    # One robot at -1, tasks at 1, 4, 6, 7, 10, delta 2. Splits leave four clusters {1}, {4}, {6, 7}, {10}
    # after iteration 4; the singleton {4} lies 2 <= delta from the centroid 6 and merges into it; {1}
    # and {10} are farther than delta from every centroid and stay. It 5 changes nothing.
    pts, d, dr = line([1, 4, 6, 7, 10], [-1])
    res = lloyd_clusters(pts, d, dr, delta_cells=2)
    assert res.labels.tolist() == [0, 1, 1, 1, 2]
    assert res.centroids.tolist() == [0, 2, 4] and res.iterations == 5
    # With as many robots as clusters there is nothing to merge: {4} stays alone.
    many = lloyd_clusters(pts, d, np.repeat(dr, 10, axis=0), delta_cells=2)
    assert many.labels.tolist() == [0, 1, 2, 2, 3]


def test_sampling_keeps_spacing_and_covers_every_frontier_cell() -> None:
    rng = np.random.default_rng(0)
    cells = np.unique(rng.integers(0, 40, size=(300, 2)), axis=0)
    tasks = sample_tasks(cells, 5.0)
    gaps = np.linalg.norm(tasks[:, None] - tasks[None], axis=2) + np.eye(len(tasks)) * 99
    assert gaps.min() >= 5.0
    reach = np.linalg.norm(cells[:, None] - tasks[None], axis=2).min(axis=1)
    assert reach.max() < 5.0  # greedy: a cell was dropped only for a kept cell within the spacing


def test_cap_drops_the_farthest_and_the_unreachable() -> None:
    assert cap_tasks(np.array([9.0, 1.0, np.inf, 4.0, 2.0]), 3).tolist() == [1, 3, 4]


def brute_force(d_start: np.ndarray, d: np.ndarray) -> float:
    return min(tour_length(np.array(p), d_start, d) for p in itertools.permutations(range(len(d_start))))


def points(m: int) -> st.SearchStrategy[list[tuple[int, int]]]:
    return st.lists(st.tuples(st.integers(0, 50), st.integers(0, 50)), min_size=m, max_size=m)


@settings(max_examples=200, deadline=None)
@given(st.integers(1, 6).flatmap(lambda m: points(m + 1)))
def test_two_opt_is_a_local_optimum_and_never_beats_brute_force(pts: list[tuple[int, int]]) -> None:
    p = np.asarray(pts, dtype=np.float64)
    robot, tasks = p[0], p[1:]
    d_start = np.linalg.norm(tasks - robot, axis=1)
    d = np.linalg.norm(tasks[:, None] - tasks[None], axis=2)
    order = two_opt_tour(d_start, d)
    assert sorted(order.tolist()) == list(range(len(tasks)))
    length = tour_length(order, d_start, d)
    assert length >= brute_force(d_start, d) - 1e-9
    for i, j in itertools.combinations(range(len(order)), 2):  # no reversal shortens it
        cand = np.concatenate([order[:i], order[i : j + 1][::-1], order[j + 1 :]])
        assert tour_length(cand, d_start, d) >= length - 1e-9


def test_two_opt_matches_brute_force_on_most_small_instances() -> None:
    rng = np.random.default_rng(7)
    hits = 0
    for _ in range(300):
        p = rng.uniform(0, 10, size=(7, 2))
        d_start = np.linalg.norm(p[1:] - p[0], axis=1)
        d = np.linalg.norm(p[1:, None] - p[None, 1:], axis=2)
        hits += tour_length(two_opt_tour(d_start, d), d_start, d) <= brute_force(d_start, d) + 1e-9
    # 2-opt is a local search: measured optimal on 243 of these 300 six-task instances.
    assert hits >= 240, hits


def test_coscan_decision_by_hand() -> None:
    # One robot in a corridor, unknown at both ends (0.2 m cells): one task per end (its 3 frontier cells
    # lie within the 0.5 m spacing), 1.6 m apart <= delta 2 m: one cluster, the nearer end first.
    state = state_grid("""
        ###########
        ?.........?
        ?.........?
        ?.........?
        ###########
    """)
    pipeline = make_strategy("coscan")
    d = pipeline.decide(state, np.array([[2, 3]], np.int32), 0.2)
    assert d.done_reason is None
    assert d.clusters.members_rc.tolist() == [[1, 1], [1, 9]] and d.clusters.labels.tolist() == [0, 0]
    assert d.routes[0].tolist() == [[1, 1], [1, 9]] and d.goals_rc.tolist() == [[1, 1]]


def test_coscan_and_the_oracle_plug_in_through_the_candidate_seam() -> None:
    """Strategies that choose their own candidates supply them (and their routing) through the pipeline's
    seam; none overrides the shared decision (STYLE rule 17)."""
    from mrexplore.strategies import CoScanPipeline, ExplorationPipeline, OraclePipeline

    for cls in (CoScanPipeline, OraclePipeline):
        assert "decide" not in cls.__dict__ and "pose" not in cls.__dict__ and "finish" not in cls.__dict__
        assert "candidates" in cls.__dict__ and "route" in cls.__dict__
    assert ExplorationPipeline.decide is CoScanPipeline.decide


def test_a_new_strategy_supplies_candidates_without_touching_the_decision() -> None:
    """A strategy offering two fixed cells as candidates: the shared code measures the distances, the
    Hungarian planner assigns, paths lead there."""
    from conftest import state_grid

    from mrexplore.global_planning.classical import GeodesicPlanner
    from mrexplore.preprocessing.clustering import Clusters
    from mrexplore.strategies import CandidateSet, ExplorationPipeline

    class TwoCells(ExplorationPipeline):
        def candidates(self, q):
            cells = np.array([[1, 1], [1, 7]], np.int32)
            return CandidateSet(Clusters(cells, np.ones(2, np.int32), cells, np.arange(2, dtype=np.int32)))

    grid = state_grid(
        """
        #########
        #.......#
        #.......#
        #########
        """
    )
    d = TwoCells("two", GeodesicPlanner()).decide(grid, np.array([[2, 6], [2, 2]], np.int32), 0.1)
    assert d.done_reason is None
    assert d.goals_rc.tolist() == [[1, 7], [1, 1]]  # each robot to the nearer cell
    assert d.paths[0][0].tolist() == [2, 6] and d.paths[0][-1].tolist() == [1, 7]
