"""Scan-line flood fill of free space, steered by neighbour codes or fenced by a mask (numba kernels).

Shared by the robot (choosing the seeds its message needs) and the centre (rebuilding free space).
"""

from __future__ import annotations

import numba as nb
import numpy as np

__all__ = ["scanline_fill", "pick_seeds", "neighbour_codes_kernel", "mark_coded_cells"]

_UP, _DOWN, _LEFT, _RIGHT = 0, 1, 2, 3
_FREE, _OCCUPIED, _UNKNOWN = 0, 1, 2  # CellState values
_DR = (-1, 1, 0, 0)
_DC = (0, 0, -1, 1)


@nb.njit(cache=True, inline="always")
def _blocked(code: int, d: int) -> bool:  # pragma: no cover - numba
    return ((code >> d) | (code >> (4 + d))) & 1 == 1


@nb.njit(cache=True, inline="always")
def _push(stack: np.ndarray, sp: int, r: int, c: int) -> tuple[np.ndarray, int]:  # pragma: no cover - numba
    if sp == len(stack):
        grown = np.empty((2 * len(stack), 2), dtype=np.int64)
        grown[:sp] = stack
        stack = grown
    stack[sp, 0] = r
    stack[sp, 1] = c
    return stack, sp + 1


@nb.njit(cache=True)
def scanline_fill(
    codes: np.ndarray, seeds: np.ndarray, fence: np.ndarray, filled: np.ndarray
) -> None:  # pragma: no cover - numba
    """Scan-line flood fill into ``filled``. With ``fence`` empty, moves follow the codes; otherwise a move
    may leave only a cell outside the fence (the paper's rule), and codes are not read."""
    H, W = filled.shape
    use_fence = fence.size > 0
    stack = np.empty((max(64, len(seeds)), 2), dtype=np.int64)
    sp = 0
    for s in seeds:
        stack, sp = _push(stack, sp, s // W, s % W)
    while sp > 0:
        sp -= 1
        r = stack[sp, 0]
        c = stack[sp, 1]
        if filled[r, c]:
            continue
        lo = c
        while lo > 0 and not filled[r, lo - 1]:
            if (fence[r, lo] or fence[r, lo - 1]) if use_fence else _blocked(codes[r, lo], _LEFT):
                break
            lo -= 1
        hi = c
        while hi < W - 1 and not filled[r, hi + 1]:
            if (fence[r, hi] or fence[r, hi + 1]) if use_fence else _blocked(codes[r, hi], _RIGHT):
                break
            hi += 1
        for x in range(lo, hi + 1):
            filled[r, x] = True
        for dr, bit in ((-1, _UP), (1, _DOWN)):
            rr = r + dr
            if rr < 0 or rr >= H:
                continue
            in_run = False
            for x in range(lo, hi + 1):
                if use_fence:  # fence cells are added afterwards; a run of cells off the fence is one seed
                    ok = not fence[r, x] and not fence[rr, x] and not filled[rr, x]
                else:
                    ok = not _blocked(codes[r, x], bit) and not filled[rr, x]
                if ok and not in_run:
                    stack, sp = _push(stack, sp, rr, x)
                in_run = ok


@nb.njit(cache=True)
def pick_seeds(codes: np.ndarray, free: np.ndarray, position: int) -> np.ndarray:  # pragma: no cover - numba
    """Row-major indices of the fewest seeds from which :func:`scanline_fill` with ``codes`` reaches every
    free cell: the robot's cell (``position``, if free) first, then the first interior cell (code 0) not
    yet reached, repeatedly. Cells with a code are in the message anyway; a component made only of them
    needs no seed."""
    H, W = codes.shape
    filled = np.zeros((H, W), dtype=np.bool_)
    no_fence = np.zeros((0, 0), dtype=np.bool_)
    out = []
    if free.ravel()[position]:
        out.append(position)
        scanline_fill(codes, np.array([position], dtype=np.int64), no_fence, filled)
    for r in range(H):
        for c in range(W):
            if free[r, c] and codes[r, c] == 0 and not filled[r, c]:
                out.append(r * W + c)
                scanline_fill(codes, np.array([r * W + c], dtype=np.int64), no_fence, filled)
    seeds = np.empty(len(out), dtype=np.int64)
    for k in range(len(out)):
        seeds[k] = out[k]
    return seeds


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
