"""Classical assigners: nearest frontier (Yamauchi) and explore_lite's utility with Hungarian coordination."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from mrexplore.config import GlobalPlanningConfig
from mrexplore.global_planning.hungarian import match_min_cost
from mrexplore.global_planning.protocol import UNASSIGNED, Assignment, AssignmentProblem

__all__ = ["NearestPlanner", "UtilityPlanner", "GeodesicPlanner", "utility_cost"]


@dataclass
class NearestPlanner:
    """Each robot heads for its geodesically nearest cluster centre, ignoring the others (Yamauchi 1998)."""

    name: str = "nearest"

    def assign(self, problem: AssignmentProblem) -> Assignment:
        d = problem.dist_cells
        out = np.full(len(d), UNASSIGNED, dtype=np.int64)
        if d.shape[1]:
            reachable = np.isfinite(d).any(axis=1)
            out[reachable] = np.argmin(d[reachable], axis=1)
        return Assignment(out)


def utility_cost(problem: AssignmentProblem, cfg: GlobalPlanningConfig) -> np.ndarray:
    """explore_lite's frontier cost, per robot and cluster: ``3 * distance_m - 1 * size_m``.

    ``size_m`` is the cluster's member count times the resolution (explore_lite measures a frontier's
    size in metres). Returns ``(n_robots, n_clusters) float64``; ``inf`` where unreachable.
    """
    size_m = problem.clusters.sizes.astype(np.float64) * problem.resolution_m
    return cfg.distance_weight * problem.dist_m - cfg.size_weight * size_m[None, :]


@dataclass
class UtilityPlanner:
    """explore_lite's utility, robots coordinated by the Hungarian algorithm (minimum total cost)."""

    cfg: GlobalPlanningConfig = field(default_factory=GlobalPlanningConfig)
    name: str = "utility"

    def assign(self, problem: AssignmentProblem) -> Assignment:
        return Assignment(match_min_cost(utility_cost(problem, self.cfg)))


@dataclass
class GeodesicPlanner:
    """Robots matched to clusters by the Hungarian algorithm on geodesic distance alone (minimum total
    distance): CoScan-2D's assignment of its clusters."""

    name: str = "geodesic"

    def assign(self, problem: AssignmentProblem) -> Assignment:
        return Assignment(match_min_cost(problem.dist_cells))
