"""The built-in strategies' names, without importing them (what the command line checks before any work)."""

from __future__ import annotations

__all__ = ["BUILTIN_STRATEGIES", "TABLE_I", "check_strategy_name"]

BUILTIN_STRATEGIES = (
    "hier", "hier-heuristic", "hier-predict-heuristic", "hier-predict", "nearest", "utility", "coscan", "ncm",
    "ncm-sampled", "ncm-matched", "oracle",
)  # fmt: skip
"""In the order :mod:`mrexplore.pipeline.registry` registers them (a test holds the two together)."""
TABLE_I = ("hier", "hier-heuristic", "utility", "coscan", "nearest", "ncm", "oracle")
"""The strategies of the dev set's Table I."""


def check_strategy_name(name: str) -> None:
    """Raise the registry's one-line error for a name that is no built-in strategy (a ``-nolocal`` suffix
    allowed), before the strategies themselves are imported.

    Examples
    --------
    >>> check_strategy_name("hier-nolocal")
    >>> check_strategy_name("heir")
    Traceback (most recent call last):
    mrexplore.types.MrExploreError: unknown strategy 'heir'; choose one of hier, ...
    """
    from mrexplore.types import MrExploreError

    if name.removesuffix("-nolocal") not in BUILTIN_STRATEGIES:
        raise MrExploreError(f"unknown strategy {name!r}; choose one of {', '.join(BUILTIN_STRATEGIES)}")
