"""Classical assigners and the Hungarian matching, on numbers checkable by hand."""

from __future__ import annotations

import numpy as np
from conftest import state_grid

from mrexplore.config import GlobalPlanningConfig
from mrexplore.global_planning.classical import NearestPlanner, UtilityPlanner, utility_cost
from mrexplore.global_planning.hungarian import match_min_cost
from mrexplore.global_planning.protocol import UNASSIGNED, AssignmentProblem, GlobalPlanner
from mrexplore.preprocessing.clustering import Clusters


def _problem(dist_cells: list[list[float]], sizes: list[int], res: float = 0.1) -> AssignmentProblem:
    k = len(sizes)
    centers = np.array([[0, j] for j in range(k)], np.int32).reshape(-1, 2)
    clusters = Clusters(centers, np.array(sizes, np.int32), centers, np.arange(k, dtype=np.int32))
    d = np.array(dist_cells, dtype=np.float64)
    return AssignmentProblem(np.zeros((len(d), 2), np.int32), clusters, d, res, state_grid(".."))


def test_planners_follow_the_protocol() -> None:
    assert isinstance(NearestPlanner(), GlobalPlanner) and isinstance(UtilityPlanner(), GlobalPlanner)


def test_nearest_is_uncoordinated() -> None:
    p = _problem([[10, 20], [12, 30], [np.inf, np.inf]], [5, 5])
    assert NearestPlanner().assign(p).cluster_of_robot.tolist() == [0, 0, UNASSIGNED]


def test_utility_cost_is_explore_lite() -> None:
    # 3 * d_m - 1 * size_m: d = 20 cells = 2 m, size 30 cells = 3 m -> 6 - 3 = 3.
    p = _problem([[20, 10]], [30, 2])
    np.testing.assert_allclose(utility_cost(p, GlobalPlanningConfig()), [[3.0, 2.8]])


def test_utility_coordinates_robots() -> None:
    # Both robots are nearer cluster 0; the Hungarian sends robot 1 to cluster 1 (total 10 + 12 < 11 + 20).
    p = _problem([[10, 20], [11, 12]], [1, 1], res=1.0)
    assert UtilityPlanner().assign(p).cluster_of_robot.tolist() == [0, 1]


def test_big_cluster_wins_over_near_small_one() -> None:
    # d 1 m vs 2 m; sizes 1 vs 100 cells at 0.1 m: costs 3 - 0.1 = 2.9 and 6 - 10 = -4.
    p = _problem([[10, 20]], [1, 100])
    assert UtilityPlanner().assign(p).cluster_of_robot.tolist() == [1]


def test_spare_robots_share_after_every_cluster_is_taken() -> None:
    cost = np.array([[1.0, 9.0], [2.0, 1.0], [1.5, 20.0], [np.inf, np.inf]])
    assert match_min_cost(cost).tolist() == [0, 1, 0, UNASSIGNED]


def test_unreachable_pairs_never_chosen() -> None:
    cost = np.array([[np.inf, 5.0], [np.inf, 1.0]])
    assert match_min_cost(cost).tolist() in ([UNASSIGNED, 1], [1, UNASSIGNED])
    assert match_min_cost(cost).tolist() == [UNASSIGNED, 1]
