"""360° 2D LiDAR by ray casting on the ground truth, fused into a log-odds belief (paper eq. 1), in numba.

One scan updates each cell at most once (a beam end wins over a pass-through), so near cells crossed by
many beams get one observation per scan, as a real sensor model intends.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np
from numpy.typing import NDArray

__all__ = ["ray_count", "ray_directions", "cast_ray", "scan_mark", "apply_scan", "scan_update"]

_MISS = 1
_HIT = 2


def ray_count(range_cells: float, oversampling: float) -> int:
    """Beams per scan so that neighbouring beams lie at most ``1 / oversampling`` cells apart at full range."""
    return max(8, math.ceil(2.0 * math.pi * range_cells * oversampling))


def ray_directions(n_rays: int) -> NDArray[np.float64]:
    """``(n_rays, 2) float64`` unit vectors ``(d_row, d_col)`` evenly spread over 360°."""
    a = np.arange(n_rays, dtype=np.float64) * (2.0 * math.pi / n_rays)
    return np.stack([-np.sin(a), np.cos(a)], axis=1)


@nb.njit(cache=True, inline="always")
def _first_step(pos: float, cell: int, d: float) -> tuple[int, float, float]:  # pragma: no cover - numba
    if d > 0:
        return 1, (cell + 1 - pos) / d, 1.0 / d
    if d < 0:
        return -1, (pos - cell) / -d, 1.0 / -d
    return 0, np.inf, np.inf


@nb.njit(cache=True)
def cast_ray(
    occupied: np.ndarray,
    sr: int,
    sc: int,
    dr: float,
    dc: float,
    range_cells: float,
    buf_r: np.ndarray,
    buf_c: np.ndarray,
    buf_t: np.ndarray,
) -> tuple[int, bool]:  # pragma: no cover - numba
    """Cells crossed by one beam from the centre of ``(sr, sc)``, in order (Amanatides-Woo traversal).

    Fills ``buf_r, buf_c`` with the cells and ``buf_t`` with the distance (cells) at which the beam enters
    each; returns ``(count, hit)`` where ``hit`` means the last cell is an obstacle that stopped the beam.
    Cells entered beyond ``range_cells`` are not reached.
    """
    H, W = occupied.shape
    y0 = sr + 0.5
    x0 = sc + 0.5
    r = sr
    c = sc
    step_r, t_r, dt_r = _first_step(y0, r, dr)
    step_c, t_c, dt_c = _first_step(x0, c, dc)
    t = 0.0
    n = 0
    while True:
        buf_r[n] = r
        buf_c[n] = c
        buf_t[n] = t
        n += 1
        if occupied[r, c]:
            return n, True
        if t_r < t_c:
            t = t_r
            t_r += dt_r
            r += step_r
        else:
            t = t_c
            t_c += dt_c
            c += step_c
        if t > range_cells or r < 0 or r >= H or c < 0 or c >= W or n >= buf_r.shape[0]:
            return n, False


@nb.njit(cache=True, nogil=True)
def scan_mark(
    occupied: np.ndarray,
    sr: int,
    sc: int,
    dirs: np.ndarray,
    range_cells: float,
    noise_cells: np.ndarray,
    mark: np.ndarray,
) -> tuple[int, int, int, int]:  # pragma: no cover - numba
    """Cast every beam from ``(sr, sc)``; mark each cell crossed (1) or where a beam ended (2).

    ``mark`` is ``(H, W) int8`` scratch, all zeros on entry. Returns the window ``(r0, r1, c0, c1)``
    (half-open) holding every mark. Touches no belief, so robots can scan in parallel;
    :func:`apply_scan` then fuses the marks.
    """
    r0, r1, c0, c1 = sr, sr + 1, sc, sc + 1
    buf_len = int(4 * range_cells) + 8
    buf_r = np.empty(buf_len, dtype=np.int64)
    buf_c = np.empty(buf_len, dtype=np.int64)
    buf_t = np.empty(buf_len, dtype=np.float64)
    for k in range(dirs.shape[0]):
        n, hit = cast_ray(occupied, sr, sc, dirs[k, 0], dirs[k, 1], range_cells, buf_r, buf_c, buf_t)
        end = n - 1
        if hit and noise_cells[k] < 0.0:
            # A short reading ends the beam inside free space; a long one cannot pass the wall.
            measured = buf_t[end] + noise_cells[k]
            while end > 0 and buf_t[end] > measured:
                end -= 1
        for i in range(end + 1):
            r = buf_r[i]
            c = buf_c[i]
            v = _HIT if (hit and i == end) else _MISS
            if v > mark[r, c]:
                mark[r, c] = v
        # The last cell kept is the farthest one of the beam: it bounds the window.
        r = buf_r[end]
        c = buf_c[end]
        r0 = min(r0, r)
        r1 = max(r1, r + 1)
        c0 = min(c0, c)
        c1 = max(c1, c + 1)
    return r0, r1, c0, c1


@nb.njit(cache=True, nogil=True)
def apply_scan(
    mark: np.ndarray,
    window: tuple[int, int, int, int],
    log_odds: np.ndarray,
    observed: np.ndarray,
    team_observed: np.ndarray,
    explorable: np.ndarray,
    l_hit: float,
    l_miss: float,
    l_min: float,
    l_max: float,
) -> tuple[int, int]:  # pragma: no cover - numba
    """Fuse one scan's marks into a robot's belief (log-odds form of paper eq. 1), in place; clear the marks.

    With a uniform prior, ``l += logit(p_hit)`` where a beam ended and ``l += logit(p_miss)`` where it
    passed, clamped to ``[l_min, l_max]``.

    Returns
    -------
    ``(robot_new, team_new)``: explorable cells this robot, and the team, observed for the first time.
    """
    robot_new = 0
    team_new = 0
    r0, r1, c0, c1 = window
    # Sweep the window row-major: sequential memory access beats visiting cells in beam order.
    for r in range(r0, r1):
        for c in range(c0, c1):
            m = mark[r, c]
            if m == 0:
                continue
            val = log_odds[r, c] + (l_hit if m == _HIT else l_miss)
            log_odds[r, c] = min(max(val, l_min), l_max)
            mark[r, c] = 0
            if not observed[r, c]:
                observed[r, c] = True
                if explorable[r, c]:
                    robot_new += 1
            if not team_observed[r, c]:
                team_observed[r, c] = True
                if explorable[r, c]:
                    team_new += 1
    return robot_new, team_new


def scan_update(
    occupied: np.ndarray,
    sr: int,
    sc: int,
    dirs: np.ndarray,
    range_cells: float,
    noise_cells: np.ndarray,
    log_odds: np.ndarray,
    observed: np.ndarray,
    team_observed: np.ndarray,
    explorable: np.ndarray,
    l_hit: float,
    l_miss: float,
    l_min: float,
    l_max: float,
    mark: np.ndarray,
) -> tuple[int, int]:
    """One robot's scan fused into its belief: :func:`scan_mark` then :func:`apply_scan`.

    Parameters
    ----------
    occupied:
        ``(H, W) bool`` ground truth.
    dirs:
        ``(n_rays, 2) float64`` beam directions from :func:`ray_directions`.
    noise_cells:
        ``(n_rays,) float64`` range error of each beam, cells (zeros for a noiseless sensor).
    log_odds, observed:
        ``(H, W) float32`` and ``(H, W) bool`` belief of this robot, updated in place.
    team_observed:
        ``(H, W) bool`` union of all robots' observed cells, updated in place.
    explorable:
        ``(H, W) bool`` cells that count for coverage.
    mark:
        Scratch: ``(H, W) int8`` all zeros (left zero on return).

    Returns
    -------
    ``(robot_new, team_new)`` as :func:`apply_scan`.
    """
    window = scan_mark(occupied, sr, sc, dirs, range_cells, noise_cells, mark)
    return apply_scan(mark, window, log_odds, observed, team_observed, explorable, l_hit, l_miss, l_min, l_max)
