"""The link's two ends as plain objects: a robot fed its own map as states, and the centre's receiving end,
through the protocol's whole maps, deltas, acknowledgements and a restart."""

from __future__ import annotations

import numpy as np
import pytest

from mrexplore.config import PreprocessConfig, SensorConfig
from mrexplore.preprocessing.agents import RobotAgent, TeamCentre
from mrexplore.preprocessing.sparse_codec import peek
from mrexplore.preprocessing.sparse_map import SparseFrontierMap
from mrexplore.types import CellState, MrExploreError

SHAPE = (8, 10)
PP = PreprocessConfig(closing_size_cells=1)


def read(centre: TeamCentre, data: bytes) -> SparseFrontierMap:
    """The centre's reading of a message it can apply."""
    message = centre.read(data)
    assert message is not None
    return message


def _room(c1: int) -> np.ndarray:
    state = np.full(SHAPE, CellState.UNKNOWN, np.uint8)
    state[2:6, 1:c1] = CellState.FREE
    return state


def test_whole_map_then_deltas_then_a_restart_asks_for_the_whole_map_again() -> None:
    robot, centre = RobotAgent(0, SHAPE, PP, SensorConfig()), TeamCentre(1, SHAPE, 1, silence_rounds=3)
    robot.sense_state(_room(4))
    first = read(centre, robot.compose(0, (3, 2), robot.window()).incremental())
    assert not first.is_delta and centre.accepts(first)
    centre.receive(first, 0)
    robot.acknowledged(first)
    assert (centre.state() == CellState.FREE).sum() == 12  # the 4 x 3 room
    robot.sense_state(_room(7))  # the room seen further east
    second = read(centre, robot.compose(1, (3, 5), robot.window()).incremental())
    assert second.is_delta and second.base_round == 0 and centre.accepts(second)
    centre.receive(second, 1)
    robot.acknowledged(second)
    assert (centre.state() == CellState.FREE).sum() == 24 and centre.positions_rc.tolist() == [[3, 5]]
    centre.restart(2)  # the centre forgets: a delta has no base there any more
    robot.sense_state(_room(8))
    out = robot.compose(2, (3, 6), robot.window())
    assert peek(out.incremental()).is_delta and centre.read(out.incremental()) is None
    whole = centre.read(out.full_bytes())  # what the robot resends on the centre's request
    assert whole is not None and centre.accepts(whole)
    centre.receive(whole, 2)
    assert (centre.state() == CellState.FREE).sum() == 28


def test_a_robot_is_assignable_while_heard_within_the_silence_limit() -> None:
    robot, centre = RobotAgent(1, SHAPE, PP, SensorConfig()), TeamCentre(2, SHAPE, 1, silence_rounds=2)
    robot.sense_state(_room(4))
    centre.receive(read(centre, robot.compose(0, (3, 2), robot.window()).full_bytes()), 0)
    assert centre.status(0).heard.tolist() == [False, True]
    assert centre.status(0).assignable.tolist() == [False, True]  # robot 0: never heard, no known cell
    assert centre.status(1).assignable.tolist() == [False, True] and not centre.status(1).heard.any()
    assert centre.status(2).assignable.tolist() == [False, False]  # two rounds of silence


def test_the_window_holds_every_known_cell_with_the_closing_margin() -> None:
    robot = RobotAgent(0, SHAPE, PreprocessConfig(closing_size_cells=3), SensorConfig())
    assert robot.window() == (slice(0, 8), slice(0, 10))  # nothing known: the whole grid
    robot.sense_state(_room(4))
    # rows 2-5, cols 1-3, grown by the closing's reach (3 cells for a 3 x 3 closing) plus one, and clipped
    assert robot.window() == (slice(0, 8), slice(0, 8))


def test_what_the_robot_sensed_between_sending_and_the_acknowledgement_is_sent_next() -> None:
    """On ROS 2 a robot keeps sensing while its message travels: the room seen further east after round 1
    was composed (and before the centre acknowledged it) reaches the centre with round 2. Forgetting it at
    the acknowledgement left the centre's codes with a gap its fill leaked through (a real-time mission
    ended with the whole grid "known" at 91% coverage)."""
    robot, centre = RobotAgent(0, SHAPE, PP, SensorConfig()), TeamCentre(1, SHAPE, 1, silence_rounds=3)
    robot.sense_state(_room(4))
    first = read(centre, robot.compose(0, (3, 2), robot.window()).incremental())
    centre.receive(first, 0)
    robot.acknowledged(first)
    robot.sense_state(_room(6))
    second = read(centre, robot.compose(1, (3, 4), robot.window()).incremental())
    robot.sense_state(_room(8))  # seen while the second message is on its way
    centre.receive(second, 1)
    robot.acknowledged(second)
    assert (centre.state() == CellState.FREE).sum() == 20  # the 4 x 5 room of round 1
    third = read(centre, robot.compose(2, (3, 6), robot.window()).incremental())
    assert third.is_delta and centre.accepts(third)
    centre.receive(third, 2)
    assert (centre.state() == CellState.FREE).sum() == 28  # the 4 x 7 room, as the robot knows it
    assert np.array_equal(centre.state(), robot.grid.closed)


def test_a_whole_map_for_another_grid_is_refused_before_decoding() -> None:
    robot, centre = RobotAgent(0, (9, 10), PP, SensorConfig()), TeamCentre(1, SHAPE, 1, silence_rounds=3)
    state = np.full((9, 10), CellState.UNKNOWN, np.uint8)
    state[2:6, 1:4] = CellState.FREE
    robot.sense_state(state)
    with pytest.raises(MrExploreError) as err:
        centre.read(robot.compose(0, (3, 2), robot.window()).full_bytes())
    assert str(err.value) == (
        "message from robot 0 for a (9, 10) grid does not fit this centre (1 robots, grid (8, 10)); "
        "check the robot id and map"
    )
