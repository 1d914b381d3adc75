"""CoScan-2D as a pipeline: its own candidates (frontier tasks clustered by robot-seeded geodesic Lloyd
iterations) and its own routes (2-opt tours of a cluster's tasks)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import partial

import numpy as np
from numpy.typing import NDArray

from mrexplore.config import CoScanConfig
from mrexplore.global_planning.coscan import (
    TaskRows,
    cap_tasks,
    lloyd_clusters,
    matrix_rows,
    sample_tasks,
    tasks_in_reach,
    two_opt_tour,
)
from mrexplore.global_planning.protocol import AssignmentProblem
from mrexplore.maps.boxes import grown_slices
from mrexplore.paths.distance_field import distance_matrix, distances_at, pairwise_distances
from mrexplore.pipeline.base import ExplorationPipeline
from mrexplore.pipeline.decision import CandidateQuery, CandidateSet, FarDistances, PosedWork
from mrexplore.preprocessing.clustering import Clusters
from mrexplore.preprocessing.denoise import denoised_frontier_cells
from mrexplore.types import BoolGrid, CellState

__all__ = ["CoScanPipeline"]


@dataclass(frozen=True)
class _CoScanTasks:
    """CoScan's candidates' context: the tasks, robot-to-task distances, task-to-task distances (rows on
    demand), task labels, and the passable grid with the near/far extent where distances are estimated."""

    tasks_rc: NDArray[np.int32]
    d_robots: NDArray[np.float64]
    rows: TaskRows
    labels: NDArray[np.int64]
    passable: BoolGrid
    far: FarDistances | None

    def between(self, members: NDArray[np.int64]) -> NDArray[np.float64]:
        """``(k, k)`` distances between the tasks ``members``: rows of the whole matrix on a map searched
        exactly; on a near/far map, exact searches on the members' box grown by the exact radius (a cluster
        spans about ``2 delta_m``), rows of near/far fields for the pairs whose way leaves that box."""
        if self.far is None:
            return self.rows(members)[:, members]
        pts = self.tasks_rc[members].astype(np.int64)
        (r0, c0), (r1, c1) = pts.min(axis=0), pts.max(axis=0) + 1
        rows, cols = grown_slices((r0, r1, c0, c1), self.far.radius_cells, self.passable.shape)
        d = pairwise_distances(self.passable[rows, cols], pts - (rows.start, cols.start))
        gone = ~np.isfinite(d)
        if gone.any():  # a way round outside the box (d is symmetric, so both ends of a pair are here)
            lost = np.flatnonzero(gone.any(axis=1))
            d[lost] = np.where(gone[lost], self.rows(members[lost])[:, members], d[lost])
        return np.minimum(d, d.T)


class _NearFarRows:
    """Task-to-task distances on a near/far map, a row per task searched when first read (Lloyd reads its
    centroids' rows only: a whole matrix was 48 whole-floor searches a decision on a KTH floor at 0.05 m).

    Row i is task i's near/far field read at every task. Where the coarse grid leaves task j at ``inf``
    (behind a passage narrower than two blocks: common just after a floor's known box outgrows
    ``far_above_cells``), task j's own field read at task i is used, and where that is ``inf`` too, an exact
    search from task i stopped at the tasks still missing."""

    def __init__(self, passable: BoolGrid, tasks_rc: NDArray[np.int32], far: FarDistances) -> None:
        self.passable, self.tasks, self.far = passable, tasks_rc, far
        self.raw: dict[int, NDArray[np.float64]] = {}
        """Rows read off each task's own near/far field alone."""
        self.cache: dict[int, NDArray[np.float64]] = {}
        """Rows with their ``inf`` entries filled."""

    def _raw(self, idx: Sequence[int]) -> None:
        new = [i for i in dict.fromkeys(idx) if i not in self.raw]
        if new:
            for i, f in zip(new, self.far.fields(self.passable, self.tasks[new]), strict=True):
                self.raw[i] = f.at(self.tasks)

    def __call__(self, idx: NDArray[np.int64]) -> NDArray[np.float64]:
        new = [i for i in dict.fromkeys(np.asarray(idx).tolist()) if i not in self.cache]
        self._raw(new)
        self._raw([int(j) for i in new for j in np.flatnonzero(~np.isfinite(self.raw[i]))])
        for i in new:
            row = self.raw[i].copy()
            for j in np.flatnonzero(~np.isfinite(row)):
                row[j] = self.raw[int(j)][i]
            still = np.flatnonzero(~np.isfinite(row))
            if len(still):
                row[still] = distance_matrix(self.passable, self.tasks[i : i + 1], self.tasks[still])[0]
            self.cache[i] = row
        return np.stack([self.cache[int(i)] for i in idx]).reshape(len(idx), len(self.tasks))


@dataclass
class CoScanPipeline(ExplorationPipeline):
    """CoScan-2D: frontier tasks clustered by robot-seeded geodesic Lloyd iterations, clusters matched to
    robots by the Hungarian algorithm on geodesic distance, tasks visited in a 2-opt tour.

    Tasks come from F_un components of at least ``min_cluster_size`` cells (the other strategies' noise
    rule), so every strategy ends on the same frontiers. Where the known passable box holds more than
    ``far_above_cells`` (the KTH floors at 0.05 m), distances beyond ``exact_radius_m`` are estimated as
    for every other strategy, and only the task-to-task rows Lloyd reads are searched. Elsewhere the
    whole matrix between the tasks is searched, and the robots' searches stop once they reach the tasks.
    """

    coscan: CoScanConfig = field(default_factory=CoScanConfig)

    def candidates(self, q: CandidateQuery) -> CandidateSet:
        """Tasks sampled on F_un, capped by reachability, clustered by robot-seeded geodesic Lloyd
        iterations; each cluster's centre is its centroid task."""
        n = len(q.robots_rc)
        un = denoised_frontier_cells(q.frontiers, q.blacklist, self.preprocess.min_cluster_size)
        tasks = sample_tasks(un, self.coscan.task_spacing_m / q.resolution_m)
        if len(tasks) == 0:
            return CandidateSet(Clusters.empty(), "no_frontiers")
        passable = q.state == CellState.FREE
        cap = self.coscan.tasks_per_robot * n
        # On a near/far map a robot's task beyond the coarse grid costs a search of its own; a task that cannot
        # be among the kept ones needs none (the kept tasks and their distances stay the same).
        needed = partial(tasks_in_reach, robots_rc=q.robots_rc, tasks_rc=tasks, max_tasks=cap)
        d_robots = np.stack([distances_at(f, tasks) for f in q.fields(tasks, needed)])
        keep = cap_tasks(d_robots.min(axis=0), cap)
        if len(keep) == 0:
            return CandidateSet(Clusters.empty(), "no_reachable_frontiers")
        tasks, d_robots = tasks[keep], d_robots[:, keep]
        rows: TaskRows
        if q.far is None:
            # The whole matrix, made symmetric by the smaller of each pair's two float32 sums. Searching only
            # the rows Lloyd reads (about half) makes rows differ in the last place and missions part, with
            # more steps (docs/performance.md).
            d_tasks = distance_matrix(passable, tasks, tasks)
            d_tasks = np.minimum(d_tasks, d_tasks.T)  # equal up to float rounding; keep it symmetric
            rows = matrix_rows(d_tasks)
        else:
            rows = _NearFarRows(passable, tasks, q.far)
        lloyd = lloyd_clusters(tasks, rows, d_robots, self.coscan.delta_m / q.resolution_m, self.coscan.max_iterations)
        sizes = np.bincount(lloyd.labels, minlength=len(lloyd.centroids)).astype(np.int32)
        clusters = Clusters(tasks[lloyd.centroids], sizes, tasks, lloyd.labels.astype(np.int32))
        return CandidateSet(clusters, context=_CoScanTasks(tasks, d_robots, rows, lloyd.labels, passable, q.far))

    def route(self, i: int, k: int, problem: AssignmentProblem, work: PosedWork) -> NDArray[np.int32]:
        """The cluster's tasks in a 2-opt tour from the robot."""
        assert work.candidates is not None
        c: _CoScanTasks = work.candidates.context
        members = np.flatnonzero(c.labels == k)
        order = two_opt_tour(c.d_robots[i, members], c.between(members))
        return c.tasks_rc[members[order]]
