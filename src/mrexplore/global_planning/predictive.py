"""explore_lite's utility with a look past the frontier: each cluster is also worth the new free area a scan
from its centre is predicted to see on the map predictor's completion of the belief."""

from __future__ import annotations

import threading
from concurrent.futures import Future
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mrexplore.config import GlobalPlanningConfig
from mrexplore.global_planning.classical import utility_cost
from mrexplore.global_planning.hungarian import match_min_cost
from mrexplore.global_planning.protocol import Assignment, AssignmentProblem
from mrexplore.prediction.gain import predicted_gain_m2, predicted_p_free, predicted_paths_m
from mrexplore.prediction.network import MapPredictor
from mrexplore.runtime.threads import start_thread
from mrexplore.types import StateGrid

__all__ = ["PredictiveUtilityPlanner", "PredictedTerms", "PredictionAhead", "predicted_terms", "predicted_cost"]


@dataclass(frozen=True)
class PredictedTerms:
    """What the predictor adds to a decision's cost."""

    gain_m2: NDArray[np.float64]
    """``(n_clusters,)`` the new free area a scan from each cluster's centre is predicted to see, m^2."""
    shortcut_m: NDArray[np.float64] | None
    """``(n_robots, n_clusters)`` how much shorter each robot's path to each centre is through predicted free
    space than through known free space, metres (0 where none is shorter or none leads); None: not computed
    (neither weighed by ``path_weight`` nor read by a policy)."""


class PredictionAhead:
    """The predictor's completion of a decision's grid, started on the shared threads as soon as the grid is
    known (:meth:`start`, from a planner's ``begin``), so that it runs while the decision clusters the
    frontiers and searches the robots' distances; :meth:`take` waits for it.

    Where one thread is allowed (``MREXPLORE_THREADS=1``, a benchmark's workers), :meth:`start` computes it at
    once. :meth:`take` computes it itself when nothing was started for that very grid, so a planner answers
    the same either way. A copy or a pickle starts empty.
    """

    def __init__(self) -> None:
        self._state: StateGrid | None = None
        self._future: Future[NDArray[np.float32]] | None = None

    def start(self, predictor: MapPredictor | None, state: StateGrid, resolution_m: float) -> None:
        """Start completing ``state`` (it must not change until :meth:`take`)."""
        self._state = state
        self._future = start_thread(lambda: _locked_p_free(predictor, state, resolution_m))

    def take(self, predictor: MapPredictor | None, state: StateGrid, resolution_m: float) -> NDArray[np.float32]:
        """The completion of ``state``: the one started for this very array, else computed now."""
        future, started = self._future, self._state
        self._state = self._future = None
        if future is not None and started is state:
            return future.result()
        return _locked_p_free(predictor, state, resolution_m)

    def __getstate__(self) -> dict[str, Any]:
        return {}

    def __setstate__(self, _: dict[str, Any]) -> None:
        self.__init__()  # type: ignore[misc]


_PREDICTING = threading.Lock()


def _locked_p_free(predictor: MapPredictor | None, state: StateGrid, resolution_m: float) -> NDArray[np.float32]:
    """:func:`predicted_p_free`, one at a time in the process (it limits the process's BLAS threads while it
    runs, and two overlapping limits could leave the wrong number behind)."""
    with _PREDICTING:
        return predicted_p_free(predictor, state, resolution_m)


def predicted_terms(
    predictor: MapPredictor | None,
    problem: AssignmentProblem,
    cfg: GlobalPlanningConfig,
    shortcuts: bool | None = None,
    ahead: PredictionAhead | None = None,
) -> PredictedTerms:
    """The predicted gain of every cluster and the predicted shortcuts, both on one completion of the
    problem's grid (``predictor`` None: every unknown cell free); the shortcuts where ``shortcuts`` is True,
    or where it is None and ``cfg.path_weight`` is not 0. ``ahead``: the completion started before the problem
    was posed, where it was."""
    centres = problem.clusters.centers_rc
    if ahead is not None:
        p = ahead.take(predictor, problem.state, problem.resolution_m)
    else:
        p = _locked_p_free(predictor, problem.state, problem.resolution_m)
    gains = predicted_gain_m2(problem.state, p, centres, problem.resolution_m, cfg.gain_range_m)
    shortcut = None
    if (cfg.path_weight != 0.0 if shortcuts is None else shortcuts) and problem.n_clusters:
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
    ahead: PredictionAhead = field(default_factory=PredictionAhead, init=False, repr=False, compare=False)

    def begin(self, state: StateGrid, resolution_m: float) -> None:
        """Start predicting ``state``, the grid of the problem that :meth:`assign` will get next."""
        self.ahead.start(self.predictor, state, resolution_m)

    def assign(self, problem: AssignmentProblem) -> Assignment:
        if problem.n_clusters == 0:
            return Assignment(match_min_cost(problem.dist_cells))
        terms = predicted_terms(self.predictor, problem, self.cfg, ahead=self.ahead)
        return Assignment(match_min_cost(predicted_cost(problem, terms, self.cfg)))
