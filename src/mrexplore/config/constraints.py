"""The allowed values of a setting, declared once per class (scikit-learn's ``_parameter_constraints``):
validation, ``mrexplore config``'s documentation and the command line's checks all read them.

Examples
--------
>>> rule = Interval(0, 1, "left")
>>> rule.holds(0.0, None), rule.holds(1.0, None), rule.describe()
(True, False, 'in [0, 1)')
>>> at_least("robots_min").describe()
'>= robots_min'
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar

__all__ = ["Bound", "Interval", "Odd", "ZeroOr", "OneOf", "Constraint", "positive", "non_negative", "at_least"]

Bound = float | str
"""A number, or the name of another field of the same settings (its value is the bound)."""


@dataclass(frozen=True)
class Interval:
    """Numbers between ``low`` and ``high`` (None: unbounded); ``closed``: which ends belong to it."""

    low: Bound | None = None
    high: Bound | None = None
    closed: str = "both"
    """``both``, ``left``, ``right`` or ``neither``."""
    unit: str = ""
    """Named after the bounds in messages and documentation (``metres``)."""
    none: str | None = None
    """Where the field may be None: what None means (``""``: nothing to say); None: not allowed."""
    name: str | None = None
    """The name messages give the field where it differs from the field's."""

    def _bound(self, b: Bound | None, cfg: object) -> float | None:
        return float(getattr(cfg, b)) if isinstance(b, str) else b

    @property
    def standalone(self) -> bool:
        """Whether the rule can be checked without the other fields (no bound names a field)."""
        return not (isinstance(self.low, str) or isinstance(self.high, str))

    def holds(self, value: Any, cfg: object) -> bool:
        lo, hi = self._bound(self.low, cfg), self._bound(self.high, cfg)
        left, right = self.closed in ("both", "left"), self.closed in ("both", "right")
        return (lo is None or (value >= lo if left else value > lo)) and (
            hi is None or (value <= hi if right else value < hi)
        )

    def describe(self, cfg: object | None = None) -> str:
        """``> 0 metres``, ``in [0, 1)``, ``>= robots_min (2)``: the rule in words."""

        def show(b: Bound | None) -> str:
            if isinstance(b, str):
                return f"{b} ({getattr(cfg, b)})" if cfg is not None else b
            return f"{b:g}"

        left, right = self.closed in ("both", "left"), self.closed in ("both", "right")
        if self.high is None:
            text = f"{'>=' if left else '>'} {show(self.low)}"
        elif self.low is None:
            text = f"{'<=' if right else '<'} {show(self.high)}"
        else:
            text = f"in {'[' if left else '('}{show(self.low)}, {show(self.high)}{']' if right else ')'}"
        return text + (f" {self.unit}" if self.unit else "") + _none_text(self.none)


@dataclass(frozen=True)
class Odd(Interval):
    """Odd integers of an interval."""

    def holds(self, value: Any, cfg: object) -> bool:
        return value % 2 == 1 and super().holds(value, cfg)

    def describe(self, cfg: object | None = None) -> str:
        return "odd and " + super().describe(cfg)


@dataclass(frozen=True)
class ZeroOr(Interval):
    """0, or a number of an interval."""

    def holds(self, value: Any, cfg: object) -> bool:
        return value == 0 or super().holds(value, cfg)

    def describe(self, cfg: object | None = None) -> str:
        return "0 or " + super().describe(cfg)


@dataclass(frozen=True)
class OneOf:
    """One of a few words."""

    options: tuple[str, ...]
    name: str | None = None
    none: str | None = None
    standalone: ClassVar[bool] = True

    def holds(self, value: Any, cfg: object) -> bool:
        return value in self.options

    def describe(self, cfg: object | None = None) -> str:
        words = [repr(o) for o in self.options]
        return (", ".join(words[:-1]) + " or " + words[-1] if len(words) > 1 else words[0]) + _none_text(self.none)


Constraint = Interval | OneOf


def _none_text(none: str | None) -> str:
    return "" if none is None else ", or null" + (f" for {none}" if none else "")


def positive(unit: str = "", **kw: Any) -> Interval:
    """Numbers > 0."""
    return Interval(0, None, "neither", unit, **kw)


def non_negative(unit: str = "", **kw: Any) -> Interval:
    """Numbers >= 0."""
    return Interval(0, None, "left", unit, **kw)


def at_least(low: Bound, **kw: Any) -> Interval:
    """Numbers >= ``low`` (a number or another field's name)."""
    return Interval(low, None, "left", **kw)
