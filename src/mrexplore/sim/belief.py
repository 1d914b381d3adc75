"""Per-robot log-odds occupancy belief, its three-state view, and the team merge of several beliefs."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from mrexplore.config import SensorConfig
from mrexplore.types import BoolGrid, CellState, StateGrid

__all__ = ["Belief", "logit", "classify", "merge_beliefs"]


def logit(p: float) -> float:
    """Log-odds of probability ``p``."""
    return math.log(p / (1.0 - p))


@dataclass
class Belief:
    """One robot's occupancy grid.

    Attributes
    ----------
    log_odds:
        ``(H, W) float32`` log-odds of occupancy (paper eq. 1 in additive form); 0 is the 0.5 prior.
    observed:
        ``(H, W) bool``; True once any beam touched the cell. Knowledge never reverts to unknown, even
        when contradicting readings bring the log-odds back to 0.
    """

    log_odds: np.ndarray
    observed: BoolGrid

    @classmethod
    def empty(cls, shape: tuple[int, int]) -> Belief:
        return cls(np.zeros(shape, dtype=np.float32), np.zeros(shape, dtype=bool))

    def state(self, sensor: SensorConfig) -> StateGrid:
        """Three-state view, ``(H, W) uint8`` of :class:`CellState`."""
        return classify(self.log_odds, self.observed, sensor)


def classify(log_odds: np.ndarray, observed: BoolGrid, sensor: SensorConfig) -> StateGrid:
    """UNKNOWN where never observed, OCCUPIED above ``sensor.p_occupied``, FREE otherwise.

    Examples
    --------
    >>> lo = np.array([[0.0, 0.9, -0.4]], np.float32); ob = np.array([[False, True, True]])
    >>> classify(lo, ob, SensorConfig()).tolist()
    [[2, 1, 0]]
    """
    out = np.full(log_odds.shape, CellState.UNKNOWN, dtype=np.uint8)
    occ = log_odds > logit(sensor.p_occupied)
    out[observed & occ] = CellState.OCCUPIED
    out[observed & ~occ] = CellState.FREE
    return out


def merge_beliefs(beliefs: Sequence[Belief]) -> Belief:
    """Fuse robots' beliefs as independent evidence: log-odds add, observed cells unite."""
    log_odds = np.zeros_like(beliefs[0].log_odds)
    for b in beliefs:
        log_odds += b.log_odds
    observed = np.logical_or.reduce([b.observed for b in beliefs])
    return Belief(log_odds, observed)
