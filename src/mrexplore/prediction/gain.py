"""What a robot would see from a cell if the map were as predicted: the project's LiDAR cast on the
predicted map, counting the unknown cells it reaches by their probability of being free."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numba as nb
import numpy as np
from numpy.typing import NDArray

from mrexplore.prediction.baselines import predict_all_free
from mrexplore.sim.lidar import cast_ray, ray_count, ray_directions
from mrexplore.types import CellState, StateGrid

if TYPE_CHECKING:
    from mrexplore.prediction.network import MapPredictor

__all__ = ["predicted_gain_m2", "predicted_p_free", "predicted_paths_m", "BEAM_GAP_M"]

_UNKNOWN = int(CellState.UNKNOWN)

BEAM_GAP_M = 0.2
"""Gap between neighbouring beams of a predicted scan at full range, metres (the predictor's cell)."""


def predicted_gain_m2(
    state: StateGrid,
    p_free: NDArray[np.floating],
    cells_rc: NDArray[np.integer],
    resolution_m: float,
    range_m: float,
    beam_gap_m: float = BEAM_GAP_M,
) -> NDArray[np.float64]:
    """``(n,) float64`` the expected new free area, m^2, a scan from each of ``cells_rc`` would see: beams
    stop at known walls and at unknown cells more likely wall than free (``p_free < 0.5``); each unknown
    cell a beam reaches, the one it stops on included, adds its ``p_free`` times the cell's area. Beams lie
    ``beam_gap_m`` apart at full range (an estimate: farther cells between two beams are not counted), so
    its cost does not grow with finer cells.

    Examples
    --------
    >>> F, O, U = CellState.FREE, CellState.OCCUPIED, CellState.UNKNOWN
    >>> g = np.array([[O, O, O, O, O, O],
    ...               [O, F, U, U, U, O],
    ...               [O, O, O, O, O, O]], np.uint8)
    >>> p = np.where(g == U, 0.5, (g == F).astype(float)); p[1, 4] = 0.25  # the last unknown cell: a wall
    >>> predicted_gain_m2(g, p, np.array([[1, 1]]), 1.0, 10.0).tolist()  # 0.5 + 0.5 + 0.25, where beams stop
    [1.25]
    """
    blocked = np.ascontiguousarray(p_free < 0.5)
    state = np.ascontiguousarray(state, np.uint8)
    p_free = np.ascontiguousarray(p_free)
    dirs = ray_directions(ray_count(range_m, 1.0 / beam_gap_m))
    cells = np.ascontiguousarray(np.asarray(cells_rc, np.int64).reshape(-1, 2))
    stamp = np.zeros(state.shape, np.int32)
    return _expected_seen(blocked, state, p_free, cells, dirs, range_m / resolution_m, stamp) * resolution_m**2


def predicted_p_free(predictor: MapPredictor | None, state: StateGrid, resolution_m: float) -> NDArray[np.float32]:
    """``predictor``'s completion of ``state`` (None: every unknown cell free)."""
    return predict_all_free(state, resolution_m) if predictor is None else predictor.p_free(state, resolution_m)


def predicted_paths_m(
    state: StateGrid,
    p_free: NDArray[np.floating],
    sources_rc: NDArray[np.integer],
    targets_rc: NDArray[np.integer],
    resolution_m: float,
) -> NDArray[np.float64]:
    """``(n_sources, n_targets) float64`` shortest path lengths, metres, through the cells known free or
    unknown and predicted free (``p_free >= 0.5``); ``inf`` where none leads.

    Examples
    --------
    >>> F, O, U = CellState.FREE, CellState.OCCUPIED, CellState.UNKNOWN
    >>> g = np.array([[F, U, F],
    ...               [F, O, F],
    ...               [F, F, F]], np.uint8)
    >>> p = np.where(g == U, 0.9, (g == F).astype(float))
    >>> predicted_paths_m(g, p, np.array([[0, 0]]), np.array([[0, 2]]), 1.0).tolist()  # over the gap
    [[2.0]]
    >>> p[0, 1] = 0.1  # predicted a wall: around the pillar, cutting no corner
    >>> predicted_paths_m(g, p, np.array([[0, 0]]), np.array([[0, 2]]), 1.0).tolist()
    [[6.0]]
    """
    from mrexplore.paths.distance_field import distance_fields

    passable = (state == CellState.FREE) | ((state == CellState.UNKNOWN) & (p_free >= 0.5))
    targets = np.asarray(targets_rc).reshape(-1, 2)
    fields = distance_fields(passable, np.asarray(sources_rc).reshape(-1, 2), targets)
    return np.array([f.at(targets) for f in fields], np.float64).reshape(len(fields), len(targets)) * resolution_m


@nb.njit(cache=True, nogil=True)
def _expected_seen(
    blocked: np.ndarray,
    state: np.ndarray,
    p_free: np.ndarray,
    cells: np.ndarray,
    dirs: np.ndarray,
    range_cells: float,
    stamp: np.ndarray,
) -> np.ndarray:  # pragma: no cover - numba
    """Per cell of ``cells``: the sum of ``p_free`` over the unknown cells (by ``state``) its beams reach,
    each once (``stamp`` marks the cells a scan counted with the scan's number)."""
    out = np.zeros(cells.shape[0])
    buf_len = int(4 * range_cells) + 8
    buf_r = np.empty(buf_len, np.int64)
    buf_c = np.empty(buf_len, np.int64)
    buf_t = np.empty(buf_len, np.float64)
    for k in range(cells.shape[0]):
        total = 0.0
        for j in range(dirs.shape[0]):
            n, _ = cast_ray(blocked, cells[k, 0], cells[k, 1], dirs[j, 0], dirs[j, 1], range_cells, buf_r, buf_c, buf_t)
            for i in range(n):
                r, c = buf_r[i], buf_c[i]
                if stamp[r, c] != k + 1:
                    stamp[r, c] = k + 1
                    if state[r, c] == _UNKNOWN:
                        total += p_free[r, c]
        out[k] = total
    return out
