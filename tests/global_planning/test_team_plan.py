"""The team plan: min-max routes on numbers checkable by hand, its invariants on random instances, and the
planners built on it."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from conftest import state_grid
from hypothesis import given, settings
from hypothesis import strategies as st
from random_problems import random_problem

from mrexplore.config import GlobalPlanningConfig
from mrexplore.global_planning.classical import UtilityPlanner
from mrexplore.global_planning.protocol import AssignmentProblem, GlobalPlanner
from mrexplore.global_planning.team_plan import PlanCostPlanner, TeamPlanPlanner, plan_routes, route_costs
from mrexplore.preprocessing.clustering import Clusters


def _line(robots: list[float], clusters: list[float]) -> tuple[np.ndarray, np.ndarray]:
    r, x = np.array(robots), np.array(clusters)
    return np.abs(r[:, None] - x[None, :]), np.abs(x[:, None] - x[None, :])


def _brute_makespan(start: np.ndarray, between: np.ndarray) -> float:
    """The least makespan over every split of the clusters between the robots and every order."""
    n_r, n_k = start.shape
    best = np.inf
    for owners in itertools.product(range(n_r), repeat=n_k):
        worst = 0.0
        for i in range(n_r):
            mine = [k for k in range(n_k) if owners[k] == i]
            orders = itertools.permutations(mine) if mine else []
            legs = (start[i, o[0]] + sum(between[a, b] for a, b in itertools.pairwise(o)) for o in orders)
            cost = min(legs, default=0.0)
            worst = max(worst, cost)
        best = min(best, worst)
    return float(best)


def test_a_route_takes_the_cluster_a_nearer_robot_would_take_first() -> None:
    # Robots at 0 and 10, clusters at 1, 9 and 19. Each to its nearest (utility's matching) leaves 19 to the
    # robot at 10 after 9: makespan 1 + 10 = 11. The plan sends the robot at 10 straight to 19 (9) and the
    # robot at 0 through 1 and 9 (1 + 8 = 9).
    start, between = _line([0, 10], [1, 9, 19])
    plan = plan_routes(start, between)
    assert [r.tolist() for r in plan.routes] == [[0, 1], [2]]
    assert plan.costs.tolist() == [9.0, 9.0] and plan.makespan == 9.0


def test_service_time_counts_per_cluster() -> None:
    start, between = _line([0], [2, 5])
    plan = plan_routes(start, between, service=np.array([1.0, 3.0]))
    assert plan.routes[0].tolist() == [0, 1] and plan.makespan == 2 + 1 + 3 + 3


def test_unreachable_clusters_are_on_no_route_and_robots_take_only_what_they_reach() -> None:
    start = np.array([[1.0, np.inf, np.inf], [np.inf, 2.0, np.inf]])
    between = np.array([[0.0, np.inf, np.inf], [np.inf, 0.0, np.inf], [np.inf, np.inf, 0.0]])
    plan = plan_routes(start, between)
    assert [r.tolist() for r in plan.routes] == [[0], [1]]


def test_first_regret_is_what_heading_elsewhere_first_adds_to_the_makespan() -> None:
    # Robots at 0 and 10, clusters at 1, 2, 8, 9: routes [1, 2] and [9, 8], makespan 2. Robot 0 heading for
    # the cluster at 2 first: 2 then 1, makespan 3 (+1); for the one at 8: 8 then 1 then 2 (8 + 7 + 1 = 16,
    # +14), robot 1 left with 9 alone.
    start, between = _line([0, 10], [1, 2, 8, 9])
    plan = plan_routes(start, between)
    assert [r.tolist() for r in plan.routes] == [[0, 1], [3, 2]]
    assert plan.first_regret.tolist() == [[0.0, 1.0, 14.0, 16.0], [16.0, 14.0, 1.0, 0.0]]


@settings(max_examples=60, deadline=None)
@given(st.integers(1, 3), st.integers(1, 5), st.integers(0, 2**31 - 1))
def test_routes_cover_every_reachable_cluster_once_at_the_costs_they_state(n_r: int, n_k: int, seed: int) -> None:
    rng = np.random.default_rng(seed)
    pts, robots = rng.integers(0, 20, (n_k, 2)), rng.integers(0, 20, (n_r, 2))
    start = np.abs(robots[:, None] - pts[None]).sum(-1).astype(float)
    between = np.abs(pts[:, None] - pts[None]).sum(-1).astype(float)
    start[rng.random(start.shape) < 0.2] = np.inf
    plan = plan_routes(start, between)
    visited = np.concatenate(plan.routes)
    assert sorted(visited.tolist()) == np.flatnonzero(np.isfinite(start).any(0)).tolist()
    np.testing.assert_allclose(route_costs(plan, start, between), plan.costs)
    for i, route in enumerate(plan.routes):
        assert np.isfinite(start[i, route]).all()
    if np.isfinite(start).all():
        # Never worse than 1.5 times the optimum on these small instances (mostly equal to it).
        assert plan.makespan <= 1.5 * _brute_makespan(start, between) + 1e-9


def test_the_heuristic_is_near_the_optimum_on_small_instances() -> None:
    # 2 robots, 5 clusters, Euclidean: the optimum (brute force) on 29 of 40, 1.9% above it on average.
    rng = np.random.default_rng(0)
    gaps = []
    for _ in range(40):
        pts, robots = rng.uniform(0, 20, (5, 2)), rng.uniform(0, 20, (2, 2))
        start = np.linalg.norm(robots[:, None] - pts[None], axis=2)
        between = np.linalg.norm(pts[:, None] - pts[None], axis=2)
        gaps.append(plan_routes(start, between).makespan / _brute_makespan(start, between) - 1.0)
    assert min(gaps) > -1e-9
    assert sum(g < 1e-9 for g in gaps) >= 29 and np.mean(gaps) < 0.02


def _corridor_problem() -> AssignmentProblem:
    # One corridor, robots at columns 0 and 10, one-cell clusters at 1, 9 and 19.
    state = state_grid("." * 20)
    centres = np.array([[0, 1], [0, 9], [0, 19]], np.int32)
    clusters = Clusters(centres, np.ones(3, np.int32), centres, np.arange(3, dtype=np.int32))
    robots = np.array([[0, 0], [0, 10]], np.int32)
    dist = np.abs(robots[:, 1:2] - centres[None, :, 1]).astype(np.float64)
    return AssignmentProblem(robots, clusters, dist, 1.0, state)


def test_team_plan_planner_sends_each_robot_to_its_routes_first_cluster() -> None:
    problem = _corridor_problem()
    np.testing.assert_array_equal(problem.cluster_dist_cells, [[0, 8, 18], [8, 0, 10], [18, 10, 0]])
    assert UtilityPlanner().assign(problem).cluster_of_robot.tolist() == [0, 1]
    planner = TeamPlanPlanner()
    assert isinstance(planner, GlobalPlanner)
    assert planner.assign(problem).cluster_of_robot.tolist() == [0, 2]
    assert planner.last_plan is not None and planner.last_plan.makespan == 9.0


@pytest.mark.parametrize("seed", range(30))
def test_plan_cost_at_weight_zero_is_the_base_matching(seed: int) -> None:
    problem = random_problem(np.random.default_rng(seed))
    planner = PlanCostPlanner(None, GlobalPlanningConfig(plan_weight=0.0))
    assert (
        planner.assign(problem).cluster_of_robot.tolist() == UtilityPlanner().assign(problem).cluster_of_robot.tolist()
    )


def test_plan_cost_follows_the_plan_when_it_weighs_enough() -> None:
    # Utility costs 3 * d - 1 (one-cell clusters at 1 m a cell): robot 1 to 9 costs 2, to 19 costs 26. Robot 1
    # heading for 9 first lengthens the plan's makespan by 2 m (9 then 19: 11 against 9), which costs
    # 3 * weight * 2: at weight 4 the two matchings tie (2 + 2 + 24 = 2 + 26), above it the plan's wins.
    problem = _corridor_problem()
    assert PlanCostPlanner(None, GlobalPlanningConfig(plan_weight=3.0)).assign(problem).cluster_of_robot.tolist() == [
        0,
        1,
    ]
    assert PlanCostPlanner(None, GlobalPlanningConfig(plan_weight=5.0)).assign(problem).cluster_of_robot.tolist() == [
        0,
        2,
    ]


def test_hier_plan_at_weight_zero_decides_as_hier() -> None:
    from mrexplore.pipeline import make_strategy

    hier = make_strategy("hier").planner
    plan = make_strategy("hier-plan", GlobalPlanningConfig(plan_weight=0.0)).planner
    for seed in range(20):
        problem = random_problem(np.random.default_rng(seed))
        assert plan.assign(problem).cluster_of_robot.tolist() == hier.assign(problem).cluster_of_robot.tolist()
