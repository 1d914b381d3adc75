"""Tiny ASCII maps shared by the tests: '#' obstacle/occupied, '.' free, '?' unknown."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from mrexplore.maps.frame import GridFrame
from mrexplore.maps.ground_truth import GroundTruthMap
from mrexplore.types import CellState

SHARED_MAPS = Path(__file__).resolve().parents[1].parent / "shared" / "maps"

_STATE = {".": CellState.FREE, "#": CellState.OCCUPIED, "?": CellState.UNKNOWN}


def ascii_rows(text: str) -> list[str]:
    return [line.strip() for line in text.strip().splitlines()]


def state_grid(text: str) -> np.ndarray:
    """``(H, W) uint8`` CellState grid from ASCII art."""
    return np.array([[_STATE[ch] for ch in row] for row in ascii_rows(text)], dtype=np.uint8)


def bool_grid(text: str, true: str = "#") -> np.ndarray:
    """``(H, W) bool`` grid: True where the character is ``true``."""
    return np.array([[ch == true for ch in row] for row in ascii_rows(text)], dtype=bool)


def cells(text: str, mark: str = "x") -> list[list[int]]:
    """Row-major ``[[r, c], ...]`` of the cells holding ``mark``."""
    return [[r, c] for r, row in enumerate(ascii_rows(text)) for c, ch in enumerate(row) if ch == mark]


def truth_map(text: str, resolution_m: float = 0.05, name: str = "ascii") -> GroundTruthMap:
    occ = bool_grid(text)
    return GroundTruthMap(occ, GridFrame(occ.shape[0], occ.shape[1], resolution_m), name)


def require_shared_maps() -> Path:
    if not SHARED_MAPS.is_dir():
        pytest.skip(f"shared maps not found at {SHARED_MAPS}; real-map tests need ../shared/maps beside the repo")
    return SHARED_MAPS
