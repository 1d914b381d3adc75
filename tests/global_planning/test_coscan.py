"""CoScan-2D: task sampling, Lloyd clustering with split and merge (traced by hand), 2-opt tours."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from conftest import NARROW_GAP, bool_grid, state_grid
from hypothesis import given, settings
from hypothesis import strategies as st

from mrexplore.global_planning.coscan import (
    cap_tasks,
    lloyd_clusters,
    sample_tasks,
    tasks_in_reach,
    tour_length,
    two_opt_tour,
)
from mrexplore.pipeline import DecisionInput, make_strategy


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


def test_lloyd_reads_only_its_centroids_rows_when_given_rows_on_demand() -> None:
    # The same trace as above: centroid x=2, split-off x=5, then x=1 and x=4. Tasks 0 and 3 are never
    # centroids, so their rows are never searched (a large map searches rows on demand).
    pts, d, dr = line([0, 1, 2, 3, 4, 5], [-1])
    read: set[int] = set()

    def rows(idx: np.ndarray) -> np.ndarray:
        read.update(int(i) for i in idx)
        return d[idx]

    res = lloyd_clusters(pts, rows, dr, delta_cells=2)
    assert res.labels.tolist() == [0, 0, 0, 1, 1, 1] and res.centroids.tolist() == [1, 4]
    assert read == {1, 2, 4, 5}


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


@settings(max_examples=60, deadline=None)
@given(
    cells=st.lists(st.tuples(st.integers(-30, 60), st.integers(-30, 60)), max_size=200),
    spacing=st.sampled_from([1e-6, 0.5, 1.0, 2.5, 5.0, 10.000000000000002]),
)
def test_sampling_is_the_greedy_pass_over_the_cells_in_order(cells: list[tuple[int, int]], spacing: float) -> None:
    # The buckets only make the greedy pass fast: keep a cell when no kept cell lies closer than the
    # spacing, checked here against every kept cell.
    kept: list[tuple[int, int]] = []
    for r, c in cells:
        if all((r - a) ** 2 + (c - b) ** 2 >= spacing**2 for a, b in kept):
            kept.append((r, c))
    got = sample_tasks(np.array(cells, dtype=np.int64).reshape(-1, 2), spacing)
    assert got.dtype == np.int32 and [tuple(x) for x in got.tolist()] == kept


def test_cap_drops_the_farthest_and_the_unreachable() -> None:
    assert cap_tasks(np.array([9.0, 1.0, np.inf, 4.0, 2.0]), 3).tolist() == [1, 3, 4]


def test_tasks_out_of_reach_by_hand() -> None:
    # One robot at the origin, a cap of 2. Reads 3 and 6 are known, so the second smallest is 6: the task at
    # (4, 4) could be as near as 4 + 4 (sqrt 2 - 1) = 5.66 and is needed; the one at (0, 7) cannot beat 7.
    reads = np.array([[3.0, 6.0, np.inf, np.inf]])
    tasks = np.array([[0, 3], [6, 0], [4, 4], [0, 7]])
    assert tasks_in_reach(reads, np.array([[0, 0]]), tasks, 2).tolist() == [True, True, True, False]
    # Fewer known reads than the cap: every task may be kept, so all are needed.
    assert tasks_in_reach(reads, np.array([[0, 0]]), tasks, 3).all()


@settings(max_examples=300, deadline=None)
@given(
    st.integers(1, 3).flatmap(
        lambda n: st.tuples(
            points(n),
            st.integers(1, 12).flatmap(points),
            st.integers(1, 6),
            st.randoms(use_true_random=False),
        )
    )
)
def test_tasks_out_of_reach_are_never_kept(case) -> None:
    # Any true distances no shorter than the straight-line bound, reads no shorter than them (inf where not
    # read): the tasks cap_tasks keeps, and their distances, are the same when the tasks tasks_in_reach
    # leaves out stay at inf wherever they were not read.
    robots_l, tasks_l, cap, rnd = case
    robots, tasks = np.array(robots_l, np.float64), np.array(tasks_l, np.float64)
    gap = np.abs(tasks[None] - robots[:, None])
    octile = gap.max(axis=2) + (np.sqrt(2.0) - 1.0) * gap.min(axis=2)
    true = octile * np.array([[1.0 + rnd.choice([0.0, 0.3, 1.0]) for _ in tasks_l] for _ in robots_l])
    reads = np.where(
        np.array([[rnd.random() < 0.5 for _ in tasks_l] for _ in robots_l]),
        true * np.array([[1.0 + rnd.choice([0.0, 0.5]) for _ in tasks_l] for _ in robots_l]),
        np.inf,
    )
    final = np.where(np.isfinite(reads), reads, true)  # what the searches would have found
    needed = tasks_in_reach(reads, robots, tasks, cap)
    pruned = np.where(np.isfinite(reads) | needed[None, :], final, np.inf)
    keep = cap_tasks(final.min(axis=0), cap)
    assert cap_tasks(pruned.min(axis=0), cap).tolist() == keep.tolist()
    np.testing.assert_array_equal(pruned[:, keep], final[:, keep])


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
    d = pipeline.decide(DecisionInput(state, np.array([[2, 3]], np.int32), 0.2))
    assert d.done_reason is None
    assert d.clusters.members_rc.tolist() == [[1, 1], [1, 9]] and d.clusters.labels.tolist() == [0, 0]
    assert d.routes[0].tolist() == [[1, 1], [1, 9]] and d.goals_rc.tolist() == [[1, 1]]


def test_coscan_and_the_oracle_plug_in_through_the_candidate_seam() -> None:
    """Strategies that choose their own candidates supply them (and their routing) through the pipeline's
    seam; none overrides the shared decision (STYLE rule 17)."""
    from mrexplore.pipeline import CoScanPipeline, ExplorationPipeline, OraclePipeline

    for cls in (CoScanPipeline, OraclePipeline):
        assert "decide" not in cls.__dict__ and "pose" not in cls.__dict__ and "finish" not in cls.__dict__
        assert "candidates" in cls.__dict__ and "route" in cls.__dict__
    assert ExplorationPipeline.decide is CoScanPipeline.decide


def test_a_new_strategy_supplies_candidates_without_touching_the_decision() -> None:
    """A strategy offering two fixed cells as candidates: the shared code measures the distances, the
    Hungarian planner assigns, paths lead there."""
    from conftest import state_grid

    from mrexplore.global_planning.classical import GeodesicPlanner
    from mrexplore.pipeline import CandidateSet, ExplorationPipeline
    from mrexplore.preprocessing.clustering import Clusters

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
    d = TwoCells("two", GeodesicPlanner()).decide(DecisionInput(grid, np.array([[2, 6], [2, 2]], np.int32), 0.1))
    assert d.done_reason is None
    assert d.goals_rc.tolist() == [[1, 7], [1, 1]]  # each robot to the nearer cell
    assert d.paths[0][0].tolist() == [2, 6] and d.paths[0][-1].tolist() == [1, 7]


def test_coscan_robot_fields_stop_once_they_reach_the_tasks() -> None:
    # Unknown only at the left end of a closed corridor: the tasks lie in column 1. The robot in column 5
    # needs nothing beyond them, so its search stops there: the far end (23 cells away) reads inf. Whole
    # fields, which CoScan-2D searched before, read 23 there.
    state = state_grid("#" * 30 + "\n" + ("?" + "." * 28 + "#\n") * 2 + "#" * 30)
    robots = np.array([[1, 5]], np.int32)
    posed = make_strategy("coscan").pose(DecisionInput(state, robots, 0.2))
    assert posed.work is not None and posed.work.candidates is not None
    assert posed.work.candidates.context.tasks_rc.tolist() == [[1, 1]]
    field = posed.work.fields[0]
    assert field.value(1, 1) == 4.0 and field.value(1, 5) == 0.0
    assert field.value(1, 28) == np.inf


def test_near_far_coscan_decides_a_long_corridor_as_the_exact_one_does() -> None:
    # A corridor 39 cells long, unknown at both ends, one robot near the left end: tasks at both ends,
    # farther apart than delta (2 m = 10 cells at 0.2 m), so two clusters; the robot takes the nearer.
    # With every grid treated as large (far_above_cells 0), an exact radius of 5 cells and blocks of 2,
    # the right end's distances are estimates and only centroid rows are searched: the same decision.
    from mrexplore.config import GlobalPlanningConfig
    from mrexplore.paths.far_field import NearFarField

    state = state_grid("#" * 41 + "\n" + ("?" + "." * 39 + "?\n") * 3 + "#" * 41)
    robots = np.array([[2, 8]], np.int32)
    far_cfg = GlobalPlanningConfig(far_above_cells=0, exact_radius_m=1.0, coarse_cell_m=0.4)
    exact, far = make_strategy("coscan"), make_strategy("coscan", far_cfg)
    posed = far.pose(DecisionInput(state, robots, 0.2))
    assert posed.work is not None and all(isinstance(f, NearFarField) for f in posed.work.fields)
    d_exact, d_far = exact.decide(DecisionInput(state, robots, 0.2)), far.decide(DecisionInput(state, robots, 0.2))
    assert d_far.clusters.members_rc.tolist() == d_exact.clusters.members_rc.tolist() == [[1, 1], [1, 39]]
    assert d_far.clusters.labels.tolist() == d_exact.clusters.labels.tolist() == [0, 1]
    assert d_far.goals_rc.tolist() == d_exact.goals_rc.tolist() == [[1, 1]]
    assert [p.tolist() for p in d_far.paths] == [p.tolist() for p in d_exact.paths]


def test_near_far_coscan_tours_a_far_cluster_as_the_exact_one_does() -> None:
    # Unknown above the left end of a corridor: frontier cells (2, 1..9), tasks 0.5 m (2.5 cells) apart at
    # columns 1, 4, 7, one cluster round the middle one (each within delta). The robot is 28 cells from
    # the nearest, beyond the exact radius (5 cells): both tour the cluster from column 7. Near/far
    # searched one task row, the centroid's (task 1); the tour's distances come from the cluster's box.
    from mrexplore.config import GlobalPlanningConfig

    state = state_grid("""
        #########################################
        #?????????###############################
        #.......................................#
        #.......................................#
        #########################################
    """)
    robots = np.array([[3, 35]], np.int32)
    far_cfg = GlobalPlanningConfig(far_above_cells=0, exact_radius_m=1.0, coarse_cell_m=0.4)
    exact, far = make_strategy("coscan"), make_strategy("coscan", far_cfg)
    d_exact = exact.decide(DecisionInput(state, robots, 0.2))
    posed = far.pose(DecisionInput(state, robots, 0.2))
    d_far = far.finish(posed, far.assign(posed))
    assert d_exact.clusters.members_rc.tolist() == d_far.clusters.members_rc.tolist() == [[2, 1], [2, 4], [2, 7]]
    assert d_exact.clusters.labels.tolist() == d_far.clusters.labels.tolist() == [0, 0, 0]
    assert d_exact.routes[0].tolist() == d_far.routes[0].tolist() == [[2, 7], [2, 4], [2, 1]]
    assert [p.tolist() for p in d_far.paths] == [p.tolist() for p in d_exact.paths]
    assert posed.work is not None and posed.work.candidates is not None
    assert sorted(posed.work.candidates.context.rows.cache) == [1]


def test_near_far_tour_distances_leave_the_clusters_box_through_near_far_rows() -> None:
    # Two tasks 4 cells apart either side of a wall open only 11 rows down: the way round (24.8 cells)
    # leaves the tasks' box grown by the exact radius (2 cells), so both rows come from near/far fields
    # (blocks of 2 beyond the radius): a real path, not shorter than the exact one; symmetric.
    from mrexplore.paths.distance_field import distance_matrix
    from mrexplore.paths.far_field import coarse_grid
    from mrexplore.pipeline import FarDistances
    from mrexplore.pipeline.coscan import _CoScanTasks, _NearFarRows

    passable = np.ones((14, 7), bool)
    passable[0:12, 3] = False
    tasks = np.array([[1, 1], [1, 5]], np.int32)
    grid = coarse_grid(passable, 2)
    assert grid is not None
    far = FarDistances(2, grid)
    rows = _NearFarRows(passable, tasks, far)
    context = _CoScanTasks(tasks, np.zeros((1, 2)), rows, np.zeros(2, np.int64), passable, far)
    d = context.between(np.array([0, 1]))
    exact = distance_matrix(passable, tasks, tasks)[0, 1]
    assert round(exact, 3) == 24.828 and d[0, 1] == d[1, 0] == 28.0 and d[0, 0] == 0.0
    assert sorted(rows.cache) == [0, 1]


def test_near_far_rows_and_robot_distances_fall_back_to_exact_searches_behind_a_narrow_gap() -> None:
    # A one-cell gap in a wall closes every 3 x 3 block round it: the coarse grid cannot cross it, so
    # the near/far fields (exact radius 4) leave the far side at inf. Task 0 at (0, 0), task 1 at
    # (0, 12) across the wall (2 cells in, beyond the radius), task 2 at (0, 19): the rows and the robot's
    # distances come back exact from searches. Tasks 1 and 2, 7 cells apart on the same side, read each
    # other's estimate: 5 + 2 sqrt(2) round the blocks, never shorter than the exact 7.
    from mrexplore.paths.distance_field import distance_matrix
    from mrexplore.paths.far_field import coarse_grid, far_fields
    from mrexplore.pipeline import FarDistances
    from mrexplore.pipeline.coscan import _NearFarRows

    passable = ~bool_grid(NARROW_GAP)
    tasks = np.array([[0, 0], [0, 12], [0, 19]], np.int32)
    grid = coarse_grid(passable, 3)
    assert grid is not None
    far = FarDistances(4, grid)
    exact = distance_matrix(passable, tasks, tasks)
    rows = _NearFarRows(passable, tasks, far)
    got = rows(np.array([0, 1, 2]))
    assert np.isinf(rows.raw[0][1:]).all()  # task 0's own field cannot see past the gap
    np.testing.assert_allclose(got[0], exact[0], rtol=1e-6)  # filled by searches: exact
    assert got[1, 2] == pytest.approx(7.828427, abs=1e-5) and got[2, 1] == pytest.approx(7.828427, abs=1e-5)
    assert exact[1, 2] == 7.0
    robots = np.array([[5, 0]], np.int32)
    fields = far.fields(passable, robots, own_rc=[tasks])  # what CoScan's candidates ask for
    d = np.stack([f.at(tasks) for f in fields])
    from_robot = distance_matrix(passable, robots, tasks)[0]
    np.testing.assert_allclose(d[0, 1:], from_robot[1:], rtol=1e-6)  # past the gap: searched exactly
    assert d[0, 0] >= from_robot[0] == 5.0  # 5 cells, beyond the radius: the blocks' estimate
    assert fields[0].value(0, 19) == pytest.approx(d[0, 2])  # noted in the field for the paths
    assert far_fields(passable, robots, 4, 3)[0].value(0, 19) == np.inf
    # A filter of the shared own cells (CoScan's tasks beyond those it may keep) leaves task 2 unsearched;
    # task 1's search from the robot gives what it gave with every task.
    seen: list[np.ndarray] = []

    def only_task_1(reads: np.ndarray) -> np.ndarray:
        seen.append(reads)
        return np.array([False, True, False])

    filtered = far.fields(passable, robots, own_rc=[tasks], own_needed=only_task_1)[0]
    assert np.isinf(seen[0][0, 1:]).all()  # the reads before any search: the far side unread
    assert filtered.value(0, 12) == fields[0].value(0, 12) and filtered.value(0, 19) == np.inf
    with pytest.raises(ValueError, match="give every source the same own_rc"):
        far.fields(passable, np.vstack([robots, robots]), own_rc=[tasks, tasks[:1]], own_needed=only_task_1)
