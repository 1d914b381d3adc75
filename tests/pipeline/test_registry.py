"""The strategy registry: names, the -nolocal suffix, policy files per kind, registering a new strategy."""

from __future__ import annotations

import pytest

from mrexplore.pipeline import make_strategy, register_strategy, strategy_names, strategy_spec
from mrexplore.pipeline.registry import _REGISTRY
from mrexplore.types import MrExploreError


def test_the_shipped_strategies_in_their_order() -> None:
    assert strategy_names() == [
        "hier", "hier-heuristic", "hier-predict-heuristic", "hier-predict", "hier-plan", "team-plan", "hier-search",
        "nearest", "utility", "coscan", "ncm", "ncm-sampled", "ncm-matched", "oracle",
    ]  # fmt: skip
    assert [strategy_spec(n).policy_kind for n in ("hier", "hier-nolocal", "ncm-matched", "utility")] == [
        "hier",
        "hier",
        "ncm",
        None,
    ]


def test_unknown_names_are_refused_with_the_choices() -> None:
    with pytest.raises(MrExploreError, match=r"^unknown strategy 'heir'; choose one of hier, hier-heuristic, "):
        make_strategy("heir")
    with pytest.raises(MrExploreError, match=r"^unknown strategy 'heir-nolocal'"):
        make_strategy("heir-nolocal")


def test_nolocal_removes_the_local_layer_only_where_there_is_one() -> None:
    assert make_strategy("hier-heuristic-nolocal").name == "hier-heuristic-nolocal"
    assert make_strategy("hier-heuristic-nolocal").local is None
    assert make_strategy("utility", local=False).name == "utility"  # no local layer to remove


def test_a_registered_strategy_is_made_by_name_and_names_are_unique() -> None:
    def quiet_utility(cfgs, policy):
        pipeline = make_strategy("utility", cfgs.global_, cfgs.preprocess)
        pipeline.name = "quiet"
        return pipeline

    register_strategy("quiet", quiet_utility)
    try:
        assert make_strategy("quiet").name == "quiet" and "quiet" in strategy_names()
        with pytest.raises(MrExploreError, match=r"^strategy 'quiet' is registered already"):
            register_strategy("quiet", quiet_utility)
        with pytest.raises(MrExploreError, match=r"must not end in '-nolocal'"):
            register_strategy("loud-nolocal", quiet_utility)
    finally:
        del _REGISTRY["quiet"]
