"""A robot's on-board copy of its grid, closed and coded, kept up to date where its scans fell.

Each round a robot sends the sparse frontier map of its closed grid. Recomputing the three-state view,
the closing and the neighbour codes over every cell it knows costs in proportion to what it has seen
(it grows as the floor is explored); a scan changes cells within the sensor's range only. So the
robot keeps the three grids over the whole map and redoes them only in the box of the scans since its
last round, grown by how far each step reads: the closing reads free cells up to
:func:`~mrexplore.preprocessing.frontiers.closing_reach` away, a code its four neighbours. The result is
cell for cell what the whole computation gives (tested against it).
"""

from __future__ import annotations

import numba as nb
import numpy as np
from numpy.typing import NDArray

from mrexplore.config import SensorConfig
from mrexplore.maps.boxes import Box, box_union, grown_slices, mask_box
from mrexplore.preprocessing.frontiers import close_unknown_holes, closing_reach
from mrexplore.preprocessing.scanline_fill import (
    joined_in_box,
    joined_to_label,
    kept_in_label,
    pick_seeds,
    pick_seeds_labelled,
)
from mrexplore.preprocessing.sparse_map import neighbour_codes
from mrexplore.sim.belief import Belief, classify
from mrexplore.types import CellState, GridRC, MrExploreError, StateGrid

__all__ = ["OnBoardGrid"]


class OnBoardGrid:
    """One robot's three-state grid, its closing and the closing's neighbour codes, all ``(H, W) uint8``.

    :meth:`update` brings them in line with the robot's :class:`~mrexplore.sim.belief.Belief`, working
    only where the belief noted scans since the last update; a belief it has not seen before (another
    object) is read whole.

    Examples
    --------
    >>> b = Belief.empty((6, 6)); b.observed[1:5, 1:5] = True; b.note_window((1, 5, 1, 5))
    >>> g = OnBoardGrid((6, 6), closing_size_cells=1, sensor=SensorConfig())
    >>> g.update(b)
    (0, 6, 0, 6)
    >>> int((g.state == CellState.FREE).sum()), int((g.codes > 0).sum())
    (16, 12)
    >>> g.update(b) is None  # no scan since
    True
    """

    def __init__(self, shape: tuple[int, int], closing_size_cells: int, sensor: SensorConfig) -> None:
        self.closing_size_cells = closing_size_cells
        self.sensor = sensor
        self.state: StateGrid = np.full(shape, CellState.UNKNOWN, dtype=np.uint8)
        self.closed: StateGrid = self.state.copy()
        self.codes: NDArray[np.uint8] = np.zeros(shape, dtype=np.uint8)
        self.cells: NDArray[np.int64] = np.zeros(0, dtype=np.int64)
        """``(n,) int64`` row-major indices of the cells with a code, increasing (a message lists them)."""
        self.n_free = 0
        """Free cells of :attr:`closed`."""
        self.state_version = 0
        """Counts the updates that changed :attr:`state` (whatever reads it whole may keep its result until
        this moves)."""
        self._belief: Belief | None = None
        self._revision = 0
        # Since the last seeds: was free space one component holding the robot, where did closed change,
        # and did a free cell stop being free (see :meth:`seeds`).
        self._one_piece = False
        self._seed_box: Box | None = None
        self._lost_free = False
        # Where free space is in pieces: each piece's label (the robot's is 1) since the first whole fill
        # that found several, and the other pieces' seeds as map cells, ``(k, 2)`` (None: not kept).
        self._labels: NDArray[np.int32] | None = None
        self._others: NDArray[np.int64] | None = None

    def update(self, belief: Belief, free_count: NDArray[np.uint16] | None = None) -> Box | None:
        """Bring the grids in line with ``belief``; returns the box where :attr:`closed` and :attr:`codes`
        may have changed (None: nowhere). ``free_count`` ``(H, W) uint16``, if given, counts per cell the
        robots whose :attr:`state` is free: this robot's changes are applied to it."""
        if belief is not self._belief:
            changed = belief.box
            if self._belief is not None and self._belief.box is not None:
                changed = box_union(changed, self._belief.box)  # cells the other belief knew are forgotten
        else:
            changed = belief.changed_since(self._revision)
        self._belief, self._revision = belief, belief.revision
        if changed is None:
            return None
        rows, cols = _slices(changed)
        own = classify(belief.log_odds[rows, cols], belief.observed[rows, cols], self.sensor)
        return self._apply(changed, own, free_count)

    def update_state(self, state: StateGrid) -> Box | None:
        """Bring the grids in line with a three-state grid of the robot's own (``(H, W) uint8``, e.g. its
        published occupancy grid read by :mod:`~mrexplore.maps.occupancy_grid`): as :meth:`update`, over
        the box of the cells that changed. A grid is fed one way: by beliefs (the simulator's robots) or by
        states (a real robot's map), not both.

        Examples
        --------
        >>> g = OnBoardGrid((4, 4), closing_size_cells=1, sensor=SensorConfig())
        >>> s = np.full((4, 4), CellState.UNKNOWN, np.uint8); s[1:3, 1:3] = CellState.FREE
        >>> g.update_state(s), g.update_state(s), g.n_free
        ((0, 4, 0, 4), None, 4)
        """
        if state.shape != self.state.shape:
            raise MrExploreError(f"the robot's grid must be {self.state.shape} cells, got {state.shape}")
        changed = mask_box(state != self.state)
        if changed is None:
            return None
        rows, cols = _slices(changed)
        return self._apply(changed, state[rows, cols].copy())

    def _apply(self, changed: Box, own: StateGrid, free_count: NDArray[np.uint16] | None = None) -> Box:
        """Set :attr:`state` to ``own`` in ``changed`` and redo the closing and the codes within their
        reach; the box where they may have changed."""
        shape = self.state.shape
        rows, cols = _slices(changed)
        if free_count is not None:
            was = self.state[rows, cols] == CellState.FREE
            now = own == CellState.FREE
            free_count[rows, cols] += now & ~was
            free_count[rows, cols] -= was & ~now
        if not np.array_equal(self.state[rows, cols], own):
            self.state_version += 1
        self.state[rows, cols] = own
        # A cell's closing reads free cells up to the reach away: recompute it within the reach of the
        # change, from the cells within the reach of that. A code reads the four neighbours: the same, one
        # cell further. (Beyond the grid counts as it does for the whole grid; a cut side is far enough.)
        reach = closing_reach(self.closing_size_cells)
        closed_box = _grown(changed, reach, shape)
        read = _slices(_grown(closed_box, reach, shape))
        closed = close_unknown_holes(self.state[read], self.closing_size_cells)[_within(closed_box, read)]
        target = self.closed[_slices(closed_box)]
        was_free, now_free = target == CellState.FREE, closed == CellState.FREE
        self.n_free += int(np.count_nonzero(now_free)) - int(np.count_nonzero(was_free))
        self._lost_free = self._lost_free or bool(np.any(was_free & ~now_free))
        self._seed_box = box_union(self._seed_box, closed_box)
        target[...] = closed
        coded_box = _grown(closed_box, 1, shape)
        read = _slices(_grown(coded_box, 1, shape))
        self.codes[_slices(coded_box)] = neighbour_codes(self.closed[read])[_within(coded_box, read)]
        self.cells = _spliced(self.cells, self.codes, coded_box)
        return coded_box

    def seeds(self, position_rc: GridRC, window: tuple[slice, slice]) -> NDArray[np.int64]:
        """:func:`~mrexplore.preprocessing.sparse_map.component_seeds` of :attr:`closed` cut to ``window``
        (window indices, sorted), the robot at ``position_rc`` (map cell).

        The robot's fill over everything it has seen was the one part of its work that grew with the map.
        Where its free space was one component holding it at the last seeds, no free cell has been lost
        since and the robot stands on free space, its free space is still one component (so the seed is
        its cell) exactly when the cells that changed join it inside their box
        (:func:`~mrexplore.preprocessing.scanline_fill.joined_in_box`): every old free cell is still free,
        and a new one is joined to the old ones by a path whose last stretch, from the last free cell
        outside the box, lies inside it.

        Where free space is in pieces (clutter: on Willow Garage at 0.05 m a robot that had seen most of the
        building filled many pieces a round), each piece keeps a label: the other pieces and their
        seeds stay as they were exactly when every changed free cell joins, inside the box, the robot's piece
        and no other (:func:`~mrexplore.preprocessing.scanline_fill.joined_to_label`, which labels them), and
        the robot still stands in that piece. Where free cells were lost too, the same holds when all of them
        were the robot's piece's and their free neighbours are still joined to one another by it within
        ``_LOST_REACH`` cells (:func:`~mrexplore.preprocessing.scanline_fill.kept_in_label`). Otherwise the
        whole fill, as before."""
        r, c = int(position_rc[0]), int(position_rc[1])
        r0, c0 = window[0].start, window[1].start
        w = window[1].stop - c0
        here = r0 <= r < window[0].stop and c0 <= c < window[1].stop  # the window lies in the grid
        on_free = here and self.closed[r, c] == CellState.FREE
        box, lost = self._seed_box, self._lost_free
        self._seed_box, self._lost_free = None, False
        robot = (r - r0) * w + (c - c0)
        if self._one_piece and on_free and not lost and (box is None or joined_in_box(self.closed, box)):
            self._others = None  # the labels were not kept up
            return np.array([robot], dtype=np.int64)
        labels, others = self._labels, self._others
        if labels is not None and others is not None and on_free:
            if box is None:
                kept = not lost
            elif lost:  # labels the robot's new cells and unlabels its lost ones
                kept = kept_in_label(self.closed, labels, box, 1, _LOST_REACH)
            else:  # labels the robot's new cells
                kept = joined_to_label(self.closed, labels, box, 1)
            if kept and labels[r, c] == 1:
                return np.sort(np.concatenate([[robot], (others[:, 0] - r0) * w + (others[:, 1] - c0)]))
        reached = np.zeros(1, dtype=np.int64)
        position = robot if here else -1
        if labels is None:
            found = pick_seeds(self.codes[window], self.closed[window], position, self.n_free, reached)
        else:
            part = labels[window]
            part[...] = 0  # nothing outside the window is free, or was: it only grows
            found = pick_seeds_labelled(self.codes[window], self.closed[window], position, self.n_free, reached, part)
        self._one_piece = on_free and int(reached[0]) == self.n_free
        self._others = None
        if labels is not None and on_free:
            rows, cols = np.divmod(found[1:], w)
            self._others = np.stack([rows + r0, cols + c0], axis=1)
        elif labels is None and not self._one_piece:
            self._labels = np.zeros(self.closed.shape, dtype=np.int32)  # pieces: label them from the next fill
        return np.sort(found)


_LOST_REACH = 8
"""How far round the cells a robot's piece lost :meth:`OnBoardGrid.seeds` looks for the ways round them
(cells); a piece joined only farther round reads as split, and the whole fill runs."""


def _grown(box: Box, margin: int, shape: tuple[int, int]) -> Box:
    rows, cols = grown_slices(box, margin, shape)
    return rows.start, rows.stop, cols.start, cols.stop


def _slices(box: Box) -> tuple[slice, slice]:
    return slice(box[0], box[1]), slice(box[2], box[3])


def _within(box: Box, outer: tuple[slice, slice]) -> tuple[slice, slice]:
    """``box`` (inside ``outer``) in the coordinates of an array cut to ``outer``."""
    r, c = outer[0].start, outer[1].start
    return slice(box[0] - r, box[1] - r), slice(box[2] - c, box[3] - c)


@nb.njit(cache=True, inline="always")
def _outside(cell: int, W: int, box: Box) -> bool:  # pragma: no cover - numba
    r, c = cell // W, cell % W
    return not (box[0] <= r < box[1] and box[2] <= c < box[3])


@nb.njit(cache=True)
def _spliced(cells: np.ndarray, codes: np.ndarray, box: Box) -> np.ndarray:  # pragma: no cover - numba
    """``cells`` (increasing row-major indices of coded cells) with those inside ``box`` replaced by the
    cells of ``box`` that have a code in ``codes`` now; still increasing (a merge of the two lists)."""
    W = codes.shape[1]
    r0, r1, c0, c1 = box
    n_new = 0
    for r in range(r0, r1):
        for c in range(c0, c1):
            n_new += codes[r, c] != 0
    out = np.empty(len(cells) + n_new, dtype=np.int64)  # at least enough: the old cells inside the box drop out
    j = 0
    o = 0
    for r in range(r0, r1):
        for c in range(c0, c1):
            if codes[r, c] == 0:
                continue
            cell = r * W + c
            while j < len(cells) and cells[j] < cell:
                if _outside(cells[j], W, box):
                    out[o] = cells[j]
                    o += 1
                j += 1
            out[o] = cell
            o += 1
    for k in range(j, len(cells)):
        if _outside(cells[k], W, box):
            out[o] = cells[k]
            o += 1
    return out[:o]
