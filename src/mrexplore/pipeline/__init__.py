"""Complete strategies: the centre's layers 1-3 as one pipeline, the seam through which a strategy supplies
its own candidates (CoScan-2D, NeuralCoMapping, the oracle), and the registry that names them."""

from mrexplore.pipeline.base import ExplorationPipeline
from mrexplore.pipeline.coscan import CoScanPipeline
from mrexplore.pipeline.decision import (
    NO_GOAL,
    NO_ROUTE,
    CandidateQuery,
    CandidateSet,
    Decision,
    DecisionInput,
    FarDistances,
    PosedDecision,
    PosedWork,
    RobotField,
)
from mrexplore.pipeline.ncm import NcmPipeline
from mrexplore.pipeline.oracle import OraclePipeline
from mrexplore.pipeline.registry import (
    NO_LOCAL_SUFFIX,
    PipelineConfigs,
    StrategySpec,
    make_strategy,
    policy_for,
    register_strategy,
    strategy_names,
    strategy_spec,
)

__all__ = [
    "NO_GOAL",
    "NO_ROUTE",
    "NO_LOCAL_SUFFIX",
    "CandidateQuery",
    "CandidateSet",
    "CoScanPipeline",
    "Decision",
    "DecisionInput",
    "ExplorationPipeline",
    "FarDistances",
    "NcmPipeline",
    "OraclePipeline",
    "PipelineConfigs",
    "PosedDecision",
    "PosedWork",
    "RobotField",
    "StrategySpec",
    "make_strategy",
    "policy_for",
    "register_strategy",
    "strategy_names",
    "strategy_spec",
]
