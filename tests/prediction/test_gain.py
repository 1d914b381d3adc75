"""The predicted gain of a scan and the planner that rewards it, on hand-drawn maps."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from conftest import state_grid

from mrexplore.config import GlobalPlanningConfig
from mrexplore.global_planning.predictive import PredictionAhead, PredictiveUtilityPlanner, predicted_terms
from mrexplore.global_planning.protocol import AssignmentProblem
from mrexplore.prediction.baselines import predict_all_free
from mrexplore.prediction.gain import predicted_gain_m2
from mrexplore.prediction.network import MapPredictor
from mrexplore.prediction.unet import UNetNp, layer_shapes
from mrexplore.preprocessing.clustering import Clusters
from mrexplore.types import CellState

# A corridor; its east end opens on unknown space, its west end on an unknown pocket of 2 cells.
BELIEF = """
    ###########
    ??.......??
    ###########
"""


def test_a_scan_counts_each_reachable_unknown_cell_by_its_probability_of_being_free() -> None:
    state = state_grid(BELIEF)
    p = predict_all_free(state, 1.0)
    # from (1, 2), 10 m: both unknown cells west (1, 0), (1, 1) and both east (1, 9), (1, 10)
    assert predicted_gain_m2(state, p, np.array([[1, 2]]), 1.0, 10.0).tolist() == [4.0]
    p[1, 1] = 0.2  # the west pocket is probably a wall: its first cell counts 0.2 and hides the second
    assert predicted_gain_m2(state, p, np.array([[1, 2]]), 1.0, 10.0) == pytest.approx([2.2])
    # out of range: from (1, 2) with 1.5 m only (1, 1) is reached
    assert predicted_gain_m2(state, p, np.array([[1, 2]]), 1.0, 1.5) == pytest.approx([0.2])
    # 0.5 m cells: the areas are a quarter
    assert predicted_gain_m2(state, predict_all_free(state, 0.5), np.array([[1, 2]]), 0.5, 5.0).tolist() == [1.0]


def test_the_planner_sends_the_robot_where_more_is_predicted_at_equal_distance() -> None:
    state = state_grid(BELIEF)
    clusters = Clusters(np.array([[1, 2], [1, 8]], np.int32), np.array([1, 1], np.int32), np.zeros((2, 2), np.int32),
                        np.zeros(2, np.int32))  # fmt: skip
    problem = AssignmentProblem(np.array([[1, 5]], np.int32), clusters, np.array([[3.0, 3.0]]), 1.0, state)
    wide = GlobalPlanningConfig(gain_weight=1.0, gain_range_m=10.0)
    assert predicted_terms(None, problem, wide).gain_m2.tolist() == [4.0, 4.0]  # each centre sees every unknown cell
    small = GlobalPlanningConfig(gain_weight=1.0, gain_range_m=2.0)  # west: (1,0),(1,1); east: (1,9),(1,10)
    planner = PredictiveUtilityPlanner(None, small)
    assert predicted_terms(None, problem, small).gain_m2.tolist() == [2.0, 2.0]
    state[1, 10] = CellState.FREE  # the east end seen: one unknown cell left there
    assert predicted_terms(None, problem, small).gain_m2.tolist() == [2.0, 1.0]
    assert planner.assign(problem).cluster_of_robot.tolist() == [0]


# A loop of known corridor around a block of wall, open at the top but for one unknown cell (1, 3).
LOOP = """
    #######
    #..?..#
    #.###.#
    #.....#
    #######
"""


def test_the_predicted_shortcut_is_the_known_path_less_the_predicted_one() -> None:
    """From (1, 1), the cluster at (1, 4) is 9 cells away through known space (down, along, up) and 3 through
    the unknown cell if it is free: a shortcut of 6 m; the cluster at (1, 2) has none."""
    from mrexplore.prediction.gain import predicted_paths_m

    state = state_grid(LOOP)
    clusters = Clusters(np.array([[1, 2], [1, 4]], np.int32), np.array([1, 1], np.int32), np.zeros((2, 2), np.int32),
                        np.zeros(2, np.int32))  # fmt: skip
    p = predict_all_free(state, 1.0)
    assert predicted_paths_m(state, p, np.array([[1, 1]]), clusters.centers_rc, 1.0).tolist() == [[1.0, 3.0]]
    p[1, 3] = 0.0  # a predictor that walls the gap: the known paths
    assert predicted_paths_m(state, p, np.array([[1, 1]]), clusters.centers_rc, 1.0).tolist() == [[1.0, 9.0]]
    problem = AssignmentProblem(np.array([[1, 1]], np.int32), clusters, np.array([[1.0, 9.0]]), 1.0, state)
    cfg = GlobalPlanningConfig(gain_weight=0.0, path_weight=1.0)
    terms = predicted_terms(None, problem, cfg)
    assert terms.shortcut_m is not None and terms.shortcut_m.tolist() == [[0.0, 6.0]]
    assert predicted_terms(None, problem, GlobalPlanningConfig(gain_weight=0.0)).shortcut_m is None  # weight 0
    # path_weight per metre of shortcut: at an equal known distance of 9 m (shortcuts 8 and 6 m) a positive
    # weight takes the cluster with the shorter shortcut, a negative weight the one with the longer
    tie = AssignmentProblem(np.array([[1, 1]], np.int32), clusters, np.array([[9.0, 9.0]]), 1.0, state)
    assert predicted_terms(None, tie, cfg).shortcut_m.tolist() == [[8.0, 6.0]]  # type: ignore[union-attr]
    assert PredictiveUtilityPlanner(None, cfg).assign(tie).cluster_of_robot.tolist() == [1]
    against = GlobalPlanningConfig(gain_weight=0.0, path_weight=-1.0)
    assert PredictiveUtilityPlanner(None, against).assign(tie).cluster_of_robot.tolist() == [0]


def _constant_predictor(logit: float) -> MapPredictor:
    """A predictor whose network gives ``logit`` on every cell (its weights 0, the head's bias ``logit``)."""
    state = {}
    for name, (o, i, k) in layer_shapes(1).items():
        state[f"{name}.weight"] = np.zeros((o, i, k, k), np.float32)
        state[f"{name}.bias"] = np.full(o, logit if name == "head" else 0.0, np.float32)
    return MapPredictor(UNetNp(1, state), 0.2, Path("constant.npz"), "", {})


@pytest.mark.parametrize("threads", ["1", "2"])
def test_a_prediction_started_ahead_is_taken_for_its_own_grid_only(monkeypatch, threads: str) -> None:
    """The completion started for the problem's own grid array is the one taken; one started for another
    array (here a belief with the east end seen) is passed over and the problem's grid completed anew."""
    monkeypatch.setenv("MREXPLORE_THREADS", threads)
    pred = _constant_predictor(-2.0)  # unknown cells near known ones: p = 0.119
    state = state_grid(BELIEF)
    other = state.copy()
    other[1, 9:] = CellState.FREE
    ahead = PredictionAhead()
    ahead.start(pred, other, 1.0)
    taken = ahead.take(pred, state, 1.0)  # the problem's grid, not the one started
    assert taken[1, 10] == pytest.approx(1 / (1 + np.exp(2.0)))
    ahead.start(pred, other, 1.0)
    assert ahead.take(pred, other, 1.0)[1, 10] == 1.0  # the one started for this very array
    assert ahead.take(pred, other, 1.0)[1, 10] == 1.0  # nothing left started: computed now, the same
    clusters = Clusters(np.array([[1, 2], [1, 8]], np.int32), np.array([1, 1], np.int32), np.zeros((2, 2), np.int32),
                        np.zeros(2, np.int32))  # fmt: skip
    problem = AssignmentProblem(np.array([[1, 5]], np.int32), clusters, np.array([[3.0, 3.0]]), 1.0, state)
    cfg = GlobalPlanningConfig(gain_weight=1.0, gain_range_m=2.0)
    planner = PredictiveUtilityPlanner(pred, cfg)
    planner.begin(other, 1.0)  # started on a stale grid: the answer is still the problem's own
    want = predicted_terms(pred, problem, cfg).gain_m2
    assert predicted_terms(pred, problem, cfg, ahead=planner.ahead).gain_m2.tolist() == want.tolist()
    assert want[1] == pytest.approx(1 / (1 + np.exp(2.0)))  # east: (1, 9) at p = 0.119 stops the beam (0 on other)


def test_a_policy_that_reads_the_predicted_shortcut_gets_the_loops_six_metres() -> None:
    """The loop above, seen by a policy trained with ``use_predicted_path``: robot (1, 1)'s shortcut to the
    cluster at (1, 4) is 6 m, over the 10 m distance scale, and none to (1, 2)."""
    from mrexplore.config import LearnedConfig
    from mrexplore.global_planning.learned.policy import LearnedPlanner
    from mrexplore.training.checkpoint import VALUE_INPUTS
    from mrexplore.training.hier_net import MultiGraphNet

    state = state_grid(LOOP)
    clusters = Clusters(np.array([[1, 2], [1, 4]], np.int32), np.array([1, 1], np.int32), np.zeros((2, 2), np.int32),
                        np.zeros(2, np.int32))  # fmt: skip
    problem = AssignmentProblem(np.array([[1, 1]], np.int32), clusters, np.array([[1.0, 9.0]]), 1.0, state)
    net = MultiGraphNet(LearnedConfig(hidden=4, blocks=1, use_predicted_path=True), VALUE_INPUTS)
    edges = LearnedPlanner(net).inputs(problem).edges
    assert edges.shape == (1, 2, 6) and edges[..., 5].tolist() == [[0.0, pytest.approx(0.6)]]
