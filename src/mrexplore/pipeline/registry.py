"""Named strategies, each a complete pipeline, registered and made by name in the manner of Gymnasium's
``register`` / ``make``: the CLI, the bench and the trainer only ever name a strategy. A strategy is registered
by its factory's import path (``module:attribute``), imported only when the strategy is made, so that naming
and checking strategies imports none of them.

Examples
--------
>>> from mrexplore.pipeline import make_strategy, strategy_names
>>> make_strategy("utility").name, "hier" in strategy_names()
('utility', True)
>>> make_strategy("hier-heuristic", local=False).name
'hier-heuristic-nolocal'
"""

from __future__ import annotations

import importlib
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from mrexplore.config import CoScanConfig, GlobalPlanningConfig, LocalPlanningConfig, PreprocessConfig, SimConfig
from mrexplore.types import MrExploreError

if TYPE_CHECKING:
    from mrexplore.pipeline.base import ExplorationPipeline

__all__ = [
    "NO_LOCAL_SUFFIX",
    "PipelineConfigs",
    "StrategySpec",
    "register_strategy",
    "strategy_spec",
    "strategy_names",
    "make_strategy",
    "strategy_for_run",
    "policy_for",
    "NO_PREDICTOR",
    "TABLE_I",
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
    """The map predictor of the predictive strategies: a file written by ``mrexplore train --target predictor``,
    ``none`` (every unknown cell free) or None (the shipped one)."""
    sim: SimConfig = field(default_factory=SimConfig)
    """The robots' sensor and motion, for a strategy that simulates ahead (``hier-search``; a mission gives its
    own through :meth:`~mrexplore.pipeline.base.ExplorationPipeline.prepare`)."""


Factory = Callable[[PipelineConfigs, "str | None"], "ExplorationPipeline"]
"""Builds a strategy's pipeline from its settings and a policy file (None: the shipped one, or no network)."""

NO_PREDICTOR = "none"
"""``--predictor none``: the predictive strategies take every unknown cell for free."""

TABLE_I = ("hier", "hier-heuristic", "utility", "coscan", "nearest", "ncm", "oracle")
"""The strategies of the dev set's Table I."""


@dataclass(frozen=True)
class StrategySpec:
    """A registered strategy."""

    name: str
    factory: Factory | str
    """The factory, or its import path ``module:attribute`` (imported when the strategy is first made)."""
    policy_kind: str | None = None
    """The kind of policy file a learned strategy reads (``hier`` or ``ncm``, which ``--policy KIND=FILE``
    names); None: no network."""
    predictive: bool = False
    """The strategy reads a map predictor (``--predictor``)."""


_REGISTRY: dict[str, StrategySpec] = {}


def register_strategy(
    name: str, factory: Factory | str, policy_kind: str | None = None, predictive: bool = False
) -> None:
    """Make ``factory``'s pipeline (a callable, or its import path ``module:attribute``) available as ``name``
    to :func:`make_strategy`, the CLI and the bench."""
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


def _factory(spec: StrategySpec) -> Factory:
    if callable(spec.factory):
        return spec.factory
    module, _, attribute = spec.factory.partition(":")
    factory: Factory = getattr(importlib.import_module(module), attribute)
    return factory


def make_strategy(
    name: str,
    global_cfg: GlobalPlanningConfig | None = None,
    preprocess_cfg: PreprocessConfig | None = None,
    local_cfg: LocalPlanningConfig | None = None,
    local: bool = True,
    policy: str | None = None,
    coscan_cfg: CoScanConfig | None = None,
    predictor: str | None = None,
    sim_cfg: SimConfig | None = None,
) -> ExplorationPipeline:
    """The pipeline called ``name``; unknown names raise a one-line error listing the choices.

    ``local=False`` (or a ``-nolocal`` suffix on the name) removes the local layer: robots go to cluster
    centres, for ablations; the pipeline's name then carries the suffix. ``policy`` is the weights file
    of a learned strategy, or ``KIND=FILE`` pairs (:func:`policy_for`; None: the policy shipped in the
    package); ``coscan_cfg`` sets CoScan-2D's task sampling and clustering; ``sim_cfg`` the robots' sensor and
    motion a strategy that simulates ahead assumes.
    """
    spec = strategy_spec(name)
    local = local and name == spec.name
    cfgs = PipelineConfigs(
        global_cfg or GlobalPlanningConfig(),
        preprocess_cfg or PreprocessConfig(),
        local_cfg or LocalPlanningConfig(),
        coscan_cfg or CoScanConfig(),
        predictor,
        sim_cfg or SimConfig(),
    )
    pipeline = _factory(spec)(cfgs, policy_for(spec.name, policy))
    if not local and pipeline.local is not None:
        pipeline.local = None
        pipeline.name += NO_LOCAL_SUFFIX
    return pipeline


def strategy_for_run(
    name: str, run: Any, local: bool = True, policy: str | None = None, predictor: str | None = None
) -> ExplorationPipeline:
    """The strategy ``name`` with a run's settings (a :class:`~mrexplore.config.RunConfig`): what
    ``mrexplore explore``, the bench and the ROS 2 centre run."""
    return make_strategy(
        name,
        run.global_planning,
        run.preprocess,
        run.local_planning,
        local=local,
        policy=policy,
        coscan_cfg=run.coscan,
        predictor=predictor,
        sim_cfg=run.sim,
    )


# -- the strategies shipped (their factories: :mod:`mrexplore.pipeline.strategies`) ---------------------------
_SHIPPED = "mrexplore.pipeline.strategies:"
register_strategy("hier", _SHIPPED + "hier", policy_kind="hier")
register_strategy("hier-heuristic", _SHIPPED + "hier_heuristic")
register_strategy("hier-predict-heuristic", _SHIPPED + "hier_predict_heuristic", predictive=True)
register_strategy("hier-predict", _SHIPPED + "hier_predict", policy_kind="hier", predictive=True)
register_strategy("hier-plan", _SHIPPED + "hier_plan", policy_kind="hier")
register_strategy("team-plan", _SHIPPED + "team_plan")
# The search runs missions ahead: its factory lives in the mission layer, named here by its path only.
register_strategy("hier-search", "mrexplore.mission.search:hier_search", policy_kind="hier")
register_strategy("nearest", _SHIPPED + "nearest")
register_strategy("utility", _SHIPPED + "utility")
register_strategy("coscan", _SHIPPED + "coscan")
register_strategy("ncm", _SHIPPED + "ncm", policy_kind="ncm")
register_strategy("ncm-sampled", _SHIPPED + "ncm_sampled", policy_kind="ncm")
register_strategy("ncm-matched", _SHIPPED + "ncm_matched", policy_kind="ncm")
register_strategy("oracle", _SHIPPED + "oracle")
