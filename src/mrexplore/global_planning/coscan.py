"""CoScan-2D (Dong et al., SIGGRAPH 2019) on the grid: frontier tasks, robot-seeded geodesic Lloyd
clustering with split and merge, Hungarian assignment, and a 2-opt tour per robot.

Pure functions on distance matrices (or, on large maps, their rows searched on demand: :data:`TaskRows`);
the pipeline that feeds them is ``pipeline.coscan.CoScanPipeline``.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numba as nb
import numpy as np
from numpy.typing import NDArray

from mrexplore.global_planning.tours import open_tour

__all__ = [
    "sample_tasks",
    "cap_tasks",
    "tasks_in_reach",
    "lloyd_clusters",
    "LloydResult",
    "TaskRows",
    "matrix_rows",
    "two_opt_tour",
    "tour_length",
]

TaskRows = Callable[[NDArray[np.int64]], NDArray[np.float64]]
"""Rows of the task-to-task distances on demand: ``rows(idx)`` is ``(len(idx), m)``, from the tasks ``idx`` to
every task (on a large map the strategy searches only the rows Lloyd reads: its centroids')."""


def sample_tasks(frontier_rc: NDArray[np.integer], spacing_cells: float) -> NDArray[np.int32]:
    """Frontier cells at least ``spacing_cells`` apart: greedy over the cells in the given order, a cell
    is kept when no kept cell lies within the spacing (buckets of the spacing's size make it linear).

    Examples
    --------
    >>> sample_tasks(np.array([[0, c] for c in range(12)]), 5).tolist()
    [[0, 0], [0, 5], [0, 10]]
    """
    pts = np.asarray(frontier_rc, dtype=np.int64).reshape(-1, 2)
    if len(pts) == 0:
        return np.zeros((0, 2), dtype=np.int32)
    s = max(float(spacing_cells), 1.0)  # buckets no smaller than a cell: finer ones only cost memory
    low = np.floor_divide(pts.min(axis=0), s).astype(np.int64) - 1  # a bucket ring round the cells
    high = np.floor_divide(pts.max(axis=0), s).astype(np.int64) + 1
    kept = _sample(pts, s, float(spacing_cells) ** 2, int(low[0]), int(low[1]), int(high[0]), int(high[1]))
    return pts[kept].astype(np.int32)


@nb.njit(cache=True)
def _sample(
    pts: np.ndarray, s: float, s2: float, br0: int, bc0: int, br1: int, bc1: int
) -> np.ndarray:  # pragma: no cover - numba
    """Indices of the kept cells, in order. Each bucket's kept cells form a linked list (``head``, ``nxt``)."""
    head = np.full((br1 - br0 + 1, bc1 - bc0 + 1), -1, dtype=np.int64)
    nxt = np.full(len(pts), -1, dtype=np.int64)
    kept = np.empty(len(pts), dtype=np.int64)
    n = 0
    for i in range(len(pts)):
        r = pts[i, 0]
        c = pts[i, 1]
        br = int(np.floor(r / s)) - br0
        bc = int(np.floor(c / s)) - bc0
        near = False
        for dr in range(-1, 2):
            for dc in range(-1, 2):
                j = head[br + dr, bc + dc]
                while j >= 0 and not near:
                    if (pts[j, 0] - r) ** 2 + (pts[j, 1] - c) ** 2 < s2:
                        near = True
                    j = nxt[j]
        if not near:
            kept[n] = i
            n += 1
            nxt[i] = head[br, bc]
            head[br, bc] = i
    return kept[:n]


def cap_tasks(nearest_robot_dist: NDArray[np.floating], max_tasks: int) -> NDArray[np.int64]:
    """Indices of the tasks kept: reachable ones, at most ``max_tasks``, the farthest dropped first.

    Examples
    --------
    >>> cap_tasks(np.array([5.0, np.inf, 1.0, 3.0]), 2).tolist()
    [2, 3]
    """
    d = np.asarray(nearest_robot_dist, dtype=np.float64)
    order = np.argsort(d, kind="stable")
    order = order[np.isfinite(d[order])][:max_tasks]
    return np.sort(order)


_LOWER_SLACK = 1e-4
"""Relative slack under which :func:`tasks_in_reach` takes its straight-line bound: searched distances add in
float32, so an exact one may read a few units in the last place under the true length."""


def tasks_in_reach(
    reads: NDArray[np.floating], robots_rc: NDArray[np.integer], tasks_rc: NDArray[np.integer], max_tasks: int
) -> NDArray[np.bool_]:
    """Which tasks :func:`cap_tasks` may keep, given distances known to be no shorter than the true ones
    (``reads``, ``(n_robots, m)``, ``inf`` where not known yet): all but those whose shortest possible way
    from any robot (the octile distance on the 8-connected grid, which no path beats) is longer than the
    ``max_tasks``-th smallest of the best reads. At least ``max_tasks`` tasks are then nearer than any such
    task, whatever its searched distance, so the tasks kept and their distances are the same without
    searching its ``inf`` reads.

    Examples
    --------
    >>> reads = np.array([[3.0, 5.0, np.inf, np.inf]])  # the third task could be 4 away, the last not
    >>> tasks_in_reach(reads, np.array([[0, 0]]), np.array([[0, 3], [5, 0], [4, 0], [0, 9]]), 2).tolist()
    [True, True, True, False]
    """
    reads = np.asarray(reads, dtype=np.float64)
    best = reads.min(axis=0) if len(reads) else np.full(len(tasks_rc), np.inf)
    known = np.sort(best[np.isfinite(best)])
    if len(known) < max_tasks or max_tasks < 1:
        return np.ones(len(best), dtype=bool)
    gap = np.abs(np.asarray(tasks_rc, np.float64)[None, :, :] - np.asarray(robots_rc, np.float64)[:, None, :])
    octile = gap.max(axis=2) + (math.sqrt(2.0) - 1.0) * gap.min(axis=2)
    return octile.min(axis=0) * (1.0 - _LOWER_SLACK) <= known[max_tasks - 1]


@dataclass(frozen=True)
class LloydResult:
    """Task clusters: ``labels`` ``(m,) int64`` cluster per task, ``centroids`` ``(k,) int64`` the task each
    cluster's centroid was snapped to, and the iterations run."""

    labels: NDArray[np.int64]
    centroids: NDArray[np.int64]
    iterations: int


def _snap(members: NDArray[np.int64], task_rc: NDArray[np.floating]) -> int:
    mean = task_rc[members].mean(axis=0)
    return int(members[np.argmin(((task_rc[members] - mean) ** 2).sum(axis=1))])


def matrix_rows(matrix: NDArray[np.float64]) -> TaskRows:
    """:data:`TaskRows` of a whole matrix.

    Examples
    --------
    >>> matrix_rows(np.array([[0.0, 2.0], [2.0, 0.0]]))(np.array([1])).tolist()
    [[2.0, 0.0]]
    """

    def rows(idx: NDArray[np.int64]) -> NDArray[np.float64]:
        return matrix[idx]

    return rows


def lloyd_clusters(
    task_rc: NDArray[np.integer],
    d_tasks: NDArray[np.floating] | TaskRows,
    d_robots: NDArray[np.floating],
    delta_cells: float,
    max_iterations: int = 10,
) -> LloydResult:
    """CoScan's robot-seeded Lloyd clustering with geodesic distances.

    The first centroids are the robots. Each iteration assigns every task to its geodesically nearest
    centroid, moves each centroid to its members' mean snapped to the nearest member (a frontier cell,
    so in free space), splits a cluster whose farthest member is more than ``delta_cells`` from its
    centroid (the farthest member seeds the new cluster), and, while clusters outnumber robots, merges
    a singleton into the cluster whose centroid is within ``delta_cells`` of it. It stops when the
    centroids no longer change, or after ``max_iterations``.

    Parameters
    ----------
    task_rc:
        ``(m, 2)`` task cells.
    d_tasks:
        ``(m, m)`` geodesic distances between tasks, cells; or :data:`TaskRows` giving its rows on demand
        (only centroids' rows are read).
    d_robots:
        ``(n, m)`` geodesic distances robot -> task, cells (finite for every task).
    """
    pts = np.asarray(task_rc, dtype=np.float64)
    n_robots, m = d_robots.shape
    rows = d_tasks if callable(d_tasks) else matrix_rows(np.asarray(d_tasks, dtype=np.float64))
    if m == 0:
        return LloydResult(np.zeros(0, np.int64), np.zeros(0, np.int64), 0)
    centroid_dist = np.asarray(d_robots, dtype=np.float64)  # (k, m): rows are centroids
    centroids: list[int] | None = None
    iterations = 0
    for _ in range(max_iterations):
        iterations += 1
        labels = np.argmin(centroid_dist, axis=0)
        groups = [np.flatnonzero(labels == k) for k in range(len(centroid_dist))]
        new = [_snap(g, pts) for g in groups if len(g)]
        groups = [g for g in groups if len(g)]
        # Split: a cluster reaching farther than delta from its centroid gives its farthest task away. Every
        # centroid's row is read, so they are asked for at once (rows searched on demand share the threads).
        for g, row in zip(groups, rows(np.asarray(new, np.int64)), strict=True):
            far = g[np.argmax(row[g])]
            if row[far] > delta_cells:
                new.append(int(far))
        # Merge: while clusters outnumber robots, a singleton within delta of another centroid joins it.
        sizes = {c: len(g) for c, g in zip(new, groups, strict=False)}
        for c in list(new):
            if len(new) <= n_robots:
                break
            if sizes.get(c, 0) != 1:
                continue
            row = rows(np.array([c]))[0]
            if any(row[o] <= delta_cells for o in new if o != c):
                new.remove(c)
        new = sorted(set(new))
        if centroids is not None and new == centroids:
            break
        centroids = new
        centroid_dist = rows(np.asarray(centroids, np.int64))
    assert centroids is not None
    labels = np.argmin(centroid_dist, axis=0)  # the centroids' rows: read when the loop last set them
    used = np.unique(labels)
    remap = np.full(len(centroids), -1, dtype=np.int64)
    remap[used] = np.arange(len(used))
    return LloydResult(remap[labels].astype(np.int64), np.asarray(centroids, np.int64)[used], iterations)


def tour_length(order: NDArray[np.integer], d_start: NDArray[np.floating], d: NDArray[np.floating]) -> float:
    """Length of the open tour robot -> order[0] -> order[1] -> ..."""
    if len(order) == 0:
        return 0.0
    o = np.asarray(order)
    return float(d_start[o[0]] + d[o[:-1], o[1:]].sum())


def two_opt_tour(d_start: NDArray[np.floating], d: NDArray[np.floating]) -> NDArray[np.int64]:
    """Order of visiting ``m`` tasks from the robot: nearest neighbour, then 2-opt (reverse the span that
    shortens the open tour most) until no reversal shortens it (:func:`~mrexplore.global_planning.tours.open_tour`).

    Parameters
    ----------
    d_start:
        ``(m,)`` distances robot -> task.
    d:
        ``(m, m)`` distances task -> task.

    Examples
    --------
    >>> x = np.array([1.0, 2.0, 3.0, 4.0])  # tasks on a line, the robot at 0
    >>> d = np.abs(x[:, None] - x[None, :])
    >>> two_opt_tour(x, d).tolist()
    [0, 1, 2, 3]
    """
    m = len(d_start)
    full = np.zeros((m + 1, m + 1), dtype=np.float64)
    full[0, 1:] = full[1:, 0] = d_start
    full[1:, 1:] = d
    return open_tour(full) - 1
