"""Complete strategies: the centre's layers 1-3 as one pipeline, the seam through which a strategy supplies
its own candidates (CoScan-2D, NeuralCoMapping, the oracle), and the registry that names them.

The registry imports no strategy (naming and checking one is instant); the pipelines' classes are imported
from their modules at first use of their names here.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

from mrexplore.pipeline.registry import (
    NO_LOCAL_SUFFIX,
    TABLE_I,
    PipelineConfigs,
    StrategySpec,
    make_strategy,
    policy_for,
    register_strategy,
    strategy_for_run,
    strategy_names,
    strategy_spec,
)

if TYPE_CHECKING:
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

_LAZY = {
    "ExplorationPipeline": "base",
    "CoScanPipeline": "coscan",
    "NcmPipeline": "ncm",
    "OraclePipeline": "oracle",
    **{
        name: "decision"
        for name in (
            "NO_GOAL",
            "NO_ROUTE",
            "CandidateQuery",
            "CandidateSet",
            "Decision",
            "DecisionInput",
            "FarDistances",
            "PosedDecision",
            "PosedWork",
            "RobotField",
        )
    },
}


def __getattr__(name: str) -> Any:
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return getattr(importlib.import_module(f"{__name__}.{module}"), name)


__all__ = [
    "NO_GOAL",
    "NO_ROUTE",
    "NO_LOCAL_SUFFIX",
    "TABLE_I",
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
    "strategy_for_run",
    "strategy_names",
    "strategy_spec",
]
