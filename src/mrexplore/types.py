"""Shared vocabulary: cell states, coordinate aliases and robot ids used by every layer."""

from __future__ import annotations

from enum import IntEnum

import numpy as np
from numpy.typing import NDArray

__all__ = ["CellState", "GridRC", "WorldXY", "RobotId", "StateGrid", "BoolGrid", "MrExploreError"]


class CellState(IntEnum):
    """State of one occupancy-grid cell, stored as ``uint8``."""

    FREE = 0
    OCCUPIED = 1
    UNKNOWN = 2


GridRC = tuple[int, int]
"""A grid index ``(row, col)``; row 0 is the top of the image (largest y)."""

WorldXY = tuple[float, float]
"""A point in the map frame, metres, ``(x, y)``; x grows with col, y shrinks with row."""

RobotId = int
"""Index of a robot in the team, ``0 .. n_robots - 1``."""

StateGrid = NDArray[np.uint8]
"""``(H, W) uint8`` grid of :class:`CellState` values."""

BoolGrid = NDArray[np.bool_]
"""``(H, W) bool`` mask."""


class MrExploreError(ValueError):
    """Bad input from a user: the message names the problem and the fix, in one line."""
