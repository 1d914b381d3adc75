"""Scan-line flood fill of free space, steered by neighbour codes (numba kernels).

Shared by the robot (choosing the seeds its message needs) and the centre (rebuilding free space).
"""

from __future__ import annotations

import numba as nb
import numpy as np

__all__ = [
    "scanline_fill",
    "pick_seeds",
    "pick_seeds_labelled",
    "joined_to_label",
    "kept_in_label",
    "coded_cells",
    "neighbour_codes_kernel",
    "mark_coded_cells",
    "entry_seeds",
    "fill_leaves_box",
    "occupied_in",
    "joined_in_box",
    "refill_box",
]

_FREE, _OCCUPIED, _UNKNOWN = 0, 1, 2  # CellState values
_DR = (-1, 1, 0, 0)
_DC = (0, 0, -1, 1)
_UP_MASK, _DOWN_MASK, _LEFT_MASK, _RIGHT_MASK = 0x11, 0x22, 0x44, 0x88
"""A neighbour code's bits that block a move up, down, left, right (unknown or occupied that side)."""


@nb.njit(cache=True, nogil=True)
def scanline_fill(
    codes: np.ndarray, seeds: np.ndarray, filled: np.ndarray, mark: int = 1
) -> int:  # pragma: no cover - numba
    """Scan-line flood fill into ``filled`` from ``seeds`` (row-major indices): a move out of a cell is allowed
    towards every side its neighbour code does not flag. Returns the number of cells it filled. ``filled``
    may be an integer grid (0: not filled), whose filled cells are set to ``mark`` (a component's label).

    The stack is a typed list of cells: an array stack that grew by reallocation (an array variable
    reassigned in the loop) ran 8x slower on the same fills, apparently because numba then left the inner
    loops unoptimised."""
    H, W = filled.shape
    count = 0
    stack = [(0, 0) for _ in range(0)]  # an empty typed list of cells
    for s in seeds:
        stack.append((s // W, s % W))
    while len(stack):
        r, c = stack.pop()
        if filled[r, c]:
            continue
        lo = c
        while lo > 0 and not filled[r, lo - 1] and (codes[r, lo] & _LEFT_MASK) == 0:
            lo -= 1
        hi = c
        while hi < W - 1 and not filled[r, hi + 1] and (codes[r, hi] & _RIGHT_MASK) == 0:
            hi += 1
        for x in range(lo, hi + 1):
            filled[r, x] = mark
        count += hi - lo + 1
        for k in range(2):
            rr = r - 1 if k == 0 else r + 1
            if rr < 0 or rr >= H:
                continue
            mask = _UP_MASK if k == 0 else _DOWN_MASK
            in_run = False
            for x in range(lo, hi + 1):
                ok = (codes[r, x] & mask) == 0 and not filled[rr, x]
                if ok and not in_run:  # one seed per run of open cells in the next row
                    stack.append((rr, x))
                in_run = ok
    return count


@nb.njit(cache=True)
def _seeds_into(
    codes: np.ndarray,
    state: np.ndarray,
    position: int,
    n_free: int,
    reached: np.ndarray,
    filled: np.ndarray,
    every: bool,
) -> np.ndarray:  # pragma: no cover - numba
    """:func:`pick_seeds` filling ``filled`` (all 0 on entry) with each component's number, 1 for the
    robot's, 2, 3, ... in the order of the seeds; with ``every``, the components of boundary cells only
    too, after them (:func:`pick_seeds_labelled`)."""
    H, W = codes.shape
    out = []
    reached[0] = -1
    k = 1
    if 0 <= position < H * W and state[position // W, position % W] == _FREE:
        out.append(position)
        reached[0] = scanline_fill(codes, np.array([position], dtype=np.int64), filled, k)
        if reached[0] == n_free:
            return np.array([position], dtype=np.int64)
    for r in range(H):
        for c in range(W):
            if state[r, c] == _FREE and codes[r, c] == 0 and filled[r, c] == 0:
                k += 1
                out.append(r * W + c)
                scanline_fill(codes, np.array([r * W + c], dtype=np.int64), filled, k)
    if every:
        for r in range(H):
            for c in range(W):
                if state[r, c] == _FREE and filled[r, c] == 0:
                    k += 1
                    scanline_fill(codes, np.array([r * W + c], dtype=np.int64), filled, k)
    seeds = np.empty(len(out), dtype=np.int64)
    for j in range(len(out)):
        seeds[j] = out[j]
    return seeds


@nb.njit(cache=True)
def pick_seeds(
    codes: np.ndarray, state: np.ndarray, position: int, n_free: int, reached: np.ndarray
) -> np.ndarray:  # pragma: no cover - numba
    """Row-major indices of the fewest seeds from which :func:`scanline_fill` with ``codes`` reaches every
    free cell of the CellState grid ``state``: the robot's cell (``position``, if free) first, then the
    first interior cell (code 0) not yet reached, repeatedly. Cells with a code are in the message anyway;
    a component made only of them needs no seed. ``n_free``: the free cells of ``state`` where the caller
    knows them (-1: not known); when the robot's own fill reaches that many, no other component is sought.
    ``reached[0]`` is set to the cells the robot's own fill reached (-1: its cell is not free)."""
    filled = np.zeros(codes.shape, dtype=np.bool_)
    return _seeds_into(codes, state, position, n_free, reached, filled, False)


@nb.njit(cache=True)
def pick_seeds_labelled(
    codes: np.ndarray, state: np.ndarray, position: int, n_free: int, reached: np.ndarray, labels: np.ndarray
) -> np.ndarray:  # pragma: no cover - numba
    """:func:`pick_seeds`, the same seeds in the same order, labelling every 4-connected free component in
    ``labels`` (``int32``, all 0 on entry): 1 for the robot's (where its cell is free), 2, 3, ... for the
    seeded ones in the order of their seeds, then the components of boundary cells only (no seed)."""
    return _seeds_into(codes, state, position, n_free, reached, labels, True)


@nb.njit(cache=True)
def joined_to_label(
    state: np.ndarray, labels: np.ndarray, box: tuple[int, int, int, int], label: int
) -> bool:  # pragma: no cover - numba
    """Whether every free cell of ``box`` that ``labels`` leaves at 0 (free since the labels were made) is
    joined, by 4-connected such cells inside the box, to cells of component ``label`` and of no other; if
    so, those cells get ``label`` (if not, ``labels`` is left part-written). Free space that lost no cell
    since its components were labelled keeps every other component as it was exactly when this holds
    (:meth:`~mrexplore.preprocessing.onboard.OnBoardGrid.seeds`): a cell new to a component is 4-joined
    to it, and a path from it leaving the box meets an old, labelled cell first."""
    H, W = state.shape
    r0, r1, c0, c1 = box
    h, w = r1 - r0, c1 - c0
    stack = np.empty(h * w, dtype=np.int64)
    piece = np.empty(h * w, dtype=np.int64)
    seen = np.zeros((h, w), dtype=np.bool_)
    for r in range(r0, r1):
        for c in range(c0, c1):
            if state[r, c] != _FREE or labels[r, c] != 0 or seen[r - r0, c - c0]:
                continue
            # One piece of new free cells inside the box, and the labels it touches.
            seen[r - r0, c - c0] = True
            stack[0] = (r - r0) * w + (c - c0)
            n, m, touches = 1, 0, False
            while n > 0:
                n -= 1
                q = stack[n]
                piece[m] = q
                m += 1
                qr, qc = q // w + r0, q % w + c0
                for d in range(4):
                    rr, cc = qr + _DR[d], qc + _DC[d]
                    if rr < 0 or rr >= H or cc < 0 or cc >= W or state[rr, cc] != _FREE:
                        continue
                    other = labels[rr, cc]
                    if other != 0:
                        if other != label:
                            return False
                        touches = True
                    elif not (r0 <= rr < r1 and c0 <= cc < c1):
                        return False  # an unlabelled free cell outside the box: the box missed a change
                    elif not seen[rr - r0, cc - c0]:
                        seen[rr - r0, cc - c0] = True
                        stack[n] = (rr - r0) * w + (cc - c0)
                        n += 1
            if not touches:
                return False
            for j in range(m):
                labels[piece[j] // w + r0, piece[j] % w + c0] = label
    return True


@nb.njit(cache=True)
def kept_in_label(  # noqa: C901 - numba kernel
    state: np.ndarray, labels: np.ndarray, box: tuple[int, int, int, int], label: int, reach: int
) -> bool:  # pragma: no cover - numba
    """:func:`joined_to_label` where free cells of ``box`` may also have stopped being free: whether every
    cell that did belonged to component ``label``, every new free cell is joined to it (as there), and
    the free 4-neighbours of the lost cells are still joined to one another by its cells within ``reach``
    cells of the lost ones. If so, the new cells get ``label`` and the lost ones 0; if not, ``labels`` may
    be left part-written. Then no other component changed, and ``label``'s is still one: a path of it that
    went through lost cells goes round them from one of their neighbours to another."""
    H, W = state.shape
    r0, r1, c0, c1 = box
    lost_r = np.empty((r1 - r0) * (c1 - c0), dtype=np.int64)
    lost_c = np.empty((r1 - r0) * (c1 - c0), dtype=np.int64)
    n_lost = 0
    for r in range(r0, r1):
        for c in range(c0, c1):
            if state[r, c] != _FREE and labels[r, c] != 0:
                if labels[r, c] != label:
                    return False  # another component lost a cell
                lost_r[n_lost] = r
                lost_c[n_lost] = c
                n_lost += 1
    if not joined_to_label(state, labels, box, label):
        return False
    if n_lost == 0:
        return True
    # The lost cells' free neighbours, joined within the box round the lost cells grown by ``reach``.
    a0, a1 = max(0, lost_r[:n_lost].min() - reach), min(H, lost_r[:n_lost].max() + reach + 1)
    b0, b1 = max(0, lost_c[:n_lost].min() - reach), min(W, lost_c[:n_lost].max() + reach + 1)
    h, w = a1 - a0, b1 - b0
    target = np.zeros((h, w), dtype=np.bool_)
    n_target, first = 0, -1
    for k in range(n_lost):
        for d in range(4):
            rr, cc = lost_r[k] + _DR[d], lost_c[k] + _DC[d]
            if 0 <= rr < H and 0 <= cc < W and state[rr, cc] == _FREE and not target[rr - a0, cc - b0]:
                if labels[rr, cc] != label:
                    return False
                target[rr - a0, cc - b0] = True
                n_target += 1
                first = (rr - a0) * w + (cc - b0)
    if n_target > 1:
        seen = np.zeros((h, w), dtype=np.bool_)
        stack = np.empty(h * w, dtype=np.int64)
        seen[first // w, first % w] = True
        stack[0] = first
        n, found = 1, 0
        while n > 0 and found < n_target:
            n -= 1
            q = stack[n]
            qr, qc = q // w, q % w
            found += target[qr, qc]
            for d in range(4):
                rr, cc = qr + _DR[d], qc + _DC[d]
                inside = 0 <= rr < h and 0 <= cc < w and not seen[rr, cc]
                if inside and state[rr + a0, cc + b0] == _FREE and labels[rr + a0, cc + b0] == label:
                    seen[rr, cc] = True
                    stack[n] = rr * w + cc
                    n += 1
        if found < n_target:
            return False  # perhaps split: the whole fill decides
    for k in range(n_lost):
        labels[lost_r[k], lost_c[k]] = 0
    return True


@nb.njit(cache=True)
def coded_cells(codes: np.ndarray, r0: int, c0: int, width: int) -> tuple[np.ndarray, np.ndarray]:  # pragma: no cover
    """The cells of a window of codes (its first cell at ``(r0, c0)`` of a map ``width`` wide) that have a
    code: their row-major indices in the map, increasing, and their codes."""
    H, W = codes.shape
    n = 0
    for r in range(H):
        for c in range(W):
            if codes[r, c] != 0:
                n += 1
    cells = np.empty(n, dtype=np.int64)
    values = np.empty(n, dtype=np.uint8)
    k = 0
    for r in range(H):
        for c in range(W):
            if codes[r, c] != 0:
                cells[k] = (r + r0) * width + c + c0
                values[k] = codes[r, c]
                k += 1
    return cells, values


@nb.njit(cache=True)
def neighbour_codes_kernel(state: np.ndarray) -> np.ndarray:  # pragma: no cover - numba
    """Neighbour code of every free cell of a CellState grid (see ``sparse_map.neighbour_codes``)."""
    H, W = state.shape
    codes = np.zeros((H, W), dtype=np.uint8)
    for r in range(H):
        for c in range(W):
            if state[r, c] != _FREE:
                continue
            code = 0
            for d in range(4):
                rr = r + _DR[d]
                cc = c + _DC[d]
                if rr < 0 or rr >= H or cc < 0 or cc >= W:
                    continue
                s = state[rr, cc]
                if s == _UNKNOWN:
                    code |= 1 << d
                elif s == _OCCUPIED:
                    code |= 1 << (4 + d)
            codes[r, c] = code
    return codes


@nb.njit(cache=True)
def mark_coded_cells(
    codes: np.ndarray, cells: np.ndarray, free: np.ndarray, occupied: np.ndarray
) -> None:  # pragma: no cover - numba
    """Mark the listed boundary cells free and the neighbours their codes call occupied (sparse: touches
    only the listed cells and their neighbours)."""
    H, W = codes.shape
    for k in range(len(cells)):
        r = cells[k] // W
        c = cells[k] % W
        free[r, c] = True
        code = codes[r, c]
        for d in range(4):
            rr = r + _DR[d]
            cc = c + _DC[d]
            # A code from the wire may flag a side beyond the grid: numba does not check bounds, so we do.
            if (code >> (4 + d)) & 1 and 0 <= rr < H and 0 <= cc < W:
                occupied[rr, cc] = True


@nb.njit(cache=True, nogil=True)
def entry_seeds(
    codes: np.ndarray, free: np.ndarray, box: tuple[int, int, int, int]
) -> np.ndarray:  # pragma: no cover - numba
    """Cells of ``box`` (row-major indices in the box) that a free cell just outside it steps into: where
    the robot's free space outside the box enters it. A move out of a cell is allowed towards each side its
    neighbour code does not flag, as in :func:`scanline_fill`."""
    H, W = codes.shape
    r0, r1, c0, c1 = box
    w = c1 - c0
    out = []
    for c in range(c0, c1):
        if r0 > 0 and free[r0 - 1, c] and (codes[r0 - 1, c] & _DOWN_MASK) == 0:
            out.append(c - c0)
        if r1 < H and free[r1, c] and (codes[r1, c] & _UP_MASK) == 0:
            out.append((r1 - 1 - r0) * w + c - c0)
    for r in range(r0, r1):
        if c0 > 0 and free[r, c0 - 1] and (codes[r, c0 - 1] & _RIGHT_MASK) == 0:
            out.append((r - r0) * w)
        if c1 < W and free[r, c1] and (codes[r, c1] & _LEFT_MASK) == 0:
            out.append((r - r0) * w + w - 1)
    seeds = np.empty(len(out), dtype=np.int64)
    for k in range(len(out)):
        seeds[k] = out[k]
    return seeds


@nb.njit(cache=True, nogil=True)
def fill_leaves_box(
    codes: np.ndarray, free: np.ndarray, filled: np.ndarray, box: tuple[int, int, int, int]
) -> bool:  # pragma: no cover
    """Whether a cell the fill in ``box`` reached steps out of the box into a cell outside it that was not
    free space: free space changed beyond the box, and only a fill of the whole grid can say how."""
    H, W = codes.shape
    r0, r1, c0, c1 = box
    for c in range(c0, c1):
        if r0 > 0 and filled[0, c - c0] and (codes[r0, c] & _UP_MASK) == 0 and not free[r0 - 1, c]:
            return True
        if r1 < H and filled[r1 - 1 - r0, c - c0] and (codes[r1 - 1, c] & _DOWN_MASK) == 0 and not free[r1, c]:
            return True
    for r in range(r0, r1):
        if c0 > 0 and filled[r - r0, 0] and (codes[r, c0] & _LEFT_MASK) == 0 and not free[r, c0 - 1]:
            return True
        if c1 < W and filled[r - r0, c1 - 1 - c0] and (codes[r, c1 - 1] & _RIGHT_MASK) == 0 and not free[r, c1]:
            return True
    return False


@nb.njit(cache=True, nogil=True)
def occupied_in(codes: np.ndarray, box: tuple[int, int, int, int]) -> np.ndarray:  # pragma: no cover - numba
    """``(h, w) bool`` the cells of ``box`` that a code (of a cell in the box or next to it) calls
    occupied: what :func:`mark_coded_cells` marks there."""
    H, W = codes.shape
    r0, r1, c0, c1 = box
    out = np.zeros((r1 - r0, c1 - c0), dtype=np.bool_)
    for r in range(max(r0 - 1, 0), min(r1 + 1, H)):
        for c in range(max(c0 - 1, 0), min(c1 + 1, W)):
            code = codes[r, c]
            if code < 16:
                continue  # no side flagged occupied
            for d in range(4):
                rr = r + _DR[d]
                cc = c + _DC[d]
                if (code >> (4 + d)) & 1 and r0 <= rr < r1 and c0 <= cc < c1:
                    out[rr - r0, cc - c0] = True
    return out


@nb.njit(cache=True, nogil=True)
def joined_in_box(state: np.ndarray, box: tuple[int, int, int, int]) -> bool:  # pragma: no cover - numba
    """Whether every free cell of ``box`` in the CellState grid ``state`` is joined, by 4-connected free
    cells inside the box, to a free cell just outside it; False where no free cell outside touches the
    box. Free space that was one component and lost no cell stays one component after gaining cells in
    ``box`` exactly when this holds (:meth:`~mrexplore.preprocessing.onboard.OnBoardGrid.seeds`)."""
    H, W = state.shape
    r0, r1, c0, c1 = box
    h, w = r1 - r0, c1 - c0
    seen = np.zeros((h, w), dtype=np.bool_)
    stack = np.empty(h * w, dtype=np.int64)
    n = 0
    for r in range(r0, r1):  # entries: free cells of the box with a free 4-neighbour outside it
        for c in range(c0, c1):
            if (r == r0 or r == r1 - 1 or c == c0 or c == c1 - 1) and state[r, c] == _FREE:
                for d in range(4):
                    rr, cc = r + _DR[d], c + _DC[d]
                    outside = rr < r0 or rr >= r1 or cc < c0 or cc >= c1
                    if outside and 0 <= rr < H and 0 <= cc < W and state[rr, cc] == _FREE:
                        if not seen[r - r0, c - c0]:
                            seen[r - r0, c - c0] = True
                            stack[n] = (r - r0) * w + (c - c0)
                            n += 1
                        break
    if n == 0:
        return False
    while n > 0:
        n -= 1
        k = stack[n]
        r, c = k // w, k % w
        for d in range(4):
            rr, cc = r + _DR[d], c + _DC[d]
            if 0 <= rr < h and 0 <= cc < w and not seen[rr, cc] and state[rr + r0, cc + c0] == _FREE:
                seen[rr, cc] = True
                stack[n] = rr * w + cc
                n += 1
    for r in range(h):
        for c in range(w):
            if state[r + r0, c + c0] == _FREE and not seen[r, c]:
                return False
    return True


@nb.njit(cache=True, nogil=True)
def refill_box(
    codes: np.ndarray,
    seeds: np.ndarray,
    free: np.ndarray,
    occupied: np.ndarray,
    free_n: np.ndarray,
    occupied_n: np.ndarray,
    box: tuple[int, int, int, int],
    free_box: np.ndarray,
) -> bool:  # pragma: no cover - numba
    """One robot's kept ``free`` and ``occupied`` cells redone in ``box`` from its ``codes`` and ``seeds``
    (row-major map indices), in place, with the per-cell robot counts ``free_n`` and ``occupied_n``; the
    centre's step for a delta (:class:`~mrexplore.preprocessing.reconstruction.CentreMap`). The fill
    starts from the seeds in the box and where the kept free space just outside steps in
    (:func:`entry_seeds`). Returns False, changing nothing, where only a whole rebuild can say: a seed
    outside the box lies outside the kept free space, or the fill steps out of the box into a cell that
    was not free (:func:`fill_leaves_box`). ``free_box`` (4 ints) receives the box of the free cells now
    in ``box`` (rows r0 > r1 where there are none)."""
    H, W = codes.shape
    r0, r1, c0, c1 = box
    h, w = r1 - r0, c1 - c0
    entries = entry_seeds(codes, free, box)
    start = np.empty(len(seeds) + len(entries), dtype=np.int64)
    n = 0
    for s in seeds:
        r, c = s // W, s % W
        if r0 <= r < r1 and c0 <= c < c1:
            start[n] = (r - r0) * w + (c - c0)
            n += 1
        elif not free[r, c]:
            return False
    for e in entries:
        start[n] = e
        n += 1
    filled = np.zeros((h, w), dtype=np.bool_)
    scanline_fill(codes[r0:r1, c0:c1], start[:n], filled)
    if fill_leaves_box(codes, free, filled, box):
        return False
    marks = occupied_in(codes, box)
    free_box[0], free_box[1], free_box[2], free_box[3] = r1, r0, c1, c0
    for r in range(r0, r1):
        for c in range(c0, c1):
            now = filled[r - r0, c - c0] or codes[r, c] != 0
            _set_counted(free, free_n, r, c, now)
            _set_counted(occupied, occupied_n, r, c, marks[r - r0, c - c0])
            if now:
                free_box[0] = min(free_box[0], r)
                free_box[1] = max(free_box[1], r + 1)
                free_box[2] = min(free_box[2], c)
                free_box[3] = max(free_box[3], c + 1)
    return True


@nb.njit(cache=True, nogil=True, inline="always")
def _set_counted(mask: np.ndarray, counts: np.ndarray, r: int, c: int, now: bool) -> None:  # pragma: no cover
    """Set ``mask[r, c]`` to ``now``, moving the per-cell robot count with it."""
    if now != mask[r, c]:
        mask[r, c] = now
        if now:
            counts[r, c] += 1
        else:
            counts[r, c] -= 1
