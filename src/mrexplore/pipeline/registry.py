"""Named strategies, each a complete pipeline, registered and made by name in the manner of Gymnasium's
``register`` / ``make``: the CLI, the bench and the trainer only ever name a strategy.

Examples
--------
>>> from mrexplore.pipeline import make_strategy, strategy_names
>>> make_strategy("utility").name, "hier" in strategy_names()
('utility', True)
>>> make_strategy("hier-heuristic", local=False).name
'hier-heuristic-nolocal'
"""

from __future__ import annotations

import os
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from mrexplore.config import CoScanConfig, GlobalPlanningConfig, LocalPlanningConfig, PreprocessConfig
from mrexplore.global_planning.classical import GeodesicPlanner, NearestPlanner, UtilityPlanner
from mrexplore.local_planning.router import LocalRouter
from mrexplore.pipeline.base import ExplorationPipeline
from mrexplore.pipeline.coscan import CoScanPipeline
from mrexplore.pipeline.ncm import NcmPipeline
from mrexplore.pipeline.oracle import OraclePipeline
from mrexplore.types import MrExploreError

__all__ = [
    "NO_LOCAL_SUFFIX",
    "PipelineConfigs",
    "StrategySpec",
    "register_strategy",
    "strategy_spec",
    "strategy_names",
    "make_strategy",
    "policy_for",
]

NO_LOCAL_SUFFIX = "-nolocal"
"""A strategy name with this suffix (``hier-nolocal``) runs without its local layer."""


@dataclass(frozen=True)
class PipelineConfigs:
    """The settings a strategy's pipeline is built from."""

    global_: GlobalPlanningConfig = field(default_factory=GlobalPlanningConfig)
    preprocess: PreprocessConfig = field(default_factory=PreprocessConfig)
    local: LocalPlanningConfig = field(default_factory=LocalPlanningConfig)
    coscan: CoScanConfig = field(default_factory=CoScanConfig)
    predictor: str | None = None
    """The map predictor of the predictive strategies: a file written by ``mrexplore train --predictor``,
    ``none`` (every unknown cell free) or None (the shipped one)."""


Factory = Callable[[PipelineConfigs, "str | None"], ExplorationPipeline]
"""Builds a strategy's pipeline from its settings and a policy file (None: the shipped one, or no network)."""


@dataclass(frozen=True)
class StrategySpec:
    """A registered strategy."""

    name: str
    factory: Factory
    policy_kind: str | None = None
    """The kind of policy file a learned strategy reads (``hier`` or ``ncm``, which ``--policy KIND=FILE``
    names); None: no network."""
    predictive: bool = False
    """The strategy reads a map predictor (``--predictor``)."""


_REGISTRY: dict[str, StrategySpec] = {}


def register_strategy(name: str, factory: Factory, policy_kind: str | None = None, predictive: bool = False) -> None:
    """Make ``factory``'s pipeline available as ``name`` to :func:`make_strategy`, the CLI and the bench."""
    if name in _REGISTRY:
        raise MrExploreError(f"strategy {name!r} is registered already; register it under another name")
    if name.endswith(NO_LOCAL_SUFFIX):
        raise MrExploreError(f"strategy names must not end in {NO_LOCAL_SUFFIX!r} (it removes the local layer)")
    _REGISTRY[name] = StrategySpec(name, factory, policy_kind, predictive)


def strategy_names() -> list[str]:
    """Every registered strategy, in the order registered."""
    return list(_REGISTRY)


def strategy_spec(name: str) -> StrategySpec:
    """The spec of ``name`` (a ``-nolocal`` suffix allowed); unknown names raise a one-line error listing
    the choices."""
    spec = _REGISTRY.get(name) or _REGISTRY.get(name.removesuffix(NO_LOCAL_SUFFIX))
    if spec is None:
        raise MrExploreError(f"unknown strategy {name!r}; choose one of {', '.join(_REGISTRY)}")
    return spec


def policy_for(name: str, policy: str | None) -> str | None:
    """The policy file strategy ``name`` runs, from a ``--policy`` value: ``FILE`` (for every learned
    strategy of the run) or ``KIND=FILE[,KIND=FILE]`` with KIND ``hier`` or ``ncm``; None: the shipped one.

    Examples
    --------
    >>> policy_for("ncm-sampled", "hier=a.npz,ncm=b.npz"), policy_for("hier", "ncm=b.npz"), policy_for("hier", "c.npz")
    ('b.npz', None, 'c.npz')
    """
    kind = strategy_spec(name).policy_kind
    if policy is None or kind is None:
        return None
    kinds = {s.policy_kind for s in _REGISTRY.values() if s.policy_kind is not None}
    parts = [p.partition("=") for p in policy.split(",")]
    if not all(sep and k in kinds for k, sep, _ in parts):
        return policy  # a plain path (it may hold '=' or ',' of its own)
    files = {k: v for k, _, v in parts}
    return files.get(kind) or None


def make_strategy(
    name: str,
    global_cfg: GlobalPlanningConfig | None = None,
    preprocess_cfg: PreprocessConfig | None = None,
    local_cfg: LocalPlanningConfig | None = None,
    local: bool = True,
    policy: str | None = None,
    coscan_cfg: CoScanConfig | None = None,
    predictor: str | None = None,
) -> ExplorationPipeline:
    """The pipeline called ``name``; unknown names raise a one-line error listing the choices.

    ``local=False`` (or a ``-nolocal`` suffix on the name) removes the local layer: robots go to cluster
    centres, for ablations; the pipeline's name then carries the suffix. ``policy`` is the weights file
    of a learned strategy, or ``KIND=FILE`` pairs (:func:`policy_for`; None: the policy shipped in the
    package); ``coscan_cfg`` sets CoScan-2D's task sampling and clustering.
    """
    spec = strategy_spec(name)
    local = local and name == spec.name
    cfgs = PipelineConfigs(
        global_cfg or GlobalPlanningConfig(),
        preprocess_cfg or PreprocessConfig(),
        local_cfg or LocalPlanningConfig(),
        coscan_cfg or CoScanConfig(),
        predictor,
    )
    pipeline = spec.factory(cfgs, policy_for(spec.name, policy))
    if not local and pipeline.local is not None:
        pipeline.local = None
        pipeline.name += NO_LOCAL_SUFFIX
    return pipeline


# -- the strategies shipped --------------------------------------------------------------------------------
CENTRE_COMMITMENT = 0.5
"""Default hysteresis of strategies whose goal is a cluster centre (measured on 6 maps x 2 seeds: utility
561 mean steps without, 414 with 0.5)."""


def _commitment(gp: GlobalPlanningConfig, default: float) -> float:
    return default if gp.commitment is None else gp.commitment


def _nearest(c: PipelineConfigs, policy: str | None) -> ExplorationPipeline:
    commitment = _commitment(c.global_, CENTRE_COMMITMENT)
    return ExplorationPipeline(
        "nearest", NearestPlanner(), c.preprocess, commitment=commitment, nearest_only=True, distances=c.global_
    )


def _utility(c: PipelineConfigs, policy: str | None) -> ExplorationPipeline:
    commitment = _commitment(c.global_, CENTRE_COMMITMENT)
    return ExplorationPipeline(
        "utility", UtilityPlanner(c.global_), c.preprocess, commitment=commitment, distances=c.global_
    )


def _hier_heuristic(c: PipelineConfigs, policy: str | None) -> ExplorationPipeline:
    # The paper's three layers with explore_lite's cost as the global affinity. No hysteresis by default: a
    # route already commits the robot to a sequence of targets (measured on 6 maps x 2 seeds: 442 mean
    # steps without, 480 with commitment 0.5).
    router = LocalRouter(c.local, c.preprocess)
    commitment = _commitment(c.global_, 1.0)
    return ExplorationPipeline(
        "hier-heuristic", UtilityPlanner(c.global_), c.preprocess, router, commitment, distances=c.global_
    )


NO_PREDICTOR = "none"
"""``--predictor none``: the predictive strategies take every unknown cell for free."""


def loaded_predictor(predictor: str | None) -> tuple[Any, dict[str, str]]:
    """The map predictor ``predictor`` names (a file; None: the shipped one; ``none``: no network) and what a
    mission's record says of it."""
    if predictor == NO_PREDICTOR:
        return None, {"path": NO_PREDICTOR, "sha256": ""}
    from mrexplore.prediction.network import load_predictor

    loaded = load_predictor(predictor)
    return loaded, loaded.describe()


def _hier_predict_heuristic(c: PipelineConfigs, policy: str | None) -> ExplorationPipeline:
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


INFERENCE_ENV = "MREXPLORE_INFERENCE"
"""``numpy`` (default): the learned strategies decide with the NumPy networks, no torch; ``torch``: with the
torch modules they were trained as (to compare the two, ``benchmarks/inference_parity.py``)."""


def _torch_inference() -> bool:
    value = os.environ.get(INFERENCE_ENV, "numpy")
    if value not in ("numpy", "torch"):
        raise MrExploreError(f"{INFERENCE_ENV}={value!r} is not an inference backend; set it to numpy or torch")
    return value == "torch"


def _loaded_policy(kind: str, policy: str | None) -> tuple[Any, dict[str, str]]:
    """The network of a learned strategy's policy file (``kind`` hier or ncm; None: the shipped one), NumPy's
    or torch's by :data:`INFERENCE_ENV`, and what a mission's record says of the file."""
    from pathlib import Path

    from mrexplore.global_planning.learned.policy_file import LoadedPolicy, load_ncm_policy_np, load_policy_np

    path = Path(policy) if policy else None
    loaded: LoadedPolicy[Any]
    if _torch_inference():
        from mrexplore.global_planning.learned.checkpoint import load_ncm_policy, load_policy

        loaded = load_policy(path) if kind == "hier" else load_ncm_policy(path)
    else:
        loaded = load_policy_np(path) if kind == "hier" else load_ncm_policy_np(path)
    info = {"path": str(loaded.path), "sha256": loaded.sha256, "code_version": str(loaded.meta["code_version"])}
    return loaded.net, info


def _hier(c: PipelineConfigs, policy: str | None) -> ExplorationPipeline:
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


def _hier_predict(c: PipelineConfigs, policy: str | None) -> ExplorationPipeline:
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


def _coscan(c: PipelineConfigs, policy: str | None) -> ExplorationPipeline:
    return CoScanPipeline("coscan", GeodesicPlanner(), c.preprocess, distances=c.global_, coscan=c.coscan)


def _oracle(c: PipelineConfigs, policy: str | None) -> ExplorationPipeline:
    return OraclePipeline("oracle", NearestPlanner(), c.preprocess, goals_are_frontiers=False, distances=c.global_)


register_strategy("hier", _hier, policy_kind="hier")
register_strategy("hier-heuristic", _hier_heuristic)
register_strategy("hier-predict-heuristic", _hier_predict_heuristic, predictive=True)
register_strategy("hier-predict", _hier_predict, policy_kind="hier", predictive=True)
register_strategy("nearest", _nearest)
register_strategy("utility", _utility)
register_strategy("coscan", _coscan)
register_strategy("ncm", _ncm("ncm"), policy_kind="ncm")
register_strategy("ncm-sampled", _ncm("ncm-sampled", sample=True), policy_kind="ncm")
register_strategy("ncm-matched", _ncm("ncm-matched", match=True), policy_kind="ncm")
register_strategy("oracle", _oracle)
