"""Mean-Shift clustering of F_un into candidate targets (paper IV-A): adaptive bandwidth, snapped centres."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numba as nb
import numpy as np
from numpy.typing import NDArray
from scipy.spatial import cKDTree
from scipy.spatial.distance import pdist

from mrexplore.config import PreprocessConfig

__all__ = [
    "Clusters",
    "adaptive_bandwidth",
    "bounded_bandwidth",
    "cluster_frontiers",
    "linear_percentile",
    "mean_shift",
    "split_for_team",
]


@dataclass(frozen=True)
class Clusters:
    """Frontier clusters, the candidate targets of the global planner.

    Attributes
    ----------
    centers_rc:
        ``(k, 2) int32`` each cluster's member nearest to its Mean-Shift mode (always a frontier cell).
    sizes:
        ``(k,) int32`` member counts |C_k| (the paper's information gain g_ik).
    members_rc:
        ``(n, 2) int32`` member cells of the kept clusters.
    labels:
        ``(n,) int32`` cluster index of each member, ``0 .. k-1``.
    """

    centers_rc: NDArray[np.int32]
    sizes: NDArray[np.int32]
    members_rc: NDArray[np.int32]
    labels: NDArray[np.int32]

    def __len__(self) -> int:
        return len(self.sizes)

    def members_of(self, k: int) -> NDArray[np.int32]:
        """``(|C_k|, 2) int32`` members of cluster ``k``."""
        return self.members_rc[self.labels == k]

    @classmethod
    def empty(cls) -> Clusters:
        z = np.zeros((0, 2), dtype=np.int32)
        return cls(z, np.zeros(0, dtype=np.int32), z, np.zeros(0, dtype=np.int32))


def adaptive_bandwidth(points: NDArray[np.floating], percentile: float, max_sample: int) -> float:
    """Percentile of pairwise distances (paper: the 15th), over at most ``max_sample`` evenly strided points.

    Examples
    --------
    >>> adaptive_bandwidth(np.array([[0.0, 0], [0, 1], [0, 3]]), 50, 100)
    2.0
    """
    return linear_percentile(pdist(_strided(points, max_sample)), percentile)


def bounded_bandwidth(points: NDArray[np.floating], percentile: float, max_sample: int, bound: float | None) -> float:
    """``min(adaptive_bandwidth(points, percentile, max_sample), bound)`` (``bound`` None: no bound).

    Where the bound binds, the pairs closer than it are counted on a k-d tree instead of sorting every
    pairwise distance: too few of them put the percentile at or above the bound. Late on a KTH floor
    (1,000 sampled frontier cells, the bound at a quarter of the percentile) 0.9 ms against 5.2.

    Examples
    --------
    >>> pts = np.array([[0.0, 0], [0, 1], [0, 3]])  # distances 1, 2, 3: the median is 2
    >>> bounded_bandwidth(pts, 50, 100, 1.5), bounded_bandwidth(pts, 50, 100, 2.5)
    (1.5, 2.0)
    """
    if bound is not None:
        sample = _strided(points, max_sample)
        pairs = len(sample) * (len(sample) - 1) // 2
        lo = min(math.floor((pairs - 1) * (percentile / 100)), pairs - 1)
        # Pairs at most a hair beyond the bound (k-d tree and pdist may round a distance differently;
        # counting too many only forgoes the shortcut); count_neighbors counts each pair twice and each
        # point with itself.
        tree = cKDTree(sample)
        near = (int(tree.count_neighbors(tree, bound * (1 + 1e-9) + 1e-9)) - len(sample)) // 2
        if near <= lo:  # the sorted distances at lo and above are >= bound: so is the percentile
            return float(bound)
    bandwidth = adaptive_bandwidth(points, percentile, max_sample)
    return bandwidth if bound is None else min(bandwidth, bound)


def _strided(points: NDArray[np.floating], max_sample: int) -> NDArray[np.floating]:
    """At most ``max_sample`` of ``points``, evenly strided (the sample the bandwidth rule reads)."""
    if len(points) > max_sample:
        return points[np.linspace(0, len(points) - 1, max_sample).astype(np.int64)]
    return points


def linear_percentile(values: NDArray[np.float64], percentile: float) -> float:
    """``np.percentile(values, percentile)`` (linear method) of a non-empty 1-D array without NaNs, bit for
    bit: the same virtual index and interpolation, on one partition. ``np.percentile``'s generality cost
    more than the pairwise distances of a routed cluster (``scipy.spatial.distance.pdist``) it reads.

    Examples
    --------
    >>> linear_percentile(np.array([4.0, 1.0, 2.0, 3.0]), 15)
    1.45
    """
    n = len(values)
    virtual = (n - 1) * (percentile / 100)
    if virtual >= n - 1:
        return float(np.max(values))
    lo = max(int(math.floor(virtual)), 0)
    part = np.partition(values, [lo, lo + 1])
    a, b = float(part[lo]), float(part[lo + 1])
    gamma = virtual - lo
    diff = b - a
    # numpy's _lerp: from the nearer end, so the result stays within [a, b].
    return b - diff * (1 - gamma) if gamma >= 0.5 else a + diff * gamma


def cluster_frontiers(
    frontier_rc: NDArray[np.integer],
    cfg: PreprocessConfig,
    bandwidth_cells: float | None = None,
    max_bandwidth_cells: float | None = None,
) -> Clusters:
    """Cluster frontier cells with Mean-Shift and snap each mode to its nearest member.

    Clusters with fewer than ``cfg.min_cluster_size`` members are dropped (paper: 2).

    Parameters
    ----------
    frontier_rc:
        ``(n, 2) int`` frontier cells (F_un).
    bandwidth_cells:
        Fixed Mean-Shift bandwidth; None: the percentile rule of ``cfg``.
    max_bandwidth_cells:
        Upper bound of the percentile rule's bandwidth (``cfg.bandwidth_max_m`` in cells); None: none.

    Examples
    --------
    >>> pts = np.array([[0, 0], [0, 1], [0, 2], [9, 9], [9, 10], [9, 11], [5, 0]])
    >>> c = cluster_frontiers(pts, PreprocessConfig())
    >>> c.centers_rc.tolist(), c.sizes.tolist()
    ([[0, 1], [9, 10]], [3, 3])
    """
    n = len(frontier_rc)
    if n < 2:
        if n == 1 and cfg.min_cluster_size <= 1:
            one = np.asarray(frontier_rc, dtype=np.int32)
            return Clusters(one, np.ones(1, np.int32), one, np.zeros(1, np.int32))
        return Clusters.empty()
    pts = np.asarray(frontier_rc, dtype=np.float64)
    if bandwidth_cells is None:
        bandwidth_cells = bounded_bandwidth(pts, cfg.bandwidth_percentile, cfg.bandwidth_sample, max_bandwidth_cells)
    bandwidth = max(bandwidth_cells, 1.0)
    modes, labels = mean_shift(pts, bandwidth)
    sizes = np.bincount(labels, minlength=len(modes))
    keep = np.flatnonzero(sizes >= cfg.min_cluster_size)
    # Deterministic, readable order: clusters sorted by their (snapped) centre, row-major.
    snapped = {int(k): _nearest_member(pts[labels == k], modes[k]) for k in keep}
    keep = np.array(sorted(keep.tolist(), key=lambda k: tuple(snapped[k])), dtype=np.int64)
    remap = np.full(len(sizes), -1, dtype=np.int64)
    remap[keep] = np.arange(len(keep))
    member = remap[labels] >= 0
    members = np.asarray(frontier_rc, dtype=np.int32)[member]
    new_labels = remap[labels[member]].astype(np.int32)
    centers = np.array([snapped[int(k)] for k in keep], dtype=np.int32).reshape(-1, 2)
    return Clusters(centers, sizes[keep].astype(np.int32), members, new_labels)


def mean_shift(
    points: NDArray[np.float64], bandwidth: float, max_iter: int = 300
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """scikit-learn's MeanShift (flat kernel, bin seeding, ``cluster_all``), its seeds moved in compiled code.

    Same seeds (``sklearn.cluster.get_bin_seeds``), same update and stopping rule, same de-duplication
    of modes by intensity and same nearest-mode labels as ``sklearn.cluster.MeanShift``; the test suite
    checks the results are equal. sklearn validates its input and dispatches through joblib on every
    neighbour query of every seed (about 0.7 ms each), which puts a decision at 100-600 ms; here every
    seed's neighbourhood sum is read off per-row prefix sums of the points (:class:`_RowIndex`), a
    binary search per row of the disc instead of a list of neighbours.

    Returns
    -------
    ``((k, 2) float64 modes, (n,) int64 labels)``, modes ordered like sklearn's ``cluster_centers_``.
    """
    seeds = bin_seeds(points, bandwidth)
    means, counts = _RowIndex(points).shift(np.array(seeds, dtype=np.float64), bandwidth, 1e-3 * bandwidth, max_iter)
    intensity: dict[tuple[float, ...], int] = {}
    for m, c in zip(means, counts, strict=True):
        if c:
            intensity[tuple(m)] = int(c)
    ordered = np.array([k for k, _ in sorted(intensity.items(), key=lambda t: (t[1], t[0]), reverse=True)])
    unique = np.ones(len(ordered), dtype=bool)
    center_tree = cKDTree(ordered)
    for j in range(len(ordered)):
        if unique[j]:
            unique[center_tree.query_ball_point(ordered[j], bandwidth)] = False
            unique[j] = True
    modes = ordered[unique]
    _, labels = cKDTree(modes).query(points, k=1)
    return modes, np.asarray(labels, dtype=np.int64)


class _RowIndex:
    """Points on integer coordinates (frontier cells) grouped by row, columns sorted, with prefix sums of
    the columns: the count and coordinate sums of the points in a disc, row by row of the disc, in
    O(rows log points) (:func:`_disc_sum`). The sums are of whole numbers, hence exact in any order."""

    def __init__(self, points: NDArray[np.float64]) -> None:
        pts = np.asarray(points, dtype=np.float64)
        if not np.array_equal(pts, np.round(pts)):
            raise ValueError("mean_shift needs points on integer coordinates (grid cells)")
        r, c = pts[:, 0].astype(np.int64), pts[:, 1].astype(np.int64)
        order = np.lexsort((c, r))
        r, c = r[order], c[order]
        self.r0 = int(r[0])
        self.starts = np.searchsorted(r, np.arange(self.r0, int(r[-1]) + 2)).astype(np.int64)
        self.cols = c.astype(np.float64)
        self.prefix = np.concatenate([[0.0], np.cumsum(self.cols)])

    def shift(
        self, seeds: NDArray[np.float64], radius: float, stop: float, max_iter: int
    ) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
        """Flat-kernel Mean-Shift of every seed: ``(m, 2)`` modes and ``(m,)`` counts of points in each
        mode's disc (0 for a seed whose disc was empty at once: sklearn drops it)."""
        return _shift(self.starts, self.cols, self.prefix, self.r0, np.ascontiguousarray(seeds), radius, stop, max_iter)


@nb.njit(cache=True, inline="always")
def _disc_sum(
    starts: np.ndarray, cols: np.ndarray, prefix: np.ndarray, r0: int, y: float, x: float, radius: float
) -> tuple[int, float, float]:  # pragma: no cover - numba
    """Count and coordinate sums of the points within ``radius`` of ``(y, x)``."""
    n_rows = starts.shape[0] - 1
    r2 = radius * radius
    count, sum_r, sum_c = 0, 0.0, 0.0
    lo_row = max(int(np.ceil(y - radius)) - r0 - 1, 0)
    hi_row = min(int(np.floor(y + radius)) - r0 + 1, n_rows - 1)
    for k in range(lo_row, hi_row + 1):
        s, e = starts[k], starts[k + 1]
        if s == e:
            continue
        dy = (k + r0) - y
        dy2 = dy * dy
        if dy2 > r2:
            continue
        # The row's columns inside the disc are a run of the sorted ones around x: its two ends by
        # bisection on the exact test (squared distance, row term first, as cKDTree sums it).
        a, b = s, e  # first column >= x
        while a < b:
            h = (a + b) // 2
            if cols[h] < x:
                a = h + 1
            else:
                b = h
        mid = a
        a, b = s, mid  # first inside among [s, mid)
        while a < b:
            h = (a + b) // 2
            d = x - cols[h]
            if dy2 + d * d <= r2:
                b = h
            else:
                a = h + 1
        lo = a
        a, b = mid, e  # first outside among [mid, e)
        while a < b:
            h = (a + b) // 2
            d = cols[h] - x
            if dy2 + d * d <= r2:
                a = h + 1
            else:
                b = h
        if a > lo:
            count += a - lo
            sum_r += (k + r0) * (a - lo)
            sum_c += prefix[a] - prefix[lo]
    return count, sum_r, sum_c


@nb.njit(cache=True, nogil=True)
def _shift(
    starts: np.ndarray,
    cols: np.ndarray,
    prefix: np.ndarray,
    r0: int,
    seeds: np.ndarray,
    radius: float,
    stop: float,
    max_iter: int,
) -> tuple[np.ndarray, np.ndarray]:  # pragma: no cover - numba
    """sklearn's per-seed loop: move to the mean of the disc until the move is at most ``stop`` or
    ``max_iter`` moves were made; a seed whose disc is empty stops where it is."""
    m = seeds.shape[0]
    means = seeds.copy()
    counts = np.zeros(m, dtype=np.int64)
    for j in range(m):
        it = 0
        while True:
            n, sum_r, sum_c = _disc_sum(starts, cols, prefix, r0, means[j, 0], means[j, 1], radius)
            if n == 0:
                break
            new_r, new_c = sum_r / n, sum_c / n
            dr, dc = new_r - means[j, 0], new_c - means[j, 1]
            moved = np.sqrt(dr * dr + dc * dc)
            means[j, 0], means[j, 1] = new_r, new_c
            counts[j] = n
            if moved <= stop or it == max_iter:
                break
            it += 1
    return means, counts


def bin_seeds(points: NDArray[np.float64], bin_size: float) -> NDArray[np.floating]:
    """``sklearn.cluster.get_bin_seeds(points, bin_size, 1)``, vectorised: the points rounded to a grid of
    ``bin_size``, one seed per occupied bin in order of first occurrence, as float32 like sklearn's; the
    points themselves where binning leaves as many seeds as points (sklearn then warns; here it is no news).
    sklearn rounds point by point in Python, which was a fifth of a decision.

    Examples
    --------
    >>> bin_seeds(np.array([[0.0, 0.0], [0.4, 0.2], [3.0, 1.0]]), 1.0).tolist()
    [[0.0, 0.0], [3.0, 1.0]]
    """
    binned = np.round(points / bin_size)
    if binned.ndim == 2 and binned.shape[1] == 2 and len(binned):
        # Each bin as one integer (row-major over the occupied span): a 1-D unique instead of numpy's
        # row-wise one, which sorts structured rows (a third of a Mean-Shift of thousands of frontier cells,
        # ``benchmarks/meanshift.py --from-coverage``); first occurrences either way.
        cells = binned.astype(np.int64)
        low = cells.min(axis=0)
        span = int(cells[:, 1].max() - low[1]) + 1
        _, first = np.unique((cells[:, 0] - low[0]) * span + (cells[:, 1] - low[1]), return_index=True)
    else:
        _, first = np.unique(binned, axis=0, return_index=True)
    if len(first) == len(points):
        return points
    return binned[np.sort(first)].astype(np.float32) * bin_size


def _nearest_member(members: NDArray[np.float64], mode: NDArray[np.float64]) -> list[int]:
    """The member nearest to a Mean-Shift mode: modes may fall in walls or unknown space (paper IV-A)."""
    d2 = ((members - mode) ** 2).sum(axis=1)
    return [int(v) for v in members[int(np.argmin(d2))]]


def split_for_team(clusters: Clusters, robots: int, min_cluster_size: int, min_members: int = 0) -> Clusters:
    """Clusters split until there is one per robot, where robots outnumber them.

    Mean-Shift's bandwidth (a percentile of pairwise distances) gives about as many clusters for 16
    robots as for 3; robots sharing a cluster then route through the same sub-clusters. Here the cluster
    with the most members is cut in two at the median of its members along their principal axis, each
    half's centre snapped to its member nearest the half's mean, until ``robots`` clusters exist or the
    largest has fewer than ``2 * min_cluster_size`` members or fewer than ``min_members`` (a frontier too
    short to be worth two robots). Unchanged when clusters suffice.

    Examples
    --------
    >>> pts = np.array([[0, c] for c in range(8)], dtype=np.int32)
    >>> one = Clusters(pts[3:4], np.array([8], np.int32), pts, np.zeros(8, np.int32))
    >>> two = split_for_team(one, 2, 2)
    >>> two.centers_rc.tolist(), two.sizes.tolist(), two.labels.tolist()
    ([[0, 1], [0, 5]], [4, 4], [0, 0, 0, 0, 1, 1, 1, 1])
    """
    if len(clusters) >= robots or len(clusters) == 0:
        return clusters
    members = clusters.members_rc
    labels = clusters.labels.astype(np.int64).copy()
    centers = [tuple(int(v) for v in c) for c in clusters.centers_rc]
    while len(centers) < robots:
        sizes = np.bincount(labels, minlength=len(centers))
        k = int(np.argmax(sizes))  # the first of the largest: deterministic
        if sizes[k] < max(2 * min_cluster_size, min_members):
            break
        idx = np.flatnonzero(labels == k)
        pts = members[idx].astype(np.float64)
        centred = pts - pts.mean(axis=0)
        axis = np.linalg.eigh(centred.T @ centred)[1][:, -1]  # principal axis
        if axis[0] < 0 or (axis[0] == 0 and axis[1] < 0):
            axis = -axis  # one sign, whatever LAPACK returns
        order = np.argsort(centred @ axis, kind="stable")
        # Each half in member order, so that ties of the nearest member go to the first listed.
        halves = (np.sort(idx[order[: len(idx) // 2]]), np.sort(idx[order[len(idx) // 2 :]]))
        labels[halves[1]] = len(centers)
        centers[k] = tuple(_nearest_member(members[halves[0]].astype(np.float64), members[halves[0]].mean(axis=0)))
        centers.append(tuple(_nearest_member(members[halves[1]].astype(np.float64), members[halves[1]].mean(axis=0))))
    # Renumber in the row-major order of the centres, as cluster_frontiers does.
    rank = sorted(range(len(centers)), key=lambda j: centers[j])
    remap = np.empty(len(centers), dtype=np.int64)
    remap[rank] = np.arange(len(centers))
    new_labels = remap[labels]
    return Clusters(
        np.array([centers[j] for j in rank], dtype=np.int32).reshape(-1, 2),
        np.bincount(new_labels, minlength=len(centers)).astype(np.int32),
        members,
        new_labels.astype(np.int32),
    )
