"""A robot's occupancy grid as ROS publishes it (nav_msgs/OccupancyGrid: -1 unknown, 0-100 occupied %),
checked and read into the team's grid: the robot's map frame placed in the team frame by a known offset
(the paper's known initial relative poses), each team cell taking the state of the robot's cell under its
centre, and every team cell that a robot's occupied cell falls in occupied, so that a map finer than the
team grid (slam_toolbox's 0.05 m under a 0.1 m team grid) keeps every wall, at any offset and rotation.
Plain data in, plain data out: no ROS here (the ROS 2 adapter fills :class:`OccupancyGridData`).

Examples
--------
>>> msg = OccupancyGridData(width=3, height=2, resolution_m=1.0, origin_xyyaw=(0.0, 0.0, 0.0),
...                         data=(0, 0, 100, -1, 0, 0))
>>> from mrexplore.config import GridThresholds
>>> team = GridFrame(height=2, width=3, resolution_m=1.0)
>>> state_in_team_frame(msg, FrameOffset(), team, GridThresholds()).tolist()  # row 0 is the top (y = 1)
[[2, 0, 0], [0, 0, 1]]
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TypeVar

import numpy as np
from numpy.typing import NDArray

from mrexplore.config import GridThresholds
from mrexplore.maps.frame import GridFrame
from mrexplore.types import CellState, MrExploreError, StateGrid

__all__ = [
    "OccupancyGridData",
    "FrameOffset",
    "checked_values",
    "state_in_team_frame",
    "occupancy_values",
    "grid_in_robot_frame",
    "yaw_of",
    "OCCUPANCY_VALUES",
]

OCCUPANCY_VALUES = np.array([0, 100, -1], dtype=np.int8)
"""An OccupancyGrid's value of each cell state, indexed by :class:`CellState` (free, occupied, unknown)."""
Coordinate = TypeVar("Coordinate", float, NDArray[np.floating])
"""A coordinate in metres: a number, or an array of them."""


@dataclass(frozen=True)
class OccupancyGridData:
    """The fields of a nav_msgs/OccupancyGrid that place and fill it."""

    width: int
    """Cells along x."""
    height: int
    """Cells along y."""
    resolution_m: float
    """Cell size, metres."""
    origin_xyyaw: tuple[float, float, float]
    """Pose of the corner of cell (0, 0) in the robot's map frame: x, y in metres, yaw in radians."""
    data: Sequence[int] | NDArray[np.integer]
    """``width * height`` values, row-major from cell (0, 0) (rows along +y): -1 unknown, 0-100 occupied %."""


@dataclass(frozen=True)
class FrameOffset:
    """Where a robot's map frame lies in the team frame: its origin at ``(x_m, y_m)``, turned by ``yaw_rad``
    (all zero: the robots share one frame, a merged map)."""

    x_m: float = 0.0
    y_m: float = 0.0
    yaw_rad: float = 0.0

    def to_team(self, x: Coordinate, y: Coordinate) -> tuple[Coordinate, Coordinate]:
        """Points (numbers or arrays) of the robot's map frame in the team frame.

        Examples
        --------
        >>> tuple(round(v, 6) for v in FrameOffset(1.0, 0.0, math.pi / 2).to_team(2.0, 0.0))
        (1.0, 2.0)
        """
        x_t, y_t = _rotate(x, y, self.yaw_rad)
        return x_t + self.x_m, y_t + self.y_m

    def to_robot(self, x: Coordinate, y: Coordinate) -> tuple[Coordinate, Coordinate]:
        """Points of the team frame in the robot's map frame (the inverse of :meth:`to_team`)."""
        return _rotate(x - self.x_m, y - self.y_m, -self.yaw_rad)


def checked_values(msg: OccupancyGridData, thresholds: GridThresholds) -> NDArray[np.int8]:
    """``(height, width) int8`` the message's values, rows along +y; a malformed message raises one
    :class:`MrExploreError` line naming what is wrong.

    Examples
    --------
    >>> from mrexplore.config import GridThresholds
    >>> bad = OccupancyGridData(2, 2, float("nan"), (0.0, 0.0, 0.0), (0, 0, 0, 0))
    >>> try:
    ...     checked_values(bad, GridThresholds())
    ... except MrExploreError as exc:
    ...     print(exc)
    occupancy grid resolution must be a finite number > 0 metres, got nan
    """
    w, h, res = msg.width, msg.height, msg.resolution_m
    if not (isinstance(res, float | int) and math.isfinite(res) and res > 0):
        raise MrExploreError(f"occupancy grid resolution must be a finite number > 0 metres, got {res!r}")
    if not all(isinstance(v, float | int) and math.isfinite(v) for v in msg.origin_xyyaw):
        raise MrExploreError(f"occupancy grid origin must be finite x, y and yaw, got {msg.origin_xyyaw!r}")
    if w < 1 or h < 1 or w * h > thresholds.max_cells:
        raise MrExploreError(
            f"occupancy grid of {w} x {h} cells is empty or larger than {thresholds.max_cells:,} cells; "
            "publish a map of the area explored"
        )
    values = np.asarray(msg.data)
    if values.ndim != 1 or len(values) != w * h:
        raise MrExploreError(f"occupancy grid data holds {values.size} values for {w} x {h} = {w * h} cells")
    if len(values) and (int(values.min()) < -1 or int(values.max()) > 100):
        raise MrExploreError(
            f"occupancy grid values must be -1 (unknown) or 0-100, got {int(values.min())} to {int(values.max())}"
        )
    return values.astype(np.int8).reshape(h, w)


def state_in_team_frame(
    msg: OccupancyGridData, offset: FrameOffset, team: GridFrame, thresholds: GridThresholds
) -> StateGrid:
    """``(team.height, team.width) uint8`` the robot's grid in the team's grid: each team cell takes the
    state of the robot's cell under its centre (unknown where none is), and is occupied wherever one of the
    robot's occupied cells falls in it (:func:`_walls_in_team_cells`): a one-cell wall of a finer map would
    otherwise be kept on some team cells and lost on others, as the team cells' centres fall on it or
    beside it. A team cell is free only where the robot's cell under its centre says so.

    Cells of equal size and aligned frames map one to one (the wall rule adds nothing there).
    """
    values = checked_values(msg, thresholds)
    states = np.full(values.shape, CellState.UNKNOWN, dtype=np.uint8)
    states[(values >= 0) & (values <= thresholds.free_max)] = CellState.FREE
    states[values >= thresholds.occupied_min] = CellState.OCCUPIED
    out = np.full((team.height, team.width), CellState.UNKNOWN, dtype=np.uint8)
    # The robot grid's cell (i along y, j along x) of each team cell's centre: team frame -> robot map frame
    # (undo the offset) -> grid frame (undo the grid origin's pose).
    ox, oy, oyaw = msg.origin_xyyaw
    rows, cols = _team_cells_near(msg, offset, team)
    if len(rows) == 0:
        return out
    x_t = team.origin_xy[0] + (cols + 0.5) * team.resolution_m
    y_t = team.origin_xy[1] + (team.height - 1 - rows + 0.5) * team.resolution_m
    x_m, y_m = offset.to_robot(x_t, y_t)
    x_g, y_g = _rotate(x_m - ox, y_m - oy, -oyaw)
    j = np.floor(x_g / msg.resolution_m).astype(np.int64)
    i = np.floor(y_g / msg.resolution_m).astype(np.int64)
    inside = (i >= 0) & (i < msg.height) & (j >= 0) & (j < msg.width)
    out[rows[inside], cols[inside]] = states[i[inside], j[inside]]
    wall_r, wall_c = _walls_in_team_cells(states == CellState.OCCUPIED, msg, offset, team)
    out[wall_r, wall_c] = CellState.OCCUPIED
    return out


_INSET = 0.25
"""Where a robot's occupied cell is sampled, in its own cells from its centre: the centre and four points a
quarter cell in along the diagonals. Inside the cell, so that a cell of an aligned grid of equal size lands in
its own team cell alone; spread, so that each of a finer cell's quarters reaches the team cell it lies in."""


def _walls_in_team_cells(
    occupied: NDArray[np.bool_], msg: OccupancyGridData, offset: FrameOffset, team: GridFrame
) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    """Rows and columns of the team cells that the robot's occupied cells fall in (each sampled at its centre
    and at four points inset from its corners), placed as :func:`state_in_team_frame` places the grid."""
    i, j = np.nonzero(occupied)
    if len(i) == 0:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    ox, oy, oyaw = msg.origin_xyyaw
    d = np.array([[0.0, 0.0], [-_INSET, -_INSET], [-_INSET, _INSET], [_INSET, -_INSET], [_INSET, _INSET]])
    x_g = ((j[:, None] + 0.5 + d[None, :, 0]) * msg.resolution_m).ravel()
    y_g = ((i[:, None] + 0.5 + d[None, :, 1]) * msg.resolution_m).ravel()
    x_r, y_r = _rotate(x_g, y_g, oyaw)
    x_t, y_t = offset.to_team(x_r + ox, y_r + oy)
    col = np.floor((x_t - team.origin_xy[0]) / team.resolution_m).astype(np.int64)
    row = team.height - 1 - np.floor((y_t - team.origin_xy[1]) / team.resolution_m).astype(np.int64)
    inside = (row >= 0) & (row < team.height) & (col >= 0) & (col < team.width)
    return row[inside], col[inside]


def _rotate(x: Coordinate, y: Coordinate, yaw: float) -> tuple[Coordinate, Coordinate]:
    """Points turned by ``yaw`` radians about the origin."""
    c, s = math.cos(yaw), math.sin(yaw)
    return c * x - s * y, s * x + c * y


def _team_cells_near(
    msg: OccupancyGridData, offset: FrameOffset, team: GridFrame
) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    """Row and column indices of the team cells inside the bounding box of the robot's grid placed in the
    team frame (only they can take a state from it)."""
    ox, oy, oyaw = msg.origin_xyyaw
    w_m, h_m = msg.width * msg.resolution_m, msg.height * msg.resolution_m
    corners = np.array([[0.0, 0.0], [w_m, 0.0], [0.0, h_m], [w_m, h_m]])
    x_m, y_m = _rotate(corners[:, 0], corners[:, 1], oyaw)
    x_t, y_t = offset.to_team(x_m + ox, y_m + oy)
    res = team.resolution_m
    c0 = max(0, math.floor((x_t.min() - team.origin_xy[0]) / res))
    c1 = min(team.width, math.ceil((x_t.max() - team.origin_xy[0]) / res))
    r0 = max(0, team.height - math.ceil((y_t.max() - team.origin_xy[1]) / res))
    r1 = min(team.height, team.height - math.floor((y_t.min() - team.origin_xy[1]) / res))
    if c1 <= c0 or r1 <= r0:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    rr, cc = np.mgrid[r0:r1, c0:c1]
    return rr.ravel().astype(np.int64), cc.ravel().astype(np.int64)


def occupancy_values(state: StateGrid) -> NDArray[np.int8]:
    """``(H * W,) int8`` a grid's cells as an OccupancyGrid's data: 0 free, 100 occupied, -1 unknown, row-major
    from the bottom row (rows along +y), the inverse of :func:`state_in_team_frame` on the same grid.

    Examples
    --------
    >>> occupancy_values(np.array([[2, 0], [0, 1]], np.uint8)).tolist()
    [0, 100, -1, 0]
    """
    return OCCUPANCY_VALUES[state[::-1]].ravel()


def grid_in_robot_frame(
    state: StateGrid, team: GridFrame, offset: FrameOffset, resolution_m: float
) -> OccupancyGridData:
    """A team-frame grid as a SLAM node would publish it in a robot's own map frame (axis-aligned there,
    ``resolution_m`` cells covering the whole team grid): each cell takes the state of the team cell under its
    centre. What a simulated robot's SLAM publishes; :func:`state_in_team_frame` reads it back.

    Examples
    --------
    >>> team = GridFrame(height=1, width=2, resolution_m=1.0)
    >>> g = grid_in_robot_frame(np.array([[0, 1]], np.uint8), team, FrameOffset(), 0.5)
    >>> (g.width, g.height, g.origin_xyyaw), [int(v) for v in g.data]  # each team cell: 2 x 2 of 0.5 m
    ((4, 2, (0.0, 0.0, 0.0)), [0, 0, 100, 100, 0, 0, 100, 100])
    """
    x0, y0 = team.origin_xy
    x1, y1 = x0 + team.width * team.resolution_m, y0 + team.height * team.resolution_m
    cx, cy = offset.to_robot(np.array([x0, x1, x0, x1]), np.array([y0, y0, y1, y1]))
    lo_x, lo_y = float(cx.min()), float(cy.min())
    nx = max(1, math.ceil(round((float(cx.max()) - lo_x) / resolution_m, 6)))
    ny = max(1, math.ceil(round((float(cy.max()) - lo_y) / resolution_m, 6)))
    xs = lo_x + (np.arange(nx) + 0.5) * resolution_m
    ys = lo_y + (np.arange(ny) + 0.5) * resolution_m
    gx, gy = offset.to_team(*np.meshgrid(xs, ys))  # (ny, nx), rows along +y
    c = np.floor((gx - x0) / team.resolution_m).astype(np.int64)
    r = team.height - 1 - np.floor((gy - y0) / team.resolution_m).astype(np.int64)
    inside = (r >= 0) & (r < team.height) & (c >= 0) & (c < team.width)
    values = np.full((ny, nx), -1, dtype=np.int8)
    values[inside] = OCCUPANCY_VALUES[state[r[inside], c[inside]]]
    return OccupancyGridData(nx, ny, resolution_m, (lo_x, lo_y, 0.0), values.ravel())


def yaw_of(qx: float, qy: float, qz: float, qw: float) -> float:
    """The heading (rotation about z, radians) of a quaternion.

    Examples
    --------
    >>> round(yaw_of(0.0, 0.0, math.sin(math.pi / 4), math.cos(math.pi / 4)), 6)
    1.570796
    """
    return math.atan2(2.0 * (qw * qz + qx * qy), 1.0 - 2.0 * (qy * qy + qz * qz))
