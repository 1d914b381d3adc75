"""The motion model on the grid: 8 neighbours, straight moves cost 1, diagonal sqrt(2), no corner cutting."""

from __future__ import annotations

import math

import numba as nb
import numpy as np

__all__ = ["DR", "DC", "move_cost"]

DR = np.array([-1, 1, 0, 0, -1, -1, 1, 1], dtype=np.int64)
"""Row offset of the 8 moves; moves 0-3 are straight, 4-7 diagonal."""
DC = np.array([0, 0, -1, 1, -1, 1, -1, 1], dtype=np.int64)
"""Column offset of the 8 moves."""


@nb.njit(cache=True, inline="always")
def move_cost(passable: np.ndarray, r: int, c: int, d: int) -> float:  # pragma: no cover - numba
    """Cost of move ``d`` from ``(r, c)``: 1 or sqrt(2); -1 when it leaves the grid, ends on a blocked cell
    or passes between two cells of which one is blocked (cutting a wall's corner)."""
    H, W = passable.shape
    rr = r + DR[d]
    cc = c + DC[d]
    if rr < 0 or rr >= H or cc < 0 or cc >= W or not passable[rr, cc]:
        return -1.0
    if d < 4:
        return 1.0
    if not passable[r, cc] or not passable[rr, c]:
        return -1.0
    return math.sqrt(2.0)
