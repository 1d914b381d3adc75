"""The GlobalPlanner protocol shared by classical and learned assigners, and its input/output types."""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property
from typing import Protocol, runtime_checkable

import numpy as np
from numpy.typing import NDArray

from mrexplore.paths.distance_field import distance_matrix
from mrexplore.preprocessing.clustering import Clusters
from mrexplore.types import CellState, StateGrid

__all__ = ["AssignmentProblem", "Assignment", "GlobalPlanner", "UNASSIGNED"]

UNASSIGNED = -1
"""Cluster index of a robot that got no target (none reachable)."""


@dataclass(frozen=True)
class AssignmentProblem:
    """Everything a global planner sees at one decision (built at the computing centre).

    Attributes
    ----------
    robots_rc:
        ``(n_robots, 2) int32`` robot cells.
    clusters:
        Candidate targets (frontier clusters with snapped centres and sizes).
    dist_cells:
        ``(n_robots, n_clusters) float64`` geodesic distance robot -> cluster centre, cells; ``inf`` where
        unreachable. With goal hysteresis, the cluster holding a robot's current goal shows the discounted
        distance to that goal instead.
    resolution_m:
        Metres per cell.
    state:
        ``(H, W) uint8`` the centre's grid the distances were computed on.
    current_cluster:
        ``(n_robots,) int64`` the cluster holding each robot's current goal, -1 for none (None: not
        known, as for a problem built by hand).
    robot_dist_cells:
        ``(n_robots, n_robots) float64`` geodesic distances between robots, cells (None: not known).
    rng:
        The mission's seeded generator, for stochastic planners (None: a planner must be deterministic).
    """

    robots_rc: NDArray[np.int32]
    clusters: Clusters
    dist_cells: NDArray[np.float64]
    resolution_m: float
    state: StateGrid
    current_cluster: NDArray[np.int64] | None = None
    robot_dist_cells: NDArray[np.float64] | None = field(default=None, repr=False)
    rng: np.random.Generator | None = field(default=None, repr=False, compare=False)

    @property
    def n_robots(self) -> int:
        return len(self.robots_rc)

    @property
    def n_clusters(self) -> int:
        return len(self.clusters)

    @cached_property
    def cluster_dist_cells(self) -> NDArray[np.float64]:
        """``(n_clusters, n_clusters) float64`` geodesic distances between cluster centres, cells; computed
        on first use (one bounded search per centre), ``inf`` where unreachable."""
        centres = self.clusters.centers_rc
        d = distance_matrix(self.state == CellState.FREE, centres, centres)
        return np.minimum(d, d.T)  # equal up to rounding; keep it symmetric

    @property
    def dist_m(self) -> NDArray[np.float64]:
        """``(n_robots, n_clusters) float64`` geodesic distances in metres."""
        return self.dist_cells * self.resolution_m


@dataclass(frozen=True)
class Assignment:
    """A planner's answer: which cluster each robot goes to."""

    cluster_of_robot: NDArray[np.int64]
    """``(n_robots,) int64`` cluster index per robot, or :data:`UNASSIGNED`."""


@runtime_checkable
class GlobalPlanner(Protocol):
    """Assigns frontier clusters to robots; classical and learned planners alike.

    A planner that reads more of the grid than the problem holds may also define ``begin(state,
    resolution_m)``: a pipeline calls it with its decision's grid before it poses the problem, so that work
    can start beside the clustering and the distance searches (the predictive planners start their map
    prediction there).
    """

    name: str

    def assign(self, problem: AssignmentProblem) -> Assignment:
        """Choose a cluster for every robot that can reach one."""
