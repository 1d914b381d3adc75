"""explore_lite's utility with a look past the frontier: each cluster is also worth the new free area a scan
from its centre is predicted to see on the map predictor's completion of the belief."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from mrexplore.config import GlobalPlanningConfig
from mrexplore.global_planning.classical import utility_cost
from mrexplore.global_planning.hungarian import match_min_cost
from mrexplore.global_planning.protocol import Assignment, AssignmentProblem
from mrexplore.prediction.gain import cluster_gains_m2
from mrexplore.prediction.network import MapPredictor

__all__ = ["PredictiveUtilityPlanner", "predicted_cost"]


def predicted_cost(problem: AssignmentProblem, gain_m2: NDArray[np.float64], cfg: GlobalPlanningConfig) -> np.ndarray:
    """``(n_robots, n_clusters) float64``: explore_lite's cost less ``gain_weight`` per m^2 of predicted gain
    (``inf`` where unreachable)."""
    return utility_cost(problem, cfg) - cfg.gain_weight * np.asarray(gain_m2, np.float64)[None, :]


@dataclass
class PredictiveUtilityPlanner:
    """Robots matched to clusters by the Hungarian algorithm on :func:`predicted_cost`; ``predictor`` None:
    every unknown cell is taken for free (the gain of a plain information-gain heuristic)."""

    predictor: MapPredictor | None
    cfg: GlobalPlanningConfig = field(default_factory=GlobalPlanningConfig)
    name: str = "predict-utility"

    def gains_m2(self, problem: AssignmentProblem) -> NDArray[np.float64]:
        """``(n_clusters,) float64`` predicted new free area seen from each cluster's centre, m^2."""
        return cluster_gains_m2(
            self.predictor, problem.state, problem.clusters.centers_rc, problem.resolution_m, self.cfg.gain_range_m
        )

    def assign(self, problem: AssignmentProblem) -> Assignment:
        if problem.n_clusters == 0:
            return Assignment(match_min_cost(problem.dist_cells))
        return Assignment(match_min_cost(predicted_cost(problem, self.gains_m2(problem), self.cfg)))
