"""The known-world expert: it scores candidates by nothing the team has not seen, leaves the mission as it
was, and ranks a team that stands idle below the heuristic's choice."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from conftest import posed_mission

from mrexplore.global_planning.protocol import UNASSIGNED
from mrexplore.mission import Mission
from mrexplore.pipeline import make_strategy
from mrexplore.training.expert import known_world_returns


def _posed_mission() -> Mission:
    return posed_mission("generated:2", "hier-heuristic", 3, seed=4)[0]


def test_known_world_returns_ignore_the_unseen_and_leave_the_mission_as_it_was() -> None:
    m = _posed_mission()
    problem = m.pose()
    assert problem is not None and problem.n_clusters > 1
    heuristic = m.strategy.planner.assign(problem).cluster_of_robot
    idle = np.full(problem.n_robots, UNASSIGNED, dtype=np.int64)
    before = (m.steps, m.sim.positions_rc.copy(), m.sim.team_observed.copy(), m.sim.known_cells)
    continuation = make_strategy("hier-heuristic").planner
    returns = known_world_returns(m, [heuristic, idle], 400, continuation)
    assert (m.steps, m.sim.known_cells) == (before[0], before[3])
    assert np.array_equal(m.sim.positions_rc, before[1]) and np.array_equal(m.sim.team_observed, before[2])
    # every unseen cell of the world flipped (the map and what the simulator's scans see): the same
    # scores, so nothing unseen reached them (rollouts in the simulator's own world score [-149, -174])
    unseen = ~m.sim.team_observed
    assert unseen.any()
    flipped = np.where(unseen, ~m.truth.occupied, m.truth.occupied)
    m.truth = replace(m.truth, occupied=flipped)
    m.sim.use_walls(flipped)
    assert known_world_returns(m, [heuristic, idle], 400, continuation).tolist() == returns.tolist()
    # minus the steps until no frontier is left: the idle team waits for its next decision first
    assert -400 < returns[1] < returns[0] < 0  # -126 and -101 here


def test_predicted_world_returns_read_the_prediction_not_the_unseen_truth() -> None:
    from mrexplore.training.expert import predicted_world_returns

    m = _posed_mission()
    problem = m.pose()
    assert problem is not None and problem.n_clusters > 1
    heuristic = m.strategy.planner.assign(problem).cluster_of_robot
    idle = np.full(problem.n_robots, UNASSIGNED, dtype=np.int64)
    continuation = make_strategy("hier-heuristic").planner
    before = (m.steps, m.sim.known_cells, m.sim.team_observed.copy())
    open_world = np.ones(m.truth.shape, np.float32)  # every unseen cell predicted free
    returns = predicted_world_returns(m, [heuristic, idle], 200, continuation, open_world)
    assert (m.steps, m.sim.known_cells) == before[:2] and np.array_equal(m.sim.team_observed, before[2])
    # the unseen truth flipped: the same returns, as only the prediction stands for it
    unseen = ~m.sim.team_observed
    flipped = np.where(unseen, ~m.truth.occupied, m.truth.occupied)
    m.truth = replace(m.truth, occupied=flipped)
    m.sim.use_walls(flipped)
    assert predicted_world_returns(m, [heuristic, idle], 200, continuation, open_world).tolist() == returns.tolist()
    # a team that moves sees more of an open predicted world than one that waits
    assert returns[0] > returns[1]
    # every unseen cell predicted wall: no free cell left to see, so the return is eq. 9's time term alone
    walled = predicted_world_returns(m, [heuristic], 200, continuation, np.zeros(m.truth.shape, np.float32))
    assert walled[0] == -float(round(-walled[0])) and -200 <= walled[0] < 0
