"""The learned global planner: mGNN affinities decoded by the Hungarian algorithm (evaluation) or sampled by
robots choosing one after another without replacement (training), with an exact log-probability.

The planner sees its network only through :class:`HierScorer`, a NumPy scoring protocol: the NumPy network
(what the strategies run) and training's torch one both answer it, and training records what it needs
through :attr:`LearnedPlanner.on_sample`. Nothing here imports torch."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field, replace
from typing import Protocol

import numpy as np
from numpy.typing import NDArray

from mrexplore.config import GlobalPlanningConfig, LearnedConfig
from mrexplore.global_planning.classical import utility_cost
from mrexplore.global_planning.hungarian import match_min_cost
from mrexplore.global_planning.learned.features import GraphInputs, graph_inputs, route_positions
from mrexplore.global_planning.predictive import PredictionAhead, predicted_cost, predicted_terms
from mrexplore.global_planning.protocol import UNASSIGNED, Assignment, AssignmentProblem
from mrexplore.global_planning.team_plan import TeamPlanPlanner
from mrexplore.prediction.network import MapPredictor
from mrexplore.types import StateGrid

__all__ = ["HierScorer", "LearnedPlanner", "SampleHook", "edge_path64", "hungarian_decode", "sample_sequential"]


class HierScorer(Protocol):
    """What the learned planner asks of its network, in NumPy: the network's settings, the weights of its
    linear edge path, whether its scoring MLP adds nothing, and the learned residual at one decision."""

    @property
    def cfg(self) -> LearnedConfig:
        """The network's settings (its inputs and size)."""

    @property
    def edge_weights(self) -> NDArray[np.float64]:
        """The linear edge path's weights, one per edge feature."""

    def scores_nothing(self) -> bool:
        """Whether the scoring MLP adds nothing (the residual is the linear edge path alone)."""

    def residual_of(self, g: GraphInputs) -> NDArray[np.float64]:
        """The learned residual ``(R, C) float64`` at one decision's inputs."""


SampleHook = Callable[[GraphInputs, NDArray[np.int64], NDArray[np.int64], float], None]
"""Called with a sampled decision's inputs, robot order, choices and log-probability (training records it)."""


def hungarian_decode(affinity: NDArray[np.floating]) -> NDArray[np.int64]:
    """The assignment maximising the summed affinity (paper eq. 2); ``-inf`` pairs are never used.

    Where robots outnumber clusters, every cluster is used once before any is shared (the "virtual
    clusters" of the paper's remark, of -inf affinity below any real one); where clusters outnumber
    robots, the rest stay unassigned (its virtual robots). See :func:`match_min_cost`.

    Examples
    --------
    >>> hungarian_decode(np.array([[5.0, 4.0], [4.0, 0.0]])).tolist()  # 4 + 4 beats 5 + 0
    [1, 0]
    """
    return match_min_cost(-np.asarray(affinity, dtype=np.float64))


def _available(allowed: NDArray[np.bool_], taken: NDArray[np.bool_]) -> NDArray[np.bool_]:
    """Clusters a robot may pick: allowed ones no robot took yet; when all are taken, any allowed one."""
    free = allowed & ~taken
    return free if free.any() else allowed


def sample_sequential(
    affinity: NDArray[np.floating], rng: np.random.Generator
) -> tuple[NDArray[np.int64], NDArray[np.int64], float]:
    """Robots choose in a random order, each a cluster with probability softmax(affinity) over the clusters
    it may still take (:func:`_available`).

    Returns ``order (R,)``, ``choices (R,)`` (cluster per robot, :data:`UNASSIGNED` where none is allowed)
    and the log-probability of the choices given the order (which does not depend on the network).
    """
    aff = np.asarray(affinity, dtype=np.float64)
    R, C = aff.shape
    order = rng.permutation(R).astype(np.int64)
    choices = np.full(R, UNASSIGNED, dtype=np.int64)
    taken = np.zeros(C, dtype=bool)
    logp = 0.0
    for i in order:
        allowed = np.isfinite(aff[i])
        if not allowed.any():
            continue
        avail = _available(allowed, taken)
        z = np.where(avail, aff[i], -np.inf)
        z = z - z[avail].max()
        p = np.exp(z)
        p /= p.sum()
        k = int(rng.choice(C, p=p))
        choices[i] = k
        taken[k] = True
        logp += float(np.log(p[k]))
    return order, choices, logp


def edge_path64(g: GraphInputs, w: NDArray[np.floating]) -> NDArray[np.float64]:
    """The linear edge path, ``edges . w`` ``(R, C)``, in float64 (one rounding for every library).

    Examples
    --------
    >>> from mrexplore.global_planning.learned.features import EDGE_FEATURES
    >>> e = np.zeros((1, 2, EDGE_FEATURES), np.float32); e[0, :, 0] = [1.0, 2.0]
    >>> g = GraphInputs(np.zeros((1, 3), np.float32), np.zeros((2, 4), np.float32), e, np.ones((1, 2), bool),
    ...                 np.zeros((1, 2), np.float32))
    >>> edge_path64(g, np.array([-0.5, 0, 0, 0, 0])).tolist()
    [[-0.5, -1.0]]
    """
    return g.edges.astype(np.float64) @ np.asarray(w, np.float64)


@dataclass
class LearnedPlanner:
    """The paper's learned global layer behind the :class:`GlobalPlanner` protocol.

    Deterministic by default (Hungarian on E_rc). With ``sample=True`` it draws from the sequential
    policy with ``rng`` (or the problem's generator) and appends a :class:`PolicyStep` to ``record``.
    ``net`` is the NumPy network (what the strategies run) or the torch one (training; ``record`` needs it).
    """

    net: HierScorer
    heuristic: GlobalPlanningConfig = field(default_factory=GlobalPlanningConfig)
    name: str = "learned"
    sample: bool = False
    rng: np.random.Generator | None = None
    on_sample: SampleHook | None = None
    """Called after each sampled decision (training's recorder)."""
    predictor: MapPredictor | None = None
    """The map predictor of a policy that reads the predicted gain, or of ``gain_cost`` (None: every unknown
    cell taken for free)."""
    gain_cost: bool = False
    """The heuristic cost under the learned residual is ``hier-predict-heuristic``'s (explore_lite's less
    ``heuristic.gain_weight`` per m^2 of predicted gain), not explore_lite's alone (strategy ``hier-predict``)."""
    min_robots: int = 1
    """Deterministic decisions of a smaller team take the heuristic cost alone, without the residual (the
    strategies set it from :attr:`~mrexplore.config.GlobalPlanningConfig.learned_min_robots`; sampling for
    training always adds it)."""
    ahead: PredictionAhead = field(default_factory=PredictionAhead, init=False, repr=False, compare=False)
    _plan: TeamPlanPlanner = field(init=False, repr=False, compare=False)
    """The team plan of a policy that reads it (``use_plan_regret``, ``use_plan_position``)."""

    def __post_init__(self) -> None:
        self._plan = TeamPlanPlanner(self.heuristic)

    def begin(self, state: StateGrid, resolution_m: float) -> None:
        """Start predicting ``state``, the grid of the problem that :meth:`assign` will get next (where this
        planner reads a prediction)."""
        if self.net.cfg.reads_prediction or self.gain_cost:
            self.ahead.start(self.predictor, state, resolution_m)

    def inputs(self, problem: AssignmentProblem) -> GraphInputs:
        """The network's inputs at ``problem`` (the predicted gains among them where the policy reads them)."""
        return self._inputs(problem)[0]

    def _inputs(self, problem: AssignmentProblem) -> tuple[GraphInputs, NDArray[np.float64]]:
        """The inputs and the heuristic cost ``(R, C) float64`` under the residual (``inf`` where unreachable)."""
        terms = None
        ncfg = self.net.cfg
        if ncfg.reads_prediction or self.gain_cost:
            # The shortcuts where the network reads them, or where the heuristic cost weighs them.
            shortcuts = ncfg.use_predicted_path or (self.gain_cost and self.heuristic.path_weight != 0.0)
            terms = predicted_terms(self.predictor, problem, self.heuristic, shortcuts, self.ahead)
        gains = terms.gain_m2 if terms is not None and ncfg.use_predicted_gain else None
        paths = terms.shortcut_m if terms is not None and ncfg.use_predicted_path else None
        regret = position = None
        if ncfg.reads_plan and problem.n_clusters:
            plan = self._plan.plan(problem)
            regret, position = plan.first_regret, route_positions(plan.routes, problem.n_clusters)
        elif ncfg.reads_plan:
            regret = position = np.zeros((problem.n_robots, 0))
        g = graph_inputs(problem, ncfg, self.heuristic, gains, paths, regret, position)
        cost = utility_cost(problem, self.heuristic)
        if self.gain_cost:
            assert terms is not None
            cost = predicted_cost(problem, terms, self.heuristic)
            base = np.where(g.reachable, -cost / self.net.cfg.base_scale, 0.0).astype(np.float32)
            g = replace(g, base=base)
        return g, cost

    def affinity(self, problem: AssignmentProblem) -> tuple[GraphInputs, NDArray[np.float64]]:
        """E_rc ``(R, C) float64`` (``-inf`` where unreachable), with the inputs.

        E_rc = -(cost - base_scale * residual) / base_scale, the cost being explore_lite's in float64.
        """
        g, cost = self._cost(problem)
        return g, -cost / self.net.cfg.base_scale

    def cost(self, problem: AssignmentProblem) -> NDArray[np.float64]:
        """The Hungarian cost ``(R, C) float64`` the deterministic decoding minimises (``inf`` where
        unreachable): what other costs can be added to before matching."""
        return self._cost(problem)[1]

    def _cost(self, problem: AssignmentProblem) -> tuple[GraphInputs, NDArray[np.float64]]:
        """The affinity in cost form, ``cost - base_scale * residual`` (``inf`` where unreachable)."""
        g, cost = self._inputs(problem)
        if problem.n_robots < self.min_robots and not self.sample:
            return g, cost
        if self.net.scores_nothing():
            # The scoring MLP adds zero: the residual is the linear edge path alone, and the blocks of
            # attention would run for nothing (1.1 of the 1.7 ms the learned assignment took a decision at
            # 8 robots on the largest HouseExpo map). It is computed in float64, on either network: in
            # float32 its rounding depended on the library (and on the CPU's code path), and assignments
            # whose sums tie exactly (robots swapping clusters at equal distances) went one way or the other.
            return g, cost - self.net.cfg.base_scale * edge_path64(g, self.net.edge_weights)
        return g, cost - self.net.cfg.base_scale * self.net.residual_of(g)  # inf stays inf

    def assign(self, problem: AssignmentProblem) -> Assignment:
        g, cost = self._cost(problem)
        if not self.sample:
            # Hungarian on E_rc (eq. 2) in cost form, argmin sum (cost - scale * residual): with a zero
            # residual exactly the utility planner's matching (no float rounding of its ties).
            return Assignment(match_min_cost(cost))
        aff = -cost / self.net.cfg.base_scale
        rng = self.rng or problem.rng or np.random.default_rng()
        order, choices, logp = sample_sequential(aff, rng)
        if self.on_sample is not None:
            self.on_sample(g, order, choices, logp)
        return Assignment(choices)
