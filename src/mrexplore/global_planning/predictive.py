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
from mrexplore.prediction.gain import predicted_gain_m2, predicted_p_free, predicted_paths_m
from mrexplore.prediction.network import MapPredictor

__all__ = ["PredictiveUtilityPlanner", "PredictedTerms", "predicted_terms", "predicted_cost"]


@dataclass(frozen=True)
class PredictedTerms:
    """What the predictor adds to a decision's cost."""

    gain_m2: NDArray[np.float64]
    """``(n_clusters,)`` the new free area a scan from each cluster's centre is predicted to see, m^2."""
    shortcut_m: NDArray[np.float64] | None
    """``(n_robots, n_clusters)`` how much shorter each robot's path to each centre is through predicted free
    space than through known free space, metres (0 where none is shorter or none leads); None: not computed
    (``path_weight`` 0)."""


def predicted_terms(
    predictor: MapPredictor | None, problem: AssignmentProblem, cfg: GlobalPlanningConfig, shortcuts: bool = True
) -> PredictedTerms:
    """The predicted gain of every cluster and, where ``shortcuts`` and ``cfg.path_weight`` is not 0, the
    predicted shortcuts, both on one completion of the problem's grid (``predictor`` None: every unknown
    cell free)."""
    centres = problem.clusters.centers_rc
    p = predicted_p_free(predictor, problem.state, problem.resolution_m)
    gains = predicted_gain_m2(problem.state, p, centres, problem.resolution_m, cfg.gain_range_m)
    shortcut = None
    if shortcuts and cfg.path_weight != 0.0 and problem.n_clusters:
        known = problem.dist_m
        predicted = predicted_paths_m(problem.state, p, problem.robots_rc, centres, problem.resolution_m)
        both = np.isfinite(known) & np.isfinite(predicted)
        shortcut = np.zeros_like(known)
        shortcut[both] = np.maximum(known[both] - predicted[both], 0.0)
    return PredictedTerms(gains, shortcut)


def predicted_cost(problem: AssignmentProblem, terms: PredictedTerms, cfg: GlobalPlanningConfig) -> np.ndarray:
    """``(n_robots, n_clusters) float64``: explore_lite's cost less ``gain_weight`` per m^2 of predicted gain,
    plus ``path_weight`` per metre of predicted shortcut (``inf`` where unreachable)."""
    cost = utility_cost(problem, cfg) - cfg.gain_weight * np.asarray(terms.gain_m2, np.float64)[None, :]
    if terms.shortcut_m is not None:
        cost = cost + cfg.path_weight * terms.shortcut_m
    return cost


@dataclass
class PredictiveUtilityPlanner:
    """Robots matched to clusters by the Hungarian algorithm on :func:`predicted_cost`; ``predictor`` None:
    every unknown cell is taken for free (the gain of a plain information-gain heuristic)."""

    predictor: MapPredictor | None
    cfg: GlobalPlanningConfig = field(default_factory=GlobalPlanningConfig)
    name: str = "predict-utility"

    def assign(self, problem: AssignmentProblem) -> Assignment:
        if problem.n_clusters == 0:
            return Assignment(match_min_cost(problem.dist_cells))
        terms = predicted_terms(self.predictor, problem, self.cfg)
        return Assignment(match_min_cost(predicted_cost(problem, terms, self.cfg)))
