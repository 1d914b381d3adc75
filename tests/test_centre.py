"""The centre's planning between messages and goals (TeamPlanner, no ROS) on a tiny room with two openings:
goals, an aborted goal kept from its robot alone, a goal stood on that stayed a frontier, a route moved along,
a silent robot, the end."""

from __future__ import annotations

import numpy as np
import pytest

from mrexplore.config import SensorConfig
from mrexplore.mission.centre import NavState, TeamPlanner
from mrexplore.pipeline import make_strategy
from mrexplore.preprocessing.agents import RobotAgent
from mrexplore.preprocessing.sparse_codec import decode
from mrexplore.types import CellState, MrExploreError

SHAPE = (12, 20)


def room() -> np.ndarray:
    """Free rows 3-8, columns 1-10, walls around; open to unknown space on the east side (column 11) and
    through a door in the north wall (row 2, columns 2-4)."""
    state = np.full(SHAPE, CellState.UNKNOWN, np.uint8)
    state[2:10, 0:11] = CellState.OCCUPIED
    state[3:9, 1:11] = CellState.FREE
    state[2, 2:5] = CellState.UNKNOWN
    return state


def planner_with(robots: list[tuple[int, int]], state: np.ndarray, **kwargs: float) -> TeamPlanner:
    strategy = make_strategy("nearest")
    planner = TeamPlanner(len(robots), SHAPE, 0.1, strategy, silence_rounds=3, blacklist_radius_m=0.2, **kwargs)
    for i, rc in enumerate(robots):
        agent = RobotAgent(i, SHAPE, strategy.preprocess, SensorConfig())
        agent.sense_state(state)
        planner.receive(decode(agent.compose(0, rc, agent.window()).full_bytes()), 0)
    return planner


def test_each_robot_gets_the_nearest_opening_and_a_kept_goal_is_not_sent_again() -> None:
    planner = planner_with([(4, 3), (6, 9)], room())
    sent = planner.plan(0, now=0.0)
    assert sorted(sent) == [0, 1]
    assert sent[0][0] == 3 and 2 <= sent[0][1] <= 4  # under the north door
    assert sent[1][1] == 10  # on the east side
    assert planner.plan(0, now=0.5) == {}  # nothing ended, the period not passed: no decision
    assert planner.plan(0, now=20.0, force=True) == {}  # decided again: both goals kept, nothing to send
    assert planner.decisions == 2


def test_an_aborted_goal_is_kept_from_its_robot_alone_for_blacklist_s() -> None:
    planner = planner_with([(4, 3)], room(), blacklist_s=30.0)
    first = planner.plan(0, now=0.0)[0].copy()
    planner.navigation(0, NavState.ABORTED, now=1.0)
    assert planner.aborts == 1 and planner.goals[0].tolist() == [-1, -1]
    second = planner.plan(0, now=1.0)[0]  # at once, elsewhere: the east side
    assert second[1] == 10 and not np.array_equal(second, first)
    assert planner.barred(0, now=1.0)[first[0], first[1]]
    assert planner.barred(0, now=31.5) is None  # its time is up
    other = planner_with([(4, 3), (6, 9)], room())
    other.plan(0, now=0.0)
    other.navigation(0, NavState.ABORTED, now=1.0)
    assert other.barred(1, now=1.0) is None  # robot 1 may still take that cluster


def test_a_goal_reached_that_stays_a_frontier_stops_being_a_candidate() -> None:
    planner = planner_with([(4, 3)], room())
    goal = planner.plan(0, now=0.0)[0].copy()
    planner.navigation(0, NavState.REACHED, now=2.0)
    assert planner.plan(0, now=2.0)  # a decision at once: the robot's goal ended
    assert not planner.blacklist()[goal[0], goal[1]]  # the robot's map from there is not in yet
    for round_ in (1, 2):  # its next maps: the goal still borders unknown space
        agent = RobotAgent(0, SHAPE, planner.strategy.preprocess, SensorConfig())
        agent.sense_state(room())
        planner.receive(decode(agent.compose(round_, (4, 3), agent.window()).full_bytes()), round_)
    planner.plan(2, now=3.0)
    assert planner.blacklist()[goal[0], goal[1]]


def test_a_silent_robot_gets_no_goal_and_the_centre_ends_when_nothing_is_left() -> None:
    planner = planner_with([(4, 3), (6, 9)], room())
    planner.team.last_heard[1] = -5  # robot 1 not heard for longer than silence_rounds
    assert list(planner.plan(0, now=0.0)) == [0]
    closed = room()
    closed[2, 2:5] = CellState.OCCUPIED
    closed[2:10, 11] = CellState.OCCUPIED  # both openings walled: no frontier left
    done = planner_with([(4, 3)], closed)
    assert done.plan(0, now=0.0) == {} and done.done_reason == "no_frontiers"


def test_the_oracle_needs_the_truth() -> None:
    with pytest.raises(MrExploreError, match="the oracle needs the ground truth, which a real team lacks"):
        TeamPlanner(1, SHAPE, 0.1, make_strategy("oracle"))
