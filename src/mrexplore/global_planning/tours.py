"""Open tours from a fixed start: nearest neighbour, then best-improvement 2-opt (numba), and tour splitting."""

from __future__ import annotations

import numba as nb
import numpy as np
from numpy.typing import NDArray

__all__ = ["open_tour", "split_tour"]


@nb.njit(cache=True)
def _open_tour(d: np.ndarray) -> np.ndarray:  # pragma: no cover - numba
    m = d.shape[0] - 1
    order = np.empty(m + 1, dtype=np.int64)
    used = np.zeros(m + 1, dtype=np.bool_)
    order[0] = 0
    used[0] = True
    for k in range(1, m + 1):
        last = order[k - 1]
        best, arg = np.inf, -1
        for j in range(1, m + 1):
            if not used[j] and d[last, j] < best:
                best, arg = d[last, j], j
        order[k] = arg
        used[arg] = True
    # Best-improvement 2-opt on the open path: reversing order[i..j] replaces the edges
    # (order[i-1], order[i]) and (order[j], order[j+1]) by (order[i-1], order[j]) and (order[i], order[j+1]).
    while True:
        gain_best, bi, bj = 1e-9, -1, -1
        for i in range(1, m):
            a, b = order[i - 1], order[i]
            for j in range(i + 1, m + 1):
                c = order[j]
                gain = d[a, b] - d[a, c]
                if j < m:
                    e = order[j + 1]
                    gain += d[c, e] - d[b, e]
                if gain > gain_best:
                    gain_best, bi, bj = gain, i, j
        if bi < 0:
            break
        order[bi : bj + 1] = order[bi : bj + 1][::-1].copy()
    return order[1:]


def open_tour(d: NDArray[np.floating]) -> NDArray[np.int64]:
    """Visiting order of nodes ``1..m`` starting from node 0, for a symmetric ``(m + 1, m + 1)`` distance
    matrix: nearest neighbour, then the 2-opt reversal that shortens the path most, until none does.

    Examples
    --------
    >>> x = np.array([0.0, 3.0, 1.0, 2.0])  # node 0 at 0, the others on a line
    >>> open_tour(np.abs(x[:, None] - x[None, :])).tolist()
    [2, 3, 1]
    """
    d = np.ascontiguousarray(d, dtype=np.float64)
    if d.shape[0] <= 1:
        return np.zeros(0, dtype=np.int64)
    return _open_tour(d)


def split_tour(d_start: NDArray[np.floating], legs: NDArray[np.floating], parts: int) -> list[tuple[int, int]]:
    """Cut a tour into at most ``parts`` contiguous pieces minimising the largest piece cost, where a piece
    ``[i, j)`` costs ``d_start[i]`` (reaching its first node) plus the legs inside it (tour splitting,
    Frederickson, Hecht and Kim 1978; the bound is found by bisection over the candidate costs).

    Parameters
    ----------
    d_start:
        ``(m,)`` distance from the team's start to each tour node.
    legs:
        ``(m - 1,)`` distance from tour node k to node k + 1.

    Examples
    --------
    A tour out and back: one robot alone costs 1 + 9 = 10; the best cut leaves the last node, which is
    near the start, to a second robot (costs 1 + 5 = 6 and 1):

    >>> split_tour(np.array([1.0, 5.0, 5.0, 1.0]), np.array([4.0, 1.0, 4.0]), 2)
    [(0, 3), (3, 4)]
    """
    m = len(d_start)
    if m == 0:
        return []
    inner = np.concatenate([[0.0], np.cumsum(legs)])

    def pieces(bound: float) -> list[tuple[int, int]] | None:
        out, i = [], 0
        while i < m:
            if d_start[i] > bound:
                return None
            j = i + 1
            while j < m and d_start[i] + inner[j] - inner[i] <= bound:
                j += 1
            out.append((i, j))
            i = j
            if len(out) > parts:
                return None
        return out

    candidates = np.unique([d_start[i] + inner[j - 1] - inner[i] for i in range(m) for j in range(i + 1, m + 1)])
    lo, hi = 0, len(candidates) - 1
    while lo < hi:
        mid = (lo + hi) // 2
        if pieces(float(candidates[mid])) is None:
            lo = mid + 1
        else:
            hi = mid
    best = pieces(float(candidates[lo]))
    assert best is not None
    return best
