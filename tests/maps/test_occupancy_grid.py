"""A robot's occupancy grid (ROS values) read into the team's grid: thresholds, placement by a frame offset,
and each malformed message refused in one line."""

from __future__ import annotations

import math

import numpy as np
import pytest

from mrexplore.config import GridThresholds
from mrexplore.maps.frame import GridFrame
from mrexplore.maps.occupancy_grid import (
    FrameOffset,
    OccupancyGridData,
    checked_values,
    grid_in_robot_frame,
    state_in_team_frame,
)
from mrexplore.types import MrExploreError

F, X, U = 0, 1, 2  # CellState: free, occupied (X), unknown
TH = GridThresholds()


def _msg(rows_up: list[list[int]], res: float = 1.0, origin=(0.0, 0.0, 0.0)) -> OccupancyGridData:
    """A message from its rows, the first row at the origin (y = 0), as ROS orders them."""
    return OccupancyGridData(len(rows_up[0]), len(rows_up), res, origin, [v for row in rows_up for v in row])


def test_values_become_states_by_the_map_server_thresholds() -> None:
    msg = _msg([[-1, 0, 19, 20, 64, 65, 100]])
    team = GridFrame(height=1, width=7, resolution_m=1.0)
    assert state_in_team_frame(msg, FrameOffset(), team, TH).tolist() == [[U, F, F, U, U, X, X]]


def test_the_first_row_of_the_message_is_the_bottom_row_of_the_grid() -> None:
    msg = _msg([[0, 0, 100], [-1, 0, 0]])
    team = GridFrame(height=2, width=3, resolution_m=1.0)
    assert state_in_team_frame(msg, FrameOffset(), team, TH).tolist() == [[U, F, F], [F, F, X]]


def test_an_offset_moves_the_robot_map_in_the_team_frame() -> None:
    msg = _msg([[0, 100]])  # free at x in [0, 1), occupied at x in [1, 2)
    team = GridFrame(height=2, width=4, resolution_m=1.0)
    moved = state_in_team_frame(msg, FrameOffset(x_m=2.0, y_m=1.0), team, TH)
    assert moved.tolist() == [[U, U, F, X], [U, U, U, U]]
    # turned a quarter left about the robot's origin: +x of the robot map is +y of the team
    turned = state_in_team_frame(msg, FrameOffset(x_m=1.0, yaw_rad=math.pi / 2), team, TH)
    assert turned.tolist() == [[X, U, U, U], [F, U, U, U]]


def test_the_grid_origin_pose_and_a_finer_team_grid_are_honoured() -> None:
    msg = _msg([[0, 100]], res=1.0, origin=(-1.0, 0.0, 0.0))  # free at x in [-1, 0), occupied in [0, 1)
    team = GridFrame(height=1, width=4, resolution_m=0.5, origin_xy=(-1.0, 0.0))
    assert state_in_team_frame(msg, FrameOffset(), team, TH).tolist() == [[F, F, X, X]]


def test_a_map_outside_the_team_grid_leaves_it_unknown() -> None:
    team = GridFrame(height=2, width=2, resolution_m=1.0)
    out = state_in_team_frame(_msg([[0]]), FrameOffset(x_m=10.0), team, TH)
    assert (out == U).all()


ZERO = (0.0, 0.0, 0.0)
RES = "occupancy grid resolution must be a finite number > 0 metres, got"
ORIGIN = "occupancy grid origin must be finite x, y and yaw, got"
SIZE = "cells is empty or larger than 60,000,000 cells; publish a map of the area explored"
BAD = [
    (OccupancyGridData(3, 2, 1.0, ZERO, [0] * 5), "occupancy grid data holds 5 values for 3 x 2 = 6 cells"),
    (OccupancyGridData(1, 1, float("nan"), ZERO, [0]), f"{RES} nan"),
    (OccupancyGridData(1, 1, float("inf"), ZERO, [0]), f"{RES} inf"),
    (OccupancyGridData(1, 1, 0.0, ZERO, [0]), f"{RES} 0.0"),
    (OccupancyGridData(100_000, 100_000, 0.05, ZERO, []), f"occupancy grid of 100000 x 100000 {SIZE}"),
    (OccupancyGridData(0, 4, 0.05, ZERO, []), f"occupancy grid of 0 x 4 {SIZE}"),
    (OccupancyGridData(1, 1, 1.0, (math.nan, 0.0, 0.0), [0]), f"{ORIGIN} (nan, 0.0, 0.0)"),
    (OccupancyGridData(2, 1, 1.0, ZERO, [0, 101]), "occupancy grid values must be -1 (unknown) or 0-100, got 0 to 101"),
]  # fmt: skip


@pytest.mark.parametrize(("msg", "message"), BAD)
def test_a_malformed_message_is_refused_in_one_line(msg: OccupancyGridData, message: str) -> None:
    with pytest.raises(MrExploreError) as err:
        checked_values(msg, TH)
    assert str(err.value) == message


def test_thresholds_must_leave_a_gap_between_free_and_occupied() -> None:
    with pytest.raises(MrExploreError, match=r"^occupied_min must be in \(free_max \(70\), 100\], got 65$"):
        GridThresholds(free_max=70, occupied_min=65)
    assert checked_values(_msg([[5, -1]]), TH).dtype == np.int8


@pytest.mark.parametrize("column", range(10))
def test_a_one_cell_wall_of_a_finer_map_is_kept_on_every_column(column: int) -> None:
    """slam_toolbox's 0.05 m map under a 0.1 m team grid: a wall one fine cell thick is kept whether it lies
    on the first or the second half of a team cell (sampling the team cells' centres kept it on odd fine
    columns and lost it on even ones)."""
    rows = [[0] * 20 for _ in range(8)]
    for r in rows:
        r[2 * column + column % 2] = 100
    team = GridFrame(height=4, width=10, resolution_m=0.1)
    got = state_in_team_frame(_msg(rows, res=0.05), FrameOffset(), team, TH)
    assert (got[:, column] == X).all()
    assert (np.delete(got, column, axis=1) == F).all()  # no other cell darkened


def _reaches_border(state: np.ndarray, start: tuple[int, int]) -> bool:
    """Whether a 4-connected walk over cells that are not occupied gets from ``start`` to the grid's border."""
    seen, todo = {start}, [start]
    h, w = state.shape
    while todo:
        r, c = todo.pop()
        if r in (0, h - 1) or c in (0, w - 1):
            return True
        for n in ((r + 1, c), (r - 1, c), (r, c + 1), (r, c - 1)):
            if n not in seen and state[n] != X:
                seen.add(n)
                todo.append(n)
    return False


@pytest.mark.parametrize("yaw", [0.0, 0.3, math.pi / 4, 1.1, math.pi])
@pytest.mark.parametrize("shift", [0.0, 0.013, 0.05, 0.077])
def test_a_closed_room_of_a_finer_map_stays_closed_at_any_offset_and_rotation(yaw: float, shift: float) -> None:
    """A room 1.5 m square with walls one 0.05 m cell thick, the robot's frame turned and moved in the team
    frame: on the 0.1 m team grid the room stays closed (no 4-connected way out of it over cells not
    occupied), and its inside stays free."""
    n = 30
    rows = [[-1] * (n + 4) for _ in range(n + 4)]
    for i in range(2, n + 2):
        for j in range(2, n + 2):
            rows[i][j] = 100 if i in (2, n + 1) or j in (2, n + 1) else 0
    msg = _msg(rows, res=0.05, origin=(-0.85, -0.85, 0.0))  # the room's centre at the robot frame's origin
    team = GridFrame(height=40, width=40, resolution_m=0.1, origin_xy=(-2.0, -2.0))
    got = state_in_team_frame(msg, FrameOffset(shift, -shift, yaw), team, TH)
    centre = team.xy_to_rc(FrameOffset(shift, -shift, yaw).to_team(0.0, 0.0))
    assert got[centre] == F
    assert not _reaches_border(got, centre)


def test_an_aligned_map_of_the_team_s_cell_size_maps_one_to_one() -> None:
    """Equal cells, aligned frames: the team grid is the robot's grid, walls not thickened."""
    rng = np.random.default_rng(3)
    values = rng.choice([-1, 0, 100], size=(12, 9)).tolist()
    team = GridFrame(height=12, width=9, resolution_m=0.1, origin_xy=(0.3, -0.2))
    got = state_in_team_frame(_msg(values, res=0.1, origin=(0.3, -0.2, 0.0)), FrameOffset(), team, TH)
    want = np.array([[{-1: U, 0: F, 100: X}[v] for v in row] for row in values[::-1]])
    assert (got == want).all()


@pytest.mark.parametrize("yaw", [0.0, math.pi / 2, math.pi, -math.pi / 2])
@pytest.mark.parametrize("fine", [0.05, 0.1])
def test_a_slam_map_published_in_a_robots_turned_frame_reads_back_to_the_same_team_grid(
    yaw: float, fine: float
) -> None:
    # The Nav2 double publishes each robot's map in its own frame (turned by a quarter turn, finer cells);
    # the robot node reads it back cell for cell, every one-cell wall kept.
    rng = np.random.default_rng(3)
    state = rng.choice(np.array([0, 1, 2], np.uint8), size=(9, 7))
    team = GridFrame(height=9, width=7, resolution_m=0.1, origin_xy=(-0.3, 0.2))
    offset = FrameOffset(0.4, -0.25, yaw)
    published = grid_in_robot_frame(state, team, offset, fine)
    assert np.array_equal(state_in_team_frame(published, offset, team, GridThresholds()), state)
