"""The strategies shipped, as pipeline factories: what :mod:`~mrexplore.pipeline.registry` names and imports
only once a strategy is made (the command line checks a name without importing any of this)."""

from __future__ import annotations

from typing import Any

from mrexplore.config import GlobalPlanningConfig
from mrexplore.global_planning.classical import GeodesicPlanner, NearestPlanner, UtilityPlanner
from mrexplore.local_planning.router import LocalRouter
from mrexplore.pipeline.base import ExplorationPipeline
from mrexplore.pipeline.coscan import CoScanPipeline
from mrexplore.pipeline.ncm import NcmPipeline
from mrexplore.pipeline.oracle import OraclePipeline
from mrexplore.pipeline.registry import NO_PREDICTOR, Factory, PipelineConfigs

__all__ = [
    "CENTRE_COMMITMENT",
    "loaded_predictor",
    "nearest",
    "utility",
    "hier_heuristic",
    "hier_predict_heuristic",
    "hier_plan",
    "team_plan",
    "hier",
    "hier_predict",
    "ncm",
    "ncm_sampled",
    "ncm_matched",
    "coscan",
    "oracle",
]


# -- the strategies shipped --------------------------------------------------------------------------------
CENTRE_COMMITMENT = 0.5
"""Default hysteresis of strategies whose goal is a cluster centre (measured on 6 maps x 2 seeds: utility
561 mean steps without, 414 with 0.5)."""


def _commitment(gp: GlobalPlanningConfig, default: float) -> float:
    return default if gp.commitment is None else gp.commitment


def nearest(c: PipelineConfigs, policy: str | None) -> ExplorationPipeline:
    commitment = _commitment(c.global_, CENTRE_COMMITMENT)
    return ExplorationPipeline(
        "nearest", NearestPlanner(), c.preprocess, commitment=commitment, nearest_only=True, distances=c.global_
    )


def utility(c: PipelineConfigs, policy: str | None) -> ExplorationPipeline:
    commitment = _commitment(c.global_, CENTRE_COMMITMENT)
    return ExplorationPipeline(
        "utility", UtilityPlanner(c.global_), c.preprocess, commitment=commitment, distances=c.global_
    )


def hier_heuristic(c: PipelineConfigs, policy: str | None) -> ExplorationPipeline:
    # The paper's three layers with explore_lite's cost as the global affinity. No hysteresis by default: a
    # route already commits the robot to a sequence of targets (measured on 6 maps x 2 seeds: 442 mean
    # steps without, 480 with commitment 0.5).
    router = LocalRouter(c.local, c.preprocess)
    commitment = _commitment(c.global_, 1.0)
    return ExplorationPipeline(
        "hier-heuristic", UtilityPlanner(c.global_), c.preprocess, router, commitment, distances=c.global_
    )


def team_plan(c: PipelineConfigs, policy: str | None) -> ExplorationPipeline:
    # The paper's layers 1 and 3 with a team plan as the global layer: every robot's route through the
    # clusters minimising the team's makespan, each robot sent to its route's first cluster.
    from mrexplore.global_planning.team_plan import TeamPlanPlanner

    router = LocalRouter(c.local, c.preprocess)
    commitment = _commitment(c.global_, 1.0)
    return ExplorationPipeline(
        "team-plan", TeamPlanPlanner(c.global_), c.preprocess, router, commitment, distances=c.global_
    )


def hier_plan(c: PipelineConfigs, policy: str | None) -> ExplorationPipeline:
    # hier, its learned cost plus what each choice costs the team plan's makespan, Hungarian decoding.
    from mrexplore.global_planning.learned.policy import LearnedPlanner
    from mrexplore.global_planning.team_plan import PlanCostPlanner

    pipeline = hier(c, policy)
    learned = pipeline.planner
    assert isinstance(learned, LearnedPlanner)
    pipeline.name = "hier-plan"
    pipeline.planner = PlanCostPlanner(learned, c.global_, "learned-plan")
    return pipeline


def loaded_predictor(predictor: str | None) -> tuple[Any, dict[str, str]]:
    """The map predictor ``predictor`` names (a file; None: the shipped one; ``none``: no network) and what a
    mission's record says of it."""
    if predictor == NO_PREDICTOR:
        return None, {"path": NO_PREDICTOR, "sha256": ""}
    from mrexplore.prediction.network import load_predictor

    loaded = load_predictor(predictor)
    return loaded, loaded.describe()


def hier_predict_heuristic(c: PipelineConfigs, policy: str | None) -> ExplorationPipeline:
    # hier-heuristic whose global cost also rewards the new area predicted beyond each cluster.
    from mrexplore.global_planning.predictive import PredictiveUtilityPlanner

    predictor, info = loaded_predictor(c.predictor)
    router = LocalRouter(c.local, c.preprocess)
    commitment = _commitment(c.global_, 1.0)
    pipeline = ExplorationPipeline(
        "hier-predict-heuristic",
        PredictiveUtilityPlanner(predictor, c.global_),
        c.preprocess,
        router,
        commitment,
        distances=c.global_,
    )
    pipeline.predictor = info
    return pipeline


def _loaded_policy(kind: str, policy: str | None) -> tuple[Any, dict[str, str]]:
    """The network of a learned strategy's policy file (``kind`` a learned method's; None: the shipped one), by
    the method's loader (NumPy's, unless training's :func:`~mrexplore.training.twins.decide_with_torch` changed
    it), and what a mission's record says of the file."""
    from pathlib import Path

    from mrexplore.global_planning.learned.methods import learned_method

    loaded = learned_method(kind).load(Path(policy) if policy else None)
    info = {"path": str(loaded.path), "sha256": loaded.sha256, "code_version": str(loaded.meta["code_version"])}
    return loaded.net, info


def hier(c: PipelineConfigs, policy: str | None) -> ExplorationPipeline:
    # The paper's three layers with the learned global layer (mGNN affinities, Hungarian decoding); a team under
    # learned_min_robots decides as hier-heuristic.
    from mrexplore.global_planning.learned.policy import LearnedPlanner

    net, info = _loaded_policy("hier", policy)
    predictor, predictor_info = loaded_predictor(c.predictor) if net.cfg.reads_prediction else (None, None)
    planner = LearnedPlanner(net, c.global_, predictor=predictor, min_robots=c.global_.learned_min_robots)
    router = LocalRouter(c.local, c.preprocess)
    commitment = _commitment(c.global_, 1.0)
    pipeline = ExplorationPipeline("hier", planner, c.preprocess, router, commitment, policy=info, distances=c.global_)
    pipeline.predictor = predictor_info  # a policy that reads the predicted gain: the predictor it ran
    return pipeline


def hier_predict(c: PipelineConfigs, policy: str | None) -> ExplorationPipeline:
    # hier's learned residual over hier-predict-heuristic's cost: the shipped policy and the predictor together.
    from mrexplore.global_planning.learned.policy import LearnedPlanner

    net, info = _loaded_policy("hier", policy)
    predictor, predictor_info = loaded_predictor(c.predictor)
    planner = LearnedPlanner(
        net, c.global_, "learned-predict", predictor=predictor, gain_cost=True, min_robots=c.global_.learned_min_robots
    )
    router = LocalRouter(c.local, c.preprocess)
    commitment = _commitment(c.global_, 1.0)
    pipeline = ExplorationPipeline(
        "hier-predict", planner, c.preprocess, router, commitment, policy=info, distances=c.global_
    )
    pipeline.predictor = predictor_info
    return pipeline


def _ncm(name: str, sample: bool = False, match: bool = False) -> Factory:
    def make(c: PipelineConfigs, policy: str | None) -> ExplorationPipeline:
        # NeuralCoMapping re-implemented: no hysteresis (it replans every robot every decision), no local
        # layer (each robot drives to its node).
        from mrexplore.global_planning.learned.ncm_planner import NcmPlanner

        net, info = _loaded_policy("ncm", policy)
        planner = NcmPlanner(net, sample=sample, name=name, match=match)
        return NcmPipeline(name, planner, c.preprocess, policy=info, distances=c.global_)

    return make


def coscan(c: PipelineConfigs, policy: str | None) -> ExplorationPipeline:
    return CoScanPipeline("coscan", GeodesicPlanner(), c.preprocess, distances=c.global_, coscan=c.coscan)


def oracle(c: PipelineConfigs, policy: str | None) -> ExplorationPipeline:
    return OraclePipeline("oracle", NearestPlanner(), c.preprocess, goals_are_frontiers=False, distances=c.global_)


ncm = _ncm("ncm")
ncm_sampled = _ncm("ncm-sampled", sample=True)
ncm_matched = _ncm("ncm-matched", match=True)
