"""How well a prediction of the unseen matches the map: per-cell accuracy and the IoU of predicted free space,
on the unknown cells within a distance of a frontier (where a planner's next decisions look)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy import ndimage

from mrexplore.preprocessing.frontiers import detect_frontiers
from mrexplore.types import CellState, StateGrid

__all__ = ["near_frontier", "Score", "score"]


def near_frontier(state: StateGrid, resolution_m: float, radius_m: float) -> NDArray[np.bool_]:
    """``(H, W) bool`` unknown cells within ``radius_m`` (straight line) of an F_un cell.

    Examples
    --------
    >>> F, U = CellState.FREE, CellState.UNKNOWN
    >>> g = np.array([[F, U, U, U, U]], np.uint8)
    >>> near_frontier(g, 1.0, 2.0).astype(int).tolist()  # F_un at column 0: columns 1 and 2 lie within 2
    [[0, 1, 1, 0, 0]]
    """
    un = detect_frontiers(state).un_mask
    if not un.any():
        return np.zeros(state.shape, bool)
    dist = ndimage.distance_transform_edt(~un) * resolution_m
    return (dist <= radius_m + 1e-9) & (state == CellState.UNKNOWN)


@dataclass(frozen=True)
class Score:
    """Cells scored, the share classified right (free above 0.5), and the IoU of predicted and true free."""

    cells: int
    accuracy: float
    iou: float


def score(p_free: NDArray[np.floating], truth_free: NDArray[np.bool_], mask: NDArray[np.bool_]) -> Score:
    """``p_free`` against the truth on the cells of ``mask`` (NaN where the mask is empty).

    Examples
    --------
    >>> p = np.array([1.0, 0.9, 0.2, 0.1]); t = np.array([True, False, False, True]); m = np.ones(4, bool)
    >>> s = score(p, t, m); s.cells, s.accuracy, round(s.iou, 4)  # right on cells 0 and 2; free {0,1} vs {0,3}
    (4, 0.5, 0.3333)
    """
    pred, true = np.asarray(p_free)[mask] > 0.5, np.asarray(truth_free)[mask]
    n = int(mask.sum())
    if n == 0:
        return Score(0, float("nan"), float("nan"))
    union = int((pred | true).sum())
    iou = float((pred & true).sum() / union) if union else 1.0
    return Score(n, float((pred == true).mean()), iou)
