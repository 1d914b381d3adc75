"""Tiny ASCII maps shared by the tests: '#' obstacle/occupied, '.' free, '?' unknown."""

from __future__ import annotations

import heapq
import math
from pathlib import Path

import numpy as np
import pytest

from mrexplore.maps.frame import GridFrame
from mrexplore.maps.ground_truth import GroundTruthMap
from mrexplore.runtime.example_maps import maps_dir
from mrexplore.types import CellState

SHARED_MAPS = maps_dir().resolve()
"""The example maps: ``$MREXPLORE_MAPS``, else ../shared/maps from the repository root (where pytest runs)."""

_STATE = {".": CellState.FREE, "#": CellState.OCCUPIED, "?": CellState.UNKNOWN}


def ascii_rows(text: str) -> list[str]:
    return [line.strip() for line in text.strip().splitlines()]


def state_grid(text: str) -> np.ndarray:
    """``(H, W) uint8`` CellState grid from ASCII art."""
    return np.array([[_STATE[ch] for ch in row] for row in ascii_rows(text)], dtype=np.uint8)


NARROW_GAP = """
    ..........#.........
    ..........#.........
    ..........#.........
    ....................
    ..........#.........
    ..........#.........
"""
"""Walls (``#``) with a one-cell gap: every 3 x 3 block round the gap holds a wall cell, so a coarse grid
pooled by 3 cannot cross it."""


def bool_grid(text: str, true: str = "#") -> np.ndarray:
    """``(H, W) bool`` grid: True where the character is ``true``."""
    return np.array([[ch == true for ch in row] for row in ascii_rows(text)], dtype=bool)


def cells(text: str, mark: str = "x") -> list[list[int]]:
    """Row-major ``[[r, c], ...]`` of the cells holding ``mark``."""
    return [[r, c] for r, row in enumerate(ascii_rows(text)) for c, ch in enumerate(row) if ch == mark]


def truth_map(text: str, resolution_m: float = 0.05, name: str = "ascii") -> GroundTruthMap:
    occ = bool_grid(text)
    return GroundTruthMap(occ, GridFrame(occ.shape[0], occ.shape[1], resolution_m), name)


def posed_mission(map_spec: str, strategy: str, decisions: int, seed: int):
    """A 3-robot mission at 0.1 m on ``map_spec`` after ``decisions`` decisions of ``strategy``, its next one
    posed (:meth:`~mrexplore.mission.Mission.pose`); returns the mission and the posed problem."""
    from mrexplore.config import MapConfig, SimConfig
    from mrexplore.maps.loaders import load_map
    from mrexplore.mission import Mission, MissionSpec
    from mrexplore.pipeline import make_strategy

    truth = load_map(map_spec, MapConfig(resolution_m=0.1))
    m = Mission(MissionSpec(truth, make_strategy(strategy), SimConfig(robots=3), seed=seed), progress=False)
    for _ in range(decisions):
        assert m.advance()
        m.decide()
    assert m.advance()
    problem = m.pose()
    assert problem is not None
    return m, problem


def _rclpy_problem() -> str | None:
    from mrexplore.ros2.loopback import rclpy_problem

    return rclpy_problem()


_RCLPY = _rclpy_problem()
requires_rclpy = pytest.mark.skipif(_RCLPY is not None, reason=f"{_RCLPY} (CI installs rclpy)")
"""Marks a test that needs ROS 2's rclpy (the ros2 extra)."""


def require_shared_maps() -> Path:
    if not SHARED_MAPS.is_dir():
        pytest.skip(f"example maps not found at {SHARED_MAPS}; real-map tests need them (set MREXPLORE_MAPS)")
    return SHARED_MAPS


def seeded_dijkstra(passable: np.ndarray, seeds: list[tuple[int, int, float]]) -> np.ndarray:
    """Plain heapq Dijkstra from many cells, each with its starting distance; the kernels' moves:
    8-connected, a diagonal only where both cells it passes between are free."""
    H, W = passable.shape
    dist = np.full((H, W), np.inf)
    heap = []
    for r, c, k in seeds:
        if passable[r, c] and k < dist[r, c]:
            dist[r, c] = k
            heap.append((k, (r, c)))
    heapq.heapify(heap)
    while heap:
        d, (r, c) = heapq.heappop(heap)
        if d > dist[r, c]:
            continue
        for dr in (-1, 0, 1):
            for dc in (-1, 0, 1):
                rr, cc = r + dr, c + dc
                if (dr, dc) == (0, 0) or not (0 <= rr < H and 0 <= cc < W) or not passable[rr, cc]:
                    continue
                if dr and dc and not (passable[r, cc] and passable[rr, c]):
                    continue
                nd = d + (math.sqrt(2) if dr and dc else 1.0)
                if nd < dist[rr, cc]:
                    dist[rr, cc] = nd
                    heapq.heappush(heap, (nd, (rr, cc)))
    return dist


_SLOW_LIST = Path(__file__).with_name("slow_tests.txt")


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """Mark slow the test functions tests/slow_tests.txt names (measured over about 0.8 s each), so that
    ``pytest -m "not slow"`` stays a quick subset."""
    slow = {line.strip() for line in _SLOW_LIST.read_text().splitlines() if line.strip() and not line.startswith("#")}
    root = Path(config.rootpath)
    for item in items:
        path = Path(str(item.path)).resolve()
        rel = path.relative_to(root).as_posix() if path.is_relative_to(root) else path.as_posix()
        if f"{rel}::{getattr(item, 'originalname', item.name)}" in slow:
            item.add_marker(pytest.mark.slow)
