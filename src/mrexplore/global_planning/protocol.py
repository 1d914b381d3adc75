"""The GlobalPlanner protocol shared by classical and learned assigners, and its input/output types."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np
from numpy.typing import NDArray

from mrexplore.preprocessing.clustering import Clusters
from mrexplore.types import StateGrid

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
    """

    robots_rc: NDArray[np.int32]
    clusters: Clusters
    dist_cells: NDArray[np.float64]
    resolution_m: float
    state: StateGrid

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
    """Assigns frontier clusters to robots; classical and learned planners alike."""

    name: str

    def assign(self, problem: AssignmentProblem) -> Assignment:
        """Choose a cluster for every robot that can reach one."""
