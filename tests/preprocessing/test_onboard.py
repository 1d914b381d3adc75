"""A robot's on-board grid kept up to date where its scans fell equals the whole computation, and the
messages and byte counts built from it equal those built from the whole closed grid."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from pytest import MonkeyPatch

from mrexplore.config import SensorConfig
from mrexplore.preprocessing.frontiers import close_unknown_holes, closing_reach
from mrexplore.preprocessing.onboard import OnBoardGrid
from mrexplore.preprocessing.sparse_map import component_seeds, neighbour_codes
from mrexplore.preprocessing.transmission import RobotSender
from mrexplore.sim.belief import Belief, classify
from mrexplore.types import CellState

SENSOR = SensorConfig()


def _scan(belief: Belief, truth: np.ndarray, rng: np.random.Generator) -> None:
    """A scan-like change: a random box of the map observed, its log-odds nudged towards the truth (with
    some cells read wrong, so cells turn from free to occupied and back), noted as the world notes it."""
    H, W = truth.shape
    r0, c0 = int(rng.integers(0, H)), int(rng.integers(0, W))
    r1, c1 = min(H, r0 + int(rng.integers(1, 9))), min(W, c0 + int(rng.integers(1, 9)))
    box = (slice(r0, r1), slice(c0, c1))
    seen = rng.random((r1 - r0, c1 - c0)) < 0.8  # gaps between beams
    wrong = rng.random(seen.shape) < 0.1
    hit = truth[box] ^ wrong
    belief.log_odds[box] += np.where(seen, np.where(hit, 0.9, -0.4), 0.0).astype(np.float32)
    belief.observed[box] |= seen
    belief.note_window((r0, r1, c0, c1))


@settings(max_examples=60, deadline=None)
@given(st.integers(0, 10**6), st.sampled_from([1, 3, 5]))
def test_updated_where_the_scans_fell_equals_the_whole_grid(seed: int, size: int) -> None:
    rng = np.random.default_rng(seed)
    shape = (int(rng.integers(6, 40)), int(rng.integers(6, 40)))
    truth = rng.random(shape) < 0.25
    beliefs = [Belief.empty(shape) for _ in range(2)]
    grids = [OnBoardGrid(shape, size, SENSOR) for _ in beliefs]
    free_count = np.zeros(shape, dtype=np.uint16)
    for _ in range(6):
        for belief, grid in zip(beliefs, grids, strict=True):
            for _ in range(int(rng.integers(0, 3))):
                _scan(belief, truth, rng)
            before = grid.codes.copy(), grid.closed.copy()
            changed = grid.update(belief, free_count)
            state = classify(belief.log_odds, belief.observed, SENSOR)
            closed = close_unknown_holes(state, size)
            assert np.array_equal(grid.state, state)
            assert np.array_equal(grid.closed, closed)
            assert np.array_equal(grid.codes, neighbour_codes(closed))
            assert np.array_equal(grid.cells, np.flatnonzero(grid.codes.ravel()))
            assert grid.n_free == np.count_nonzero(closed == CellState.FREE)
            # Nothing changed outside the box it returns.
            outside = np.ones(shape, dtype=bool)
            if changed is not None:
                outside[changed[0] : changed[1], changed[2] : changed[3]] = False
            assert np.array_equal(before[0][outside], grid.codes[outside])
            assert np.array_equal(before[1][outside], grid.closed[outside])
        free = sum((g.state == CellState.FREE).astype(int) for g in grids)
        assert np.array_equal(free_count, free)


def test_another_belief_is_read_whole_and_forgets_the_last() -> None:
    shape = (8, 8)
    first, second = Belief.empty(shape), Belief.empty(shape)
    first.observed[0:3, 0:3] = True
    first.note_window((0, 3, 0, 3))
    second.observed[5:8, 5:8] = True
    second.note_window((5, 8, 5, 8))
    grid = OnBoardGrid(shape, 1, SENSOR)
    grid.update(first)
    assert grid.update(second) == (0, 8, 0, 8)
    assert np.array_equal(grid.state, classify(second.log_odds, second.observed, SENSOR))


@settings(max_examples=40, deadline=None)
@given(st.integers(0, 10**6))
def test_onboard_messages_equal_those_of_the_whole_closed_grid(seed: int) -> None:
    # Two senders of the same robot, one from its whole closed grid (send), one from the on-board grid
    # (send_onboard); acknowledgements lost at random, so deltas span several rounds of change.
    rng = np.random.default_rng(seed)
    shape = (int(rng.integers(8, 36)), int(rng.integers(8, 36)))
    truth = rng.random(shape) < 0.2
    size = 3
    belief = Belief.empty(shape)
    grid = OnBoardGrid(shape, size, SENSOR)
    whole, onboard = RobotSender(0, shape), RobotSender(0, shape)
    everywhere = (slice(0, shape[0]), slice(0, shape[1]))
    for rnd in range(8):
        for _ in range(int(rng.integers(0, 4))):
            _scan(belief, truth, rng)
        onboard.note_changed(grid.update(belief))
        if belief.box is None:
            continue
        window = belief.window(closing_reach(size) + 1)
        r0, r1, c0, c1 = belief.box  # the robot stands where it has scanned
        pos = (int(rng.integers(r0, r1)), int(rng.integers(c0, c1)))
        own = classify(belief.log_odds, belief.observed, SENSOR)
        expected = whole.outgoing(close_unknown_holes(own, size), rnd, pos)
        got = onboard.send_onboard(grid, rnd, pos, window)
        assert got.both() == expected.both()
        assert got.incremental_message() == expected.incremental_message()
        assert onboard.onboard_grid_delta_bytes(grid) == whole.grid_delta_bytes(own, everywhere)
        if rng.random() < 0.7:  # acknowledged
            whole.acknowledged(expected.incremental_message())
            onboard.acknowledged(got.incremental_message())


def test_state_version_moves_only_when_the_three_state_grid_changes() -> None:
    belief = Belief.empty((5, 5))
    grid = OnBoardGrid((5, 5), 1, SENSOR)
    belief.observed[1:3, 1:3] = True
    belief.note_window((1, 3, 1, 3))
    grid.update(belief)
    assert grid.state_version == 1
    belief.log_odds[1, 1] -= 0.4  # more sure it is free: the same state
    belief.note_window((1, 2, 1, 2))
    grid.update(belief)
    assert grid.state_version == 1
    belief.log_odds[1, 1] += 5.0  # now occupied
    belief.note_window((1, 2, 1, 2))
    grid.update(belief)
    assert grid.state_version == 2 and grid.state[1, 1] == CellState.OCCUPIED


@settings(max_examples=200, deadline=None)
@given(st.integers(1, 12), st.integers(1, 12), st.integers(0, 2**32 - 1), st.floats(0.0, 1.0))
def test_baseline_grid_bytes_are_the_known_box_as_ros_values(h: int, w: int, seed: int, known: float) -> None:
    """The baseline message's bytes: the box of known cells as int8 ROS values (-1, 0, 100), raw and zlib
    level 6, as numpy's mask, box and table lookup give them; a window of a larger grid (not contiguous)
    too, and a grid with nothing known gives the header alone."""
    import zlib

    from mrexplore.maps.boxes import mask_box
    from mrexplore.preprocessing.sparse_codec import BASELINE_HEADER_BYTES
    from mrexplore.preprocessing.transmission import occupancy_grid_bytes

    rng = np.random.default_rng(seed)
    grid = np.where(rng.random((h + 2, w + 2)) < known, rng.integers(0, 2, (h + 2, w + 2)), CellState.UNKNOWN)
    grid = grid.astype(np.uint8)
    window = grid[1:-1, 1:-1]
    box = mask_box(window != CellState.UNKNOWN)
    if box is None:
        expected = (BASELINE_HEADER_BYTES, BASELINE_HEADER_BYTES)
    else:
        ros = np.array([0, 100, -1], np.int8)[window[box[0] : box[1], box[2] : box[3]]].tobytes()
        expected = (BASELINE_HEADER_BYTES + len(ros), BASELINE_HEADER_BYTES + len(zlib.compress(ros, 6)))
    assert occupancy_grid_bytes(window) == expected


@settings(max_examples=100, deadline=None)
@given(st.integers(0, 10**6), st.sampled_from([1, 3]), st.floats(0.05, 0.4))
def test_seeds_kept_where_free_space_stays_one_piece_equal_the_whole_fill(
    seed: int, size: int, wall_share: float
) -> None:
    """A robot scanning a random map round by round, standing on a free cell most rounds: the seeds it
    finds from what changed since its last seeds equal the whole fill's, every round."""
    rng = np.random.default_rng(seed)
    shape = (int(rng.integers(6, 30)), int(rng.integers(6, 30)))
    truth = rng.random(shape) < wall_share
    belief = Belief.empty(shape)
    grid = OnBoardGrid(shape, size, SENSOR)
    window = (slice(0, shape[0]), slice(0, shape[1]))
    for _ in range(12):
        for _ in range(int(rng.integers(0, 3))):
            _scan(belief, truth, rng)
        grid.update(belief)
        free = np.argwhere(grid.closed == CellState.FREE)
        if len(free) and rng.random() < 0.9:
            pos = tuple(int(v) for v in free[rng.integers(len(free))])
        else:
            pos = (int(rng.integers(0, shape[0])), int(rng.integers(0, shape[1])))
        expected = component_seeds(grid.closed, grid.codes, pos, grid.n_free)
        assert grid.seeds(pos, window).tolist() == expected.tolist()


def test_a_room_seen_through_a_door_keeps_one_seed_and_a_shut_door_splits_them(monkeypatch: MonkeyPatch) -> None:
    # Walls everywhere but two 3 x 3 rooms and the door between them (2, 4). The robot sees its room and
    # the door, then the other room: its free space grows as one piece, so its seed stays its cell without
    # a whole fill. Then the door is seen shut: a free cell is lost, the whole fill runs, one seed a room.
    import mrexplore.preprocessing.onboard as onboard

    fills: list[int] = []
    whole = onboard.pick_seeds
    monkeypatch.setattr(onboard, "pick_seeds", lambda *a: fills.append(1) or whole(*a))
    wall = np.ones((5, 9), bool)
    wall[1:4, 1:4] = wall[1:4, 5:8] = wall[2, 4] = False
    belief = Belief.empty(wall.shape)
    belief.log_odds[:] = np.where(wall, 2.0, -2.0).astype(np.float32)

    def see(r0: int, r1: int, c0: int, c1: int) -> None:
        belief.observed[r0:r1, c0:c1] = True
        belief.note_window((r0, r1, c0, c1))
        grid.update(belief)

    grid = OnBoardGrid(wall.shape, 1, SENSOR)
    window = (slice(0, 5), slice(0, 9))
    see(0, 5, 0, 5)  # the robot's room and the door
    assert grid.seeds((2, 2), window).tolist() == [2 * 9 + 2] and len(fills) == 1
    see(0, 5, 5, 9)  # the other room, through the door
    assert grid.seeds((2, 2), window).tolist() == [2 * 9 + 2] and len(fills) == 1
    belief.log_odds[2, 4] = 2.0  # the door seen shut
    see(2, 3, 4, 5)
    expected = component_seeds(grid.closed, grid.codes, (2, 2), grid.n_free).tolist()
    assert expected == [2 * 9 + 2, 2 * 9 + 6]  # the other room's first interior cell
    assert grid.seeds((2, 2), window).tolist() == expected and len(fills) == 2


def test_pieces_kept_where_only_the_robots_piece_changes(monkeypatch: MonkeyPatch) -> None:
    # Walls everywhere but three 3 x 3 rooms: A (the robot's, columns 1-3), B (5-7) behind a door (2, 4),
    # and C (11-13), walled off by columns 8-10 until a way through them (row 2) is seen. Free space is in
    # pieces from the start (A and C), so seeds come from whole fills until the pieces are labelled; then
    # B, seen through the door, joins the robot's piece and no fill runs, nor when a cell of B is seen
    # occupied; the way joins C to B, and the whole fill runs again.
    import mrexplore.preprocessing.onboard as onboard

    fills: list[str] = []
    plain, labelled = onboard.pick_seeds, onboard.pick_seeds_labelled
    monkeypatch.setattr(onboard, "pick_seeds", lambda *a: fills.append("plain") or plain(*a))
    monkeypatch.setattr(onboard, "pick_seeds_labelled", lambda *a: fills.append("labelled") or labelled(*a))
    wall = np.ones((5, 15), bool)
    wall[1:4, 1:4] = wall[1:4, 5:8] = wall[1:4, 11:14] = wall[2, 4] = False
    belief = Belief.empty(wall.shape)
    belief.log_odds[:] = np.where(wall, 2.0, -2.0).astype(np.float32)
    grid = OnBoardGrid(wall.shape, 1, SENSOR)
    window = (slice(0, 5), slice(0, 15))

    def see(r0: int, r1: int, c0: int, c1: int) -> list[int]:
        belief.observed[r0:r1, c0:c1] = True
        belief.note_window((r0, r1, c0, c1))
        grid.update(belief)
        expected = component_seeds(grid.closed, grid.codes, (2, 2), grid.n_free).tolist()
        assert grid.seeds((2, 2), window).tolist() == expected
        return expected

    assert see(0, 5, 0, 4) + see(0, 5, 10, 15) == [2 * 15 + 2, 2 * 15 + 2, 2 * 15 + 12]  # A, then A and C
    assert see(0, 5, 0, 4) == [2 * 15 + 2, 2 * 15 + 12] and fills == ["plain", "plain", "labelled"]
    assert see(0, 5, 4, 9) == [2 * 15 + 2, 2 * 15 + 12]  # B joins A: C's seed is kept, no fill
    belief.log_odds[1, 5] = 2.0  # a corner of B seen occupied: the robot's piece loses a cell, stays whole
    assert see(1, 2, 5, 6) == [2 * 15 + 2, 2 * 15 + 12]
    assert fills == ["plain", "plain", "labelled"]
    belief.log_odds[2, 8:11] = -2.0  # a way from B to C, seen
    assert see(2, 3, 8, 11) == [2 * 15 + 2] and fills[-1] == "labelled"  # one piece again


@settings(max_examples=40, deadline=None)
@given(st.integers(0, 10**6), st.sampled_from([1, 3]))
def test_a_grid_fed_states_equals_one_fed_the_beliefs_they_come_from(seed: int, size: int) -> None:
    # A real robot's map arrives as states (its published occupancy grid), not as log-odds: the same states
    # give the same closing, codes, cells and message seeds as the beliefs they classify.
    rng = np.random.default_rng(seed)
    shape = (int(rng.integers(6, 30)), int(rng.integers(6, 30)))
    truth = rng.random(shape) < 0.25
    belief = Belief.empty(shape)
    by_belief, by_state = OnBoardGrid(shape, size, SENSOR), OnBoardGrid(shape, size, SENSOR)
    for _ in range(5):
        for _ in range(int(rng.integers(1, 3))):
            _scan(belief, truth, rng)
        by_belief.update(belief)
        changed = by_state.update_state(classify(belief.log_odds, belief.observed, SENSOR))
        for name in ("state", "closed", "codes", "cells"):
            assert np.array_equal(getattr(by_state, name), getattr(by_belief, name)), name
        assert by_state.n_free == by_belief.n_free
        robot = (shape[0] // 2, shape[1] // 2)
        window = (slice(0, shape[0]), slice(0, shape[1]))
        assert np.array_equal(by_state.seeds(robot, window), by_belief.seeds(robot, window))
        assert by_state.update_state(by_state.state.copy()) is None  # nothing new, nothing to redo
        assert changed is None or changed[0] < changed[1]


def test_a_state_grid_of_another_shape_is_refused() -> None:
    import pytest

    from mrexplore.types import MrExploreError

    with pytest.raises(MrExploreError, match=r"^the robot's grid must be \(4, 4\) cells, got \(4, 5\)$"):
        OnBoardGrid((4, 4), 1, SENSOR).update_state(np.zeros((4, 5), np.uint8))
