"""What a map predictor is trained and scored on, on its own cells: the truth (free or not) and the band of
unknown cells near a frontier."""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from mrexplore.prediction.encoding import POOL_LEVELS
from mrexplore.prediction.quality import near_frontier
from mrexplore.types import StateGrid

__all__ = ["pool_share", "pooled_targets"]


def pool_share(mask: NDArray[np.bool_], factor: int) -> NDArray[np.float32]:
    """``(h, w) float32`` the share of True cells in each ``factor x factor`` block, the grid padded with False
    at its bottom and right to a multiple of ``factor * 2 ** POOL_LEVELS`` (as
    :func:`~mrexplore.prediction.encoding.belief_channels` pads).

    Examples
    --------
    >>> pool_share(np.array([[True, False], [True, True]]), 2).tolist()[0][:2]
    [0.75, 0.0]
    """
    H, W = mask.shape
    step = factor * 2**POOL_LEVELS
    Hp, Wp = math.ceil(H / step) * step, math.ceil(W / step) * step
    padded = np.zeros((Hp, Wp), bool)
    padded[:H, :W] = mask
    return padded.reshape(Hp // factor, factor, Wp // factor, factor).mean(axis=(1, 3), dtype=np.float32)


def pooled_targets(
    state: StateGrid, truth_free: NDArray[np.bool_], resolution_m: float, factor: int, band_m: float
) -> tuple[NDArray[np.bool_], NDArray[np.bool_]]:
    """The label and the loss mask on the predictor's cells, ``(h, w) bool`` each: a cell is free where most
    of its planning cells are, and counts where most of them are unknown cells within ``band_m`` of a
    frontier."""
    label = pool_share(truth_free, factor) >= 0.5
    mask = pool_share(near_frontier(state, resolution_m, band_m), factor) > 0.5
    return label, mask
