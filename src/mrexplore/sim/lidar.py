"""360° 2D LiDAR by ray casting on the ground truth, fused into a log-odds belief (paper eq. 1), in numba.

One scan updates each cell at most once (a beam end wins over a pass-through), so near cells crossed by
many beams get one observation per scan, as a real sensor model intends.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numba as nb
import numpy as np
from numpy.typing import NDArray

__all__ = ["ray_count", "ray_directions", "cast_ray", "scan_mark", "Beams", "apply_scan", "scan_update"]

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


@nb.njit(cache=True, inline="always")
def _beam_buffers(range_cells: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:  # pragma: no cover - numba
    """Scratch for :func:`cast_ray`: rows, columns and entry distances of a beam's cells, room for any beam."""
    buf_len = int(4 * range_cells) + 8
    return np.empty(buf_len, dtype=np.int64), np.empty(buf_len, dtype=np.int64), np.empty(buf_len, dtype=np.float64)


@nb.njit(cache=True, nogil=True, inline="always")
def _cast_and_mark(
    occupied: np.ndarray,
    sr: int,
    sc: int,
    direction: np.ndarray,
    range_cells: float,
    noise: float,
    buf_r: np.ndarray,
    buf_c: np.ndarray,
    buf_t: np.ndarray,
    mark: np.ndarray,
) -> tuple[int, int]:  # pragma: no cover - numba
    """Cast one beam and mark its cells (1 crossed, 2 where it ended on an obstacle), ``noise`` cells off its
    reading; returns the last cell kept."""
    n, hit = cast_ray(occupied, sr, sc, direction[0], direction[1], range_cells, buf_r, buf_c, buf_t)
    end = n - 1
    if hit and noise < 0.0:
        # A short reading ends the beam inside free space; a long one cannot pass the wall.
        measured = buf_t[end] + noise
        while end > 0 and buf_t[end] > measured:
            end -= 1
    for i in range(end + 1):
        r = buf_r[i]
        c = buf_c[i]
        v = _HIT if (hit and i == end) else _MISS
        if v > mark[r, c]:
            mark[r, c] = v
    return buf_r[end], buf_c[end]


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
    buf_r, buf_c, buf_t = _beam_buffers(range_cells)
    for k in range(dirs.shape[0]):
        r, c = _cast_and_mark(occupied, sr, sc, dirs[k], range_cells, noise_cells[k], buf_r, buf_c, buf_t, mark)
        # The last cell kept is the farthest one of the beam: it bounds the window.
        r0 = min(r0, r)
        r1 = max(r1, r + 1)
        c0 = min(c0, c)
        c1 = max(c1, c + 1)
    return r0, r1, c0, c1


@nb.njit(cache=True)
def _beam_moves(
    dirs: np.ndarray, range_cells: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:  # pragma: no cover - numba
    """Each beam of :func:`cast_ray` from a cell's centre on an open grid, as moves: ``(n_rays, L) uint8``
    (1: a column step, 0: a row step), the cells it enters within range (its source among them), and the
    sign of its row and column steps."""
    buf_r, buf_c, buf_t = _beam_buffers(range_cells)
    buf_len = buf_r.shape[0]
    side = 2 * buf_len + 3
    open_grid = np.zeros((side, side), dtype=np.bool_)
    o = buf_len + 1
    n_rays = dirs.shape[0]
    moves = np.zeros((n_rays, buf_len), dtype=np.uint8)
    count = np.zeros(n_rays, dtype=np.int64)
    sign_r = np.zeros(n_rays, dtype=np.int64)
    sign_c = np.zeros(n_rays, dtype=np.int64)
    for k in range(n_rays):
        n, _ = cast_ray(open_grid, o, o, dirs[k, 0], dirs[k, 1], range_cells, buf_r, buf_c, buf_t)
        count[k] = n
        for i in range(n - 1):
            if buf_c[i + 1] != buf_c[i]:
                moves[k, i] = 1
                sign_c[k] = buf_c[i + 1] - buf_c[i]
            else:
                sign_r[k] = buf_r[i + 1] - buf_r[i]
    return moves, count, sign_r, sign_c


@nb.njit(cache=True, nogil=True)
def _mark_by_moves(
    occupied: np.ndarray,
    sr: int,
    sc: int,
    moves: np.ndarray,
    count: np.ndarray,
    sign_r: np.ndarray,
    sign_c: np.ndarray,
    dirs: np.ndarray,
    range_cells: float,
    noise_cells: np.ndarray,
    mark: np.ndarray,
) -> tuple[int, int, int, int]:  # pragma: no cover - numba
    """:func:`scan_mark` with each beam walked by its precomputed moves (:class:`Beams`), marking as it goes;
    a beam whose reading is short (negative noise) is cast as there, to find where it ends."""
    H, W = occupied.shape
    occ = occupied.reshape(H * W)  # views: both are C-contiguous (numba refuses to reshape others)
    mk = mark.reshape(H * W)
    r0, r1, c0, c1 = sr, sr + 1, sc, sc + 1
    reach = moves.shape[1] + 1
    inside = sr - reach >= 0 and sr + reach < H and sc - reach >= 0 and sc + reach < W  # no beam leaves the grid
    buf_r, buf_c, buf_t = _beam_buffers(range_cells)
    for k in range(moves.shape[0]):
        if noise_cells[k] < 0.0:
            r, c = _cast_and_mark(occupied, sr, sc, dirs[k], range_cells, noise_cells[k], buf_r, buf_c, buf_t, mark)
        else:
            dr, dc = sign_r[k], sign_c[k]
            r, c = sr, sc
            at = r * W + c
            n = count[k]
            for i in range(n):
                if occ[at]:
                    mk[at] = _HIT  # the beam's end wins over any pass-through
                    break
                if mk[at] == 0:
                    mk[at] = _MISS
                if i == n - 1:
                    break
                if moves[k, i]:
                    if not inside and (c + dc < 0 or c + dc >= W):
                        break
                    c += dc
                    at += dc
                else:
                    if not inside and (r + dr < 0 or r + dr >= H):
                        break
                    r += dr
                    at += dr * W
        # The last cell kept is the farthest one of the beam: it bounds the window.
        r0 = min(r0, r)
        r1 = max(r1, r + 1)
        c0 = min(c0, c)
        c1 = max(c1, c + 1)
    return r0, r1, c0, c1


@dataclass(frozen=True)
class Beams:
    """A sensor's beams, each walked once on an open grid: from a cell's centre a beam first crosses a cell
    side half a cell away on each axis, so the cells it enters, as steps from its source, are the same from
    every cell. A scan then walks those steps (:meth:`mark`) instead of casting each beam again: the same
    marks as :func:`scan_mark` in half the time (100 against 197 us a scan from 3,000 random free cells of
    KTH 50052748 at 0.05 m, a throwaway timing; the scans were a fifth of a whole mission's time there).

    Examples
    --------
    >>> occ = np.zeros((5, 5), bool); occ[:, 4] = True
    >>> beams = Beams.of(2.0, 1.0)
    >>> mark = np.zeros((5, 5), np.int8)
    >>> beams.mark(occ, 2, 2, np.zeros(len(beams.dirs)), mark)
    (0, 5, 0, 5)
    >>> mark[2].tolist()  # free to the left, the wall two cells to the right stops the beam
    [1, 1, 1, 1, 2]
    """

    dirs: NDArray[np.float64]
    """``(n_rays, 2) float64`` the beams' directions (:func:`ray_directions`)."""
    range_cells: float
    moves: NDArray[np.uint8]
    """``(n_rays, L) uint8`` each beam's steps from its source: 1 a column step, 0 a row step."""
    count: NDArray[np.int64]
    """``(n_rays,) int64`` the cells each beam enters within range, its source included."""
    sign_r: NDArray[np.int64]
    sign_c: NDArray[np.int64]

    def __deepcopy__(self, memo: dict[int, object]) -> Beams:
        return self  # read-only once built: a mission's snapshot shares it

    @classmethod
    def of(cls, range_cells: float, oversampling: float) -> Beams:
        """The beams of :func:`ray_count` and :func:`ray_directions` for a sensor of ``range_cells``."""
        dirs = ray_directions(ray_count(range_cells, oversampling))
        return cls(dirs, float(range_cells), *_beam_moves(dirs, float(range_cells)))

    def mark(
        self, occupied: np.ndarray, sr: int, sc: int, noise_cells: np.ndarray, mark: np.ndarray
    ) -> tuple[int, int, int, int]:
        """:func:`scan_mark` from ``(sr, sc)``: the same marks in ``mark`` and the same window.
        ``occupied`` ``(H, W) bool`` C-contiguous."""
        return _mark_by_moves(
            occupied,
            sr,
            sc,
            self.moves,
            self.count,
            self.sign_r,
            self.sign_c,
            self.dirs,
            self.range_cells,
            noise_cells,
            mark,
        )


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
