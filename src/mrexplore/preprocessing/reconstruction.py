"""The computing centre: rebuild each robot's grid from its sparse frontier map and merge them (paper IV-A).

Free space is filled scan line by scan line from the message's seeds. A step out of a cell is allowed
towards every neighbour its code does not flag (an interior cell has code 0: all four neighbours free), so
the fill never leaves the robot's free space and reaches all of it. Non-free neighbours take the state
the code gives them; every other cell is unknown. The robots' grids are merged (free where some robot
saw free space and none an obstacle), denoised by closing, and frontiers are detected again on the
merged grid, so a frontier of one robot inside space another has seen is no frontier.

:func:`fill_paper` is the paper's own fill for comparison: one seed at the robot's position, F_un ∪ F_occ
as the fence, no neighbour codes.
"""

from __future__ import annotations

import numba as nb
import numpy as np
from numpy.typing import NDArray

from mrexplore.maps.boxes import Box, box_union, grown_slices, mask_box
from mrexplore.preprocessing.frontiers import Frontiers, close_unknown_holes, closing_reach, redetect_frontiers
from mrexplore.preprocessing.scanline_fill import mark_coded_cells, refill_box, scanline_fill
from mrexplore.preprocessing.sparse_codec import decode, peek
from mrexplore.preprocessing.sparse_map import SparseFrontierMap, apply_delta
from mrexplore.types import BoolGrid, CellState, GridRC, MrExploreError, StateGrid

__all__ = ["fill_free", "fill_paper", "reconstruct", "CentreMap", "free_iou"]

_NOT_HEARD = -1
"""Round held for a robot the centre has not heard from."""


def fill_free(codes: NDArray[np.uint8], seeds: NDArray[np.int64]) -> BoolGrid:
    """``(H, W) bool`` free space rebuilt from a code grid and its seeds (with every coded cell free).

    Examples
    --------
    Two rooms joined by a one-cell door; the door and every wall-side cell are boundary cells, and the
    fill crosses the door because the codes say where the walls are:

    >>> from mrexplore.preprocessing.sparse_map import neighbour_codes
    >>> F, O = CellState.FREE, CellState.OCCUPIED
    >>> g = np.full((5, 9), O, np.uint8); g[1:4, 1:4] = F; g[1:4, 5:8] = F; g[2, 4] = F
    >>> codes = neighbour_codes(g)
    >>> bool((fill_free(codes, np.array([2 * 9 + 2])) == (g == F)).all())
    True
    """
    filled = np.zeros(codes.shape, dtype=bool)
    scanline_fill(codes, np.asarray(seeds, dtype=np.int64), filled)
    return filled | (codes != 0)


def fill_paper(boundary: BoolGrid, seed_rc: GridRC) -> BoolGrid:
    """The paper's reconstruction: scan-line fill from one seed, fenced by F_un ∪ F_occ, plus the fence.

    The paper seeds at the robot's cell; a robot standing on the fence (next to a wall, say) has no
    interior cell to start from, and the centre cannot tell which neighbour is free. Callers measuring
    the method pass the interior cell nearest the robot instead (an oracle start, generous to the paper).
    A fill may only leave cells off the fence, so from an interior seed it stays in the free space.
    """
    filled = np.zeros(boundary.shape, dtype=bool)
    r, c = seed_rc
    if not boundary[r, c]:
        seeds = np.array([r * boundary.shape[1] + c], np.int64)
        scanline_fill(_fence_codes(boundary), seeds, filled)
    return filled | boundary


def _fence_codes(fence: BoolGrid) -> NDArray[np.uint8]:
    """The paper's rule as neighbour codes for :func:`scanline_fill`: a move between two cells is blocked
    where either lies on the fence (bits 0-3: up, down, left, right)."""
    codes = np.where(fence, np.uint8(0x0F), np.uint8(0))
    codes[1:] |= fence[:-1].astype(np.uint8)  # the cell above is on the fence
    codes[:-1] |= fence[1:].astype(np.uint8) << 1
    codes[:, 1:] |= fence[:, :-1].astype(np.uint8) << 2
    codes[:, :-1] |= fence[:, 1:].astype(np.uint8) << 3
    return codes


def _fill_box(codes: NDArray[np.uint8], cells: NDArray[np.int64], seeds: NDArray[np.int64]) -> Box | None:
    """Where one robot's fill can go: the box of its coded cells and seeds grown by one cell (free space
    is fenced by coded cells, except along the map's edges); None when the message is empty."""
    flat = np.concatenate([cells, seeds])
    if len(flat) == 0:
        return None
    W = codes.shape[1]
    rows, cols = np.divmod(flat, W)
    rs, cs = grown_slices((int(rows.min()), int(rows.max()) + 1, int(cols.min()), int(cols.max()) + 1), 1, codes.shape)
    return rs.start, rs.stop, cs.start, cs.stop


def _escaped(filled: BoolGrid, box: Box, shape: tuple[int, int]) -> bool:
    """Whether a fill in ``box`` reached a side of it inside the grid: free space may go on beyond."""
    r0, r1, c0, c1 = box
    return bool(
        (r0 > 0 and filled[0].any())
        or (r1 < shape[0] and filled[-1].any())
        or (c0 > 0 and filled[:, 0].any())
        or (c1 < shape[1] and filled[:, -1].any())
    )


def _rebuild_into(
    codes: NDArray[np.uint8], cells: NDArray[np.int64], seeds: NDArray[np.int64], free: BoolGrid, occupied: BoolGrid
) -> Box | None:
    """One robot's fill and coded cells into ``free`` and ``occupied``; returns the box every cell it set
    lies in (the whole grid where free space reached the side of the message's box), None when the
    message is empty."""
    seeds = np.asarray(seeds, dtype=np.int64)
    box = _fill_box(codes, cells, seeds)
    if box is None:
        return None
    # On a large map a robot's free space is a small part of it: fill that box only.
    r0, r1, c0, c1 = box
    sub = np.ascontiguousarray(codes[r0:r1, c0:c1])
    rows, cols = np.divmod(seeds, codes.shape[1])
    filled = np.zeros(sub.shape, dtype=bool)
    scanline_fill(sub, (rows - r0) * sub.shape[1] + (cols - c0), filled)
    if not _escaped(filled, box, codes.shape):
        free[r0:r1, c0:c1] |= filled
        mark_coded_cells(codes, cells, free, occupied)  # coded cells and their neighbours: inside the box
        return box
    filled = np.zeros(codes.shape, dtype=bool)
    scanline_fill(codes, seeds, filled)
    free |= filled
    mark_coded_cells(codes, cells, free, occupied)
    return 0, codes.shape[0], 0, codes.shape[1]


@nb.njit(cache=True, nogil=True)
def _updated_cells(cells: np.ndarray, changed: np.ndarray, codes: np.ndarray) -> np.ndarray:  # pragma: no cover
    """The sorted cells left coded after a delta: those of ``cells`` (sorted, unique) the delta did not
    touch, and the delta's ``changed`` cells (sorted) whose ``codes`` are not 0; a cell the delta lists more
    than once stays when one of its codes is not 0. One merge of the two sorted lists, the set that
    ``np.union1d(np.setdiff1d(cells, changed[codes == 0]), changed[codes != 0])`` gives, which sorted both
    again per message: 5% of a mission's time on a KTH floor under cProfile."""
    out = np.empty(len(cells) + len(changed), dtype=np.int64)
    n = i = j = 0
    while i < len(cells) or j < len(changed):
        if j >= len(changed) or (i < len(cells) and cells[i] < changed[j]):
            out[n] = cells[i]
            n += 1
            i += 1
            continue
        v = changed[j]
        keep = False
        while j < len(changed) and changed[j] == v:
            keep = keep or codes[j] != 0
            j += 1
        if i < len(cells) and cells[i] == v:
            i += 1
        if keep:
            out[n] = v
            n += 1
    return out[:n]


def _union(a: Box | None, b: Box | None) -> Box | None:
    """:func:`~mrexplore.maps.boxes.box_union` where ``b`` may be None too."""
    return a if b is None else box_union(a, b)


def _merged_state(free: BoolGrid, occupied: BoolGrid, box: Box | None, closing_size_cells: int) -> StateGrid:
    """The grid of ``free`` and ``occupied`` (nothing set outside ``box``), closed: state and closing are
    computed on ``box`` grown by the closing's reach only, which closes exactly as the whole grid does
    (:func:`~mrexplore.preprocessing.frontiers.closing_reach`); every cell beyond is unknown."""
    state = np.full(free.shape, CellState.UNKNOWN, dtype=np.uint8)
    if box is None:
        return state
    rows, cols = grown_slices(box, closing_reach(closing_size_cells), free.shape)
    state[rows, cols] = close_unknown_holes(_state_of(free[rows, cols], occupied[rows, cols]), closing_size_cells)
    return state


def _state_of(free: BoolGrid, occupied: BoolGrid) -> StateGrid:
    state = np.full(free.shape, CellState.UNKNOWN, dtype=np.uint8)
    state[occupied] = CellState.OCCUPIED
    state[free & ~occupied] = CellState.FREE
    return state


def reconstruct(
    codes: NDArray[np.uint8], seeds: NDArray[np.int64], cells: NDArray[np.int64] | None = None
) -> StateGrid:
    """``(H, W) uint8`` one robot's grid: filled free space, the coded neighbours as unknown or occupied,
    the rest unknown. ``cells``: the coded cells' row-major indices where the caller has them (a message's
    ``cells``); None: found in ``codes`` (a pass over the whole grid)."""
    free = np.zeros(codes.shape, dtype=bool)
    occupied = np.zeros(codes.shape, dtype=bool)
    if cells is None:
        cells = np.flatnonzero(codes.ravel()).astype(np.int64)
    box = _rebuild_into(codes, np.asarray(cells, dtype=np.int64), seeds, free, occupied)
    return _merged_state(free, occupied, box, 1)  # a closing of 1 cell leaves the grid as it is


_ALL = (-1, -1, -1, -1)
"""A robot's dirty box when its whole map must be rebuilt (a full map arrived, or none was rebuilt yet)."""


class CentreMap:
    """The centre's memory of every robot's last map; takes full maps and deltas, gives the merged grid.

    The merged grid is kept between rounds and redone only where the robots' maps changed (the
    centre's work follows what changed, not the map). A delta changes a robot's codes in a box; its free
    space can then differ only in that box grown by one cell, so its fill is redone there alone, seeded
    from its free space just outside, and the merge and the closing are redone round that box.
    :meth:`state_from_scratch` rebuilds everything, the reference the tests hold :meth:`state` to.

    Why a box suffices: a robot's codes are the neighbour codes of its grid, with a seed in each of its
    free components (what :func:`~mrexplore.preprocessing.sparse_map.sparse_frontier_map` sends). A cell
    that turns free or stops being free changes its own code or a neighbour's, unless every neighbour
    changed with it; so a changed cell beyond the box would bring every cell of its side of the box with
    it, out to the grid's edge. The centre rebuilds a robot whole when that cannot be ruled out: when
    its free space touched the grid's edge before, when a seed outside the box lies outside its free
    space, or when the fill in the box steps out of it into a cell that was not free.

    Examples
    --------
    >>> from mrexplore.preprocessing.sparse_map import sparse_frontier_map
    >>> F, O, U = CellState.FREE, CellState.OCCUPIED, CellState.UNKNOWN
    >>> a = np.full((4, 6), U, np.uint8); a[1:3, 0:3] = F   # robot 0 saw the left half
    >>> b = np.full((4, 6), U, np.uint8); b[1:3, 2:6] = F   # robot 1 the right half
    >>> centre = CentreMap(n_robots=2, shape=(4, 6), closing_size_cells=1)
    >>> centre.receive(sparse_frontier_map(a, 0, 0, (1, 0)))
    >>> centre.receive(sparse_frontier_map(b, 1, 0, (1, 5)))
    >>> (centre.state() == F).sum()  # 2 x 6 free cells; (1, 2) is F_un for robot 0 but not for the team
    np.int64(12)
    """

    def __init__(self, n_robots: int, shape: tuple[int, int], closing_size_cells: int) -> None:
        self.shape = shape
        self.closing_size_cells = closing_size_cells
        self._codes = [np.zeros(shape, dtype=np.uint8) for _ in range(n_robots)]
        self._seeds = [np.zeros(0, dtype=np.int64) for _ in range(n_robots)]
        self._cells = [np.zeros(0, dtype=np.int64) for _ in range(n_robots)]
        self._round = [_NOT_HEARD] * n_robots
        self._known = [False] * n_robots
        # Kept between rounds: each robot's rebuilt free space and occupied cells (allocated when first
        # rebuilt), the boxes their free cells and all their cells lie in, and where its codes changed since.
        self._free: list[BoolGrid | None] = [None] * n_robots
        self._occupied: list[BoolGrid | None] = [None] * n_robots
        self._free_box: list[Box | None] = [None] * n_robots
        self._extent: list[Box | None] = [None] * n_robots
        self._dirty: list[Box | None] = [None] * n_robots
        # Per cell, how many robots hold it free / occupied; the merged grid, closed.
        self._free_n = np.zeros(shape, dtype=np.uint16)
        self._occupied_n = np.zeros(shape, dtype=np.uint16)
        self._closed = np.full(shape, CellState.UNKNOWN, dtype=np.uint8)
        self._un = np.zeros(shape, dtype=bool)  # the merged grid's F_un and F_occ
        self._occ = np.zeros(shape, dtype=bool)

    def accepts(self, message: SparseFrontierMap) -> bool:
        """Whether :meth:`receive` can take ``message``: a full map always, a delta only on the round the
        centre holds for that robot (a delta on a base it lacks would corrupt the map)."""
        i = message.robot
        return not message.is_delta or (0 <= i < len(self._round) and self._round[i] == message.base_round)

    def base_codes(self, robot: int, round_: int) -> NDArray[np.uint8] | None:
        """``(H, W) uint8`` the code grid held for ``robot`` where the centre holds its round ``round_`` (the
        base a delta of that round decodes against), else None. Read only."""
        if 0 <= robot < len(self._round) and self._round[robot] == round_:
            return self._codes[robot]
        return None

    def read(self, data: bytes) -> SparseFrontierMap | None:
        """Decode a message's bytes: a whole map, or a delta against the codes held for its base round; None
        for a delta on a base the centre lacks. Bad bytes raise
        :class:`~mrexplore.preprocessing.sparse_codec.CodecError`."""
        head = peek(data)
        if not head.is_delta:
            if head.shape != self.shape:  # checked before decoding: the box's arrays follow the grid's size
                raise MrExploreError(
                    f"message from robot {head.robot} for a {head.shape} grid does not fit this centre "
                    f"({len(self._codes)} robots, grid {self.shape}); check the robot id and map"
                )
            return decode(data)
        base = self.base_codes(head.robot, head.base_round)
        return None if base is None else decode(data, base)

    def receive(self, message: SparseFrontierMap) -> None:
        """Take one robot's message: a full map replaces its map, a delta updates the acknowledged one."""
        i = message.robot
        if not 0 <= i < len(self._codes) or message.shape != self.shape:
            raise MrExploreError(
                f"message from robot {i} for a {message.shape} grid does not fit this centre "
                f"({len(self._codes)} robots, grid {self.shape}); check the robot id and map"
            )
        if message.is_delta:
            if self._round[i] != message.base_round:
                raise MrExploreError(
                    f"delta from robot {i} applies to round {message.base_round}, the centre holds round "
                    f"{self._round[i]}; ask the robot for a full map"
                )
            apply_delta(self._codes[i], message)
            changed, codes = message.cells, message.codes
            if len(changed) > 1 and not bool(np.all(changed[1:] >= changed[:-1])):
                order = np.argsort(changed, kind="stable")
                changed, codes = changed[order], codes[order]
            self._cells[i] = _updated_cells(self._cells[i], changed.astype(np.int64, copy=False), codes)
            if len(changed) and self._dirty[i] != _ALL:
                rows = changed // self.shape[1]
                cols = changed % self.shape[1]
                near = grown_slices(
                    (int(rows[0]), int(rows[-1]) + 1, int(cols.min()), int(cols.max()) + 1), 1, self.shape
                )
                self._dirty[i] = _union(self._dirty[i], (near[0].start, near[0].stop, near[1].start, near[1].stop))
        else:
            self._codes[i] = message.code_grid()
            # Sorted and unique, as the delta's merge needs them (the fill reads them in any order).
            self._cells[i] = np.unique(message.cells).astype(np.int64, copy=False)
            self._dirty[i] = _ALL
        self._seeds[i] = message.seeds
        self._round[i] = message.round
        self._known[i] = True

    def state(self) -> StateGrid:
        """The merged, closed grid the planners run on: free where some robot has free space and none an
        obstacle, occupied where some robot has an obstacle, then closed (paper IV-A: noise removed by
        closing after reconstruction). A copy: the centre's own grid changes with the next round; its
        frontiers come from :meth:`frontiers`."""
        changed = [box for i in range(len(self._codes)) if self._known[i] and (box := self._update(i)) is not None]
        reach = closing_reach(self.closing_size_cells)
        for box in _fewer_boxes(changed, reach):
            # The closing reads free cells up to its reach away: redo it within the reach of the change,
            # from the cells within the reach of that (as the robots do on board).
            inner = grown_slices(box, reach, self.shape)
            read = grown_slices((inner[0].start, inner[0].stop, inner[1].start, inner[1].stop), reach, self.shape)
            raw = _state_of(self._free_n[read] > 0, self._occupied_n[read] > 0)
            within = (
                slice(inner[0].start - read[0].start, inner[0].stop - read[0].start),
                slice(inner[1].start - read[1].start, inner[1].stop - read[1].start),
            )
            self._closed[inner] = close_unknown_holes(raw, self.closing_size_cells)[within]
            redetect_frontiers(
                self._closed, (inner[0].start, inner[0].stop, inner[1].start, inner[1].stop), self._un, self._occ
            )
        return self._closed.copy()

    def frontiers(self) -> Frontiers:
        """The frontiers of the grid :meth:`state` last gave (``detect_frontiers`` of it), kept like the grid
        and redone only where it changed: a whole-grid detection was 8-15 ms a decision late on a KTH floor."""
        return Frontiers(un_mask=self._un.copy(), occ_mask=self._occ.copy())

    def state_from_scratch(self) -> StateGrid:
        """:meth:`state` computed from every robot's whole map, nothing kept: each robot's fill over the
        box of its message, merged and closed on their boxes. The reference for :meth:`state`."""
        free = np.zeros(self.shape, dtype=bool)
        occupied = np.zeros(self.shape, dtype=bool)
        box: Box | None = None
        for i in range(len(self._codes)):
            if self._known[i]:  # each robot's fill in one shared pair of masks, touching only its cells
                box = _union(box, _rebuild_into(self._codes[i], self._cells[i], self._seeds[i], free, occupied))
        return _merged_state(free, occupied, box, self.closing_size_cells)

    def _update(self, i: int) -> Box | None:
        """Bring robot i's kept free space and occupied cells, and the counts, up to its codes and seeds;
        returns the box where they changed (None: nowhere)."""
        dirty, free = self._dirty[i], self._free[i]
        self._dirty[i] = None
        seeds = self._seeds[i]
        if free is None or dirty == _ALL or _touches_edge(self._free_box[i], self.shape):
            return self._rebuild_whole(i)
        if dirty is None:  # codes unchanged: so is free space, if every seed still lies in it
            return None if bool(free.ravel()[seeds].all()) else self._rebuild_whole(i)
        occupied = self._occupied[i]
        assert occupied is not None  # allocated with free
        found = np.zeros(4, dtype=np.int64)
        if not refill_box(self._codes[i], seeds, free, occupied, self._free_n, self._occupied_n, dirty, found):
            return self._rebuild_whole(i)
        if found[0] < found[1]:
            self._free_box[i] = _union(self._free_box[i], (int(found[0]), int(found[1]), int(found[2]), int(found[3])))
        self._extent[i] = _union(self._extent[i], dirty)
        return dirty

    def _rebuild_whole(self, i: int) -> Box | None:
        """Robot i's fill over the box of its whole message (the whole grid where free space reaches its
        side), replacing what was kept; returns the box where its cells changed."""
        free = np.zeros(self.shape, dtype=bool)
        occupied = np.zeros(self.shape, dtype=bool)
        box = _rebuild_into(self._codes[i], self._cells[i], self._seeds[i], free, occupied)
        changed = _union(self._extent[i], box)
        if changed is not None:
            window = slice(changed[0], changed[1]), slice(changed[2], changed[3])
            old_free, old_occupied = self._free[i], self._occupied[i]
            if old_free is None or old_occupied is None:
                self._free_n[window] += free[window]
                self._occupied_n[window] += occupied[window]
            else:
                _recount(self._free_n[window], old_free[window], free[window])
                _recount(self._occupied_n[window], old_occupied[window], occupied[window])
        self._free[i], self._occupied[i] = free, occupied
        self._free_box[i] = None if box is None else _mask_box_in(free, box)
        self._extent[i] = box
        return changed


_BOX_CALL_CELLS = 20_000
"""What closing and re-detecting one more box costs beyond its cells, in cells (about 20 us of calls at
about 1 ns a cell): on a small map the robots' boxes are closed as one wherever that is cheaper."""


def _fewer_boxes(boxes: list[Box], margin: int) -> list[Box]:
    """``boxes``, or the one box holding them all where that is less work than the boxes grown by
    ``margin`` one by one (each with :data:`_BOX_CALL_CELLS` of calls): on a small map the robots' boxes
    overlap, and closing each would close cells several times."""
    if len(boxes) < 2:
        return boxes
    whole = boxes[0]
    for b in boxes[1:]:
        whole = box_union(whole, b)

    def area(b: Box) -> int:
        return (b[1] - b[0] + 2 * margin) * (b[3] - b[2] + 2 * margin)

    return [whole] if area(whole) <= sum(area(b) + _BOX_CALL_CELLS for b in boxes) else boxes


def _mask_box_in(mask: BoolGrid, box: Box) -> Box | None:
    """The bounding box of the True cells of ``mask`` inside ``box``, in the grid's coordinates."""
    r0, r1, c0, c1 = box
    found = mask_box(mask[r0:r1, c0:c1])
    return None if found is None else (found[0] + r0, found[1] + r0, found[2] + c0, found[3] + c0)


def _recount(counts: NDArray[np.uint16], was: BoolGrid, now: BoolGrid) -> None:
    """Move per-cell robot counts from one robot's old mask to its new one, in place."""
    counts += now & ~was
    counts -= was & ~now


def _touches_edge(box: Box | None, shape: tuple[int, int]) -> bool:
    """Whether a box reaches the grid's edge (free space there may change beyond any box: rebuild whole)."""
    return box is not None and (box[0] == 0 or box[2] == 0 or box[1] == shape[0] or box[3] == shape[1])


def free_iou(a: BoolGrid, b: BoolGrid) -> float:
    """Intersection over union of two free-space masks (1.0 when both are empty).

    Examples
    --------
    >>> free_iou(np.array([True, True, False]), np.array([True, False, False]))
    0.5
    """
    union = int(np.count_nonzero(a | b))
    return 1.0 if union == 0 else int(np.count_nonzero(a & b)) / union
