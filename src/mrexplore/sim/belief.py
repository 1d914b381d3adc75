"""Per-robot log-odds occupancy belief, its three-state view, and the team merge of several beliefs."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from mrexplore.config import SensorConfig
from mrexplore.maps.boxes import Box, box_union, grown_slices
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
    box: Box | None = None
    """``(r0, r1, c0, c1)`` half-open rows and columns holding every observed cell; None: none observed."""
    windows: NDArray[np.int32] = field(default_factory=lambda: np.zeros((0, 4), dtype=np.int32))
    """``(n_scans, 4) int32`` the window of every noted scan, in order (a reader that keeps a copy of the
    grid updates it where the scans since its last look fell: :meth:`changed_since`)."""
    revision: int = 0
    """Scans noted so far (the rows of :attr:`windows` in use)."""

    @classmethod
    def empty(cls, shape: tuple[int, int]) -> Belief:
        return cls(np.zeros(shape, dtype=np.float32), np.zeros(shape, dtype=bool))

    def state(self, sensor: SensorConfig) -> StateGrid:
        """Three-state view, ``(H, W) uint8`` of :class:`CellState`."""
        return classify(self.log_odds, self.observed, sensor)

    def note_window(self, window: Box) -> None:
        """Record that a scan changed cells in ``window`` ``(r0, r1, c0, c1)`` only: grows :attr:`box` and
        appends to :attr:`windows`. Whoever writes :attr:`log_odds` or :attr:`observed` must note it."""
        r0, r1, c0, c1 = window
        if self.revision == len(self.windows):  # amortised growth: a mission notes a scan per step
            grown = np.zeros((max(16, 2 * len(self.windows)), 4), dtype=np.int32)
            grown[: self.revision] = self.windows
            self.windows = grown
        self.windows[self.revision] = window
        self.revision += 1
        self.box = box_union(self.box, (r0, r1, c0, c1))

    def changed_since(self, revision: int) -> Box | None:
        """The box of the scans noted after ``revision`` (a value of :attr:`revision`); None: none since.

        Examples
        --------
        >>> b = Belief.empty((10, 10)); b.note_window((4, 6, 2, 3)); seen = b.revision
        >>> b.note_window((1, 2, 5, 9)); b.note_window((3, 4, 4, 5))
        >>> b.changed_since(seen), b.changed_since(b.revision)
        ((1, 4, 4, 9), None)
        """
        if revision >= self.revision:
            return None
        w = self.windows[revision : self.revision]
        return int(w[:, 0].min()), int(w[:, 1].max()), int(w[:, 2].min()), int(w[:, 3].max())

    def window(self, margin: int) -> tuple[slice, slice]:
        """:attr:`box` grown by ``margin`` cells and clipped to the grid (the whole grid when unknown).

        Examples
        --------
        >>> b = Belief.empty((10, 10)); b.note_window((4, 6, 2, 3))
        >>> b.window(2)
        (slice(2, 8, None), slice(0, 5, None))
        """
        H, W = self.observed.shape
        return grown_slices(self.box if self.box is not None else (0, H, 0, W), margin, (H, W))


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
