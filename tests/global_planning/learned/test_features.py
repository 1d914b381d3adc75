"""The network's inputs on a hand-drawn decision: every edge feature checkable by hand."""

from __future__ import annotations

import numpy as np
import pytest

from mrexplore.config import GlobalPlanningConfig, LearnedConfig
from mrexplore.global_planning.learned.features import edge_feature_count, graph_inputs, route_positions
from mrexplore.global_planning.learned.policy import LearnedPlanner
from mrexplore.global_planning.protocol import AssignmentProblem
from mrexplore.global_planning.team_plan import TeamPlanPlanner
from mrexplore.preprocessing.clustering import Clusters
from mrexplore.training.checkpoint import VALUE_INPUTS
from mrexplore.training.hier_net import MultiGraphNet


def _problem(current: list[int] | None = None) -> AssignmentProblem:
    # Two robots at (0, 0) and (0, 4); three clusters at (0, 10), (0, 14) and (8, 0); 1 m cells.
    centres = np.array([[0, 10], [0, 14], [8, 0]], np.int32)
    sizes = np.array([5, 10, 2], np.int32)
    members = np.repeat(centres, sizes, axis=0)
    labels = np.repeat(np.arange(3, dtype=np.int32), sizes)
    dist = np.array([[10.0, 14.0, 8.0], [6.0, 10.0, np.inf]])
    return AssignmentProblem(
        np.array([[0, 0], [0, 4]], np.int32),
        Clusters(centres, sizes, members, labels),
        dist,
        1.0,
        np.zeros((9, 15), np.uint8),
        current_cluster=None if current is None else np.array(current, np.int64),
    )


def test_edge_features_by_hand() -> None:
    g = graph_inputs(_problem([1, -1]), LearnedConfig(distance_scale_m=2.0, size_scale_m=5.0), GlobalPlanningConfig())
    e = g.edges
    assert e[..., 0].tolist() == [[5.0, 7.0, 4.0], [3.0, 5.0, 10.0]]  # d / 2 m; unreachable clipped to 10
    assert e[0, :, 1].tolist() == pytest.approx([1.0, 2.0, 0.4])  # |C_k| x 1 m / 5 m
    # advantage: d_ik - the other robot's d_jk, halved: robot 0 is 2 m behind for both near clusters
    assert e[..., 2].tolist() == [[2.0, 2.0, -6.0], [-2.0, -2.0, 6.0]]
    assert e[..., 3].tolist() == [[0.0, 1.0, 0.0], [0.0, 0.0, 0.0]]  # robot 0's goal lies in cluster 1
    # isolation: straight line to the nearest other centre, halved: 4 m, 4 m, sqrt(64 + 100) m
    assert e[0, :, 4].tolist() == pytest.approx([2.0, 2.0, np.sqrt(164) / 2])
    assert g.reachable.tolist() == [[True, True, True], [True, True, False]]
    # base: -(3 d - 1 x size) / 3
    assert g.base[0].tolist() == pytest.approx([-(30 - 5) / 3, -(42 - 10) / 3, -(24 - 2) / 3])
    assert g.base[1, 2] == 0.0
    # nodes: metres from the robots' centroid (0, 2) over 2 m; robots labelled 1
    assert g.robots.tolist() == [[0.0, -1.0, 1.0], [0.0, 1.0, 1.0]]
    assert g.clusters[2].tolist() == pytest.approx([4.0, -1.0, 0.0, 0.4])


def test_switched_off_features_are_zero() -> None:
    cfg = LearnedConfig(use_advantage=False, use_current_goal=False, use_isolation=False)
    g = graph_inputs(_problem([1, 0]), cfg, GlobalPlanningConfig())
    assert not g.edges[..., 2:].any()


def test_a_policy_that_reads_the_predicted_gain_gets_it_as_a_sixth_edge_feature() -> None:
    cfg = LearnedConfig(use_predicted_gain=True, gain_scale_m2=4.0)
    g = graph_inputs(_problem(), cfg, GlobalPlanningConfig(), gain_m2=np.array([8.0, 2.0, 100.0]))
    assert g.edges.shape == (2, 3, 6)
    assert g.edges[..., 5].tolist() == [[2.0, 0.5, 10.0]] * 2  # m^2 / 4, the same for both robots, clipped
    with pytest.raises(ValueError, match=r"needs one per cluster \(3\), got None"):
        graph_inputs(_problem(), cfg, GlobalPlanningConfig())
    assert graph_inputs(_problem(), LearnedConfig(), GlobalPlanningConfig()).edges.shape == (2, 3, 5)


def test_a_policy_that_reads_the_predicted_shortcut_gets_it_per_pair_after_the_gain() -> None:
    shortcut = np.array([[0.0, 6.0, 500.0], [2.0, 0.0, 0.0]])  # metres; the scale is distance_scale_m (2 m here)
    for gain, at in ((False, 5), (True, 6)):
        cfg = LearnedConfig(distance_scale_m=2.0, use_predicted_gain=gain, use_predicted_path=True)
        gains = np.zeros(3) if gain else None
        g = graph_inputs(_problem(), cfg, GlobalPlanningConfig(), gain_m2=gains, shortcut_m=shortcut)
        assert g.edges.shape == (2, 3, at + 1)
        assert g.edges[..., at].tolist() == [[0.0, 3.0, 10.0], [1.0, 0.0, 0.0]]  # per robot, clipped at 10
    with pytest.raises(ValueError, match=r"needs one per robot and cluster \(2, 3\), got None"):
        graph_inputs(_problem(), LearnedConfig(use_predicted_path=True), GlobalPlanningConfig())


def test_a_policy_that_reads_the_team_plan_gets_its_regret_and_route_position_last() -> None:
    regret = np.array([[0.0, 4.0, np.inf], [2.0, 0.0, 100.0]])  # metres; inf: the pair is unreachable
    position = route_positions([np.array([2, 0]), np.array([1])], 3)
    assert position.tolist() == [[0.5, 0.0, 1.0], [0.0, 1.0, 0.0]]
    cfg = LearnedConfig(distance_scale_m=2.0, use_predicted_gain=True, use_plan_regret=True, use_plan_position=True)
    g = graph_inputs(_problem(), cfg, GlobalPlanningConfig(), np.zeros(3), None, regret, position)
    assert g.edges.shape == (2, 3, 8) and edge_feature_count(cfg) == 8
    assert g.edges[..., 6].tolist() == [[0.0, 2.0, 10.0], [1.0, 0.0, 10.0]]  # regret / 2 m, clipped at 10
    assert g.edges[..., 7].tolist() == position.tolist()
    with pytest.raises(ValueError, match=r"^a network that reads the plan's position needs one per robot and"):
        graph_inputs(_problem(), LearnedConfig(use_plan_position=True), GlobalPlanningConfig())


def test_the_learned_planner_feeds_the_team_plan_it_makes() -> None:
    problem = _problem()
    cfg = LearnedConfig(use_plan_regret=True, use_plan_position=True)
    planner = LearnedPlanner(MultiGraphNet(cfg, VALUE_INPUTS).eval())
    plan = TeamPlanPlanner(GlobalPlanningConfig()).plan(problem)
    edges = planner.inputs(problem).edges
    regret = np.where(np.isfinite(plan.first_regret), plan.first_regret / cfg.distance_scale_m, 10.0)
    assert edges[..., 5] == pytest.approx(np.minimum(regret, 10.0))
    assert edges[..., 6].tolist() == route_positions(plan.routes, 3).tolist()
