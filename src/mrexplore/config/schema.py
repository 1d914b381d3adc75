"""The settings schema: a base class that checks any frozen settings dataclass from its own declaration.

A settings class declares each field once: its type (the annotation), its default, its documentation (the
string literal under it) and, where it has one, its allowed values (``_constraints``, scikit-learn's
``_parameter_constraints``). Everything else is read from that declaration: the checks on construction, the
YAML file that ``mrexplore config`` prints and ``--config`` reads, the command line's ``--set`` and flags, and
the ROS parameters. Nothing here knows which classes exist: any subclass of :class:`Checked`, in any module,
gets the same checks and the same words.

Examples
--------
>>> from dataclasses import dataclass
>>> @dataclass(frozen=True)
... class Lidar(Checked):
...     range_m: float = 6.0
...     '''Maximum range, metres.'''
...     _constraints = {"range_m": positive("metres")}
>>> Lidar(range_m=4).range_m  # an integer given for a float is a float
4.0
>>> try:
...     Lidar(range_m=-1.0)
... except MrExploreError as exc:
...     print(exc)
range_m must be > 0 metres, got -1.0
>>> from mrexplore.config import SensorConfig  # documentation is read from a class's source file
>>> field_docs(SensorConfig)["range_m"]
'Maximum range, metres (paper: 6 m).'
"""

from __future__ import annotations

import ast
import dataclasses
import inspect
import math
import numbers
import textwrap
import types
import typing
from collections.abc import Iterator
from dataclasses import asdict, dataclass, fields, is_dataclass
from typing import Any, ClassVar

from mrexplore.config.constraints import Constraint, Interval, Odd, OneOf, ZeroOr, at_least, non_negative, positive
from mrexplore.types import MrExploreError

__all__ = [
    "Checked",
    "Interval",
    "Odd",
    "ZeroOr",
    "OneOf",
    "Constraint",
    "Setting",
    "positive",
    "non_negative",
    "at_least",
    "require",
    "is_integer",
    "is_finite",
    "field_docs",
    "settings_of",
    "parse_setting",
    "with_settings",
    "config_from_dict",
    "config_to_dict",
    "config_yaml",
]


def require(ok: bool, name: str, rule: str, value: object) -> None:
    """Raise ``name must be rule, got value`` where ``ok`` is false."""
    if not ok:
        raise MrExploreError(f"{name} must be {rule}, got {value!r}")


class Checked:
    """Base of every settings class: checks each field's type (numbers finite, bools not taken for numbers,
    nested settings of their class) before the class's own range rules, so that a YAML file or a flag with
    the wrong kind of value gets the same one-line error as one out of range. An integer given for a float
    field is stored as a float, so ``6`` and ``6.0`` make equal settings."""

    _constraints: ClassVar[dict[str, Constraint]] = {}
    """Each field's allowed values (a field not named here takes any value of its type)."""

    _env: ClassVar[dict[str, str]] = {}
    """Fields an environment variable may set, by the variable's name (read where the setting is used)."""

    def __post_init__(self) -> None:
        hints = type_hints(type(self))
        for f in fields(self):  # type: ignore[arg-type]
            value = getattr(self, f.name)
            checked = _check_type(f.name, value, hints[f.name])
            if checked is not value:
                object.__setattr__(self, f.name, checked)
        self._validate()
        for name, rule in self._constraints.items():
            value = getattr(self, name)
            if value is None and rule.none is not None:
                continue
            require(value is not None and rule.holds(value, self), rule.name or name, rule.describe(self), value)

    def _validate(self) -> None:
        """Rules that are more than a field's range (normalising YAML's lists, for one)."""

    @classmethod
    def env_var(cls, name: str) -> str | None:
        """The environment variable that may set field ``name``, if any."""
        return next((var for var, field_name in cls._env.items() if field_name == name), None)


_HINTS: dict[type, dict[str, Any]] = {}
_DOCS: dict[type, dict[str, str]] = {}


def type_hints(cls: type) -> dict[str, Any]:
    """A settings class's field types, its string annotations resolved in its own module (once per class)."""
    if cls not in _HINTS:
        _HINTS[cls] = typing.get_type_hints(cls)
    return _HINTS[cls]


def _optional(hint: Any) -> tuple[Any, bool]:
    """``(T, True)`` for ``T | None``, ``(hint, False)`` otherwise."""
    if typing.get_origin(hint) in (types.UnionType, typing.Union):
        options = [a for a in typing.get_args(hint) if a is not type(None)]
        return options[0], len(options) < len(typing.get_args(hint))
    return hint, False


def _check_type(name: str, value: object, hint: Any) -> object:
    """``value`` checked against ``hint`` (an int given for a float becomes a float)."""
    hint, optional = _optional(hint)
    if optional and value is None:
        return value
    rule_none = " or None" if optional else ""
    if typing.get_origin(hint) is typing.Literal:
        hint = str
    if hint is float:
        require(is_finite(value), name, f"a finite number{rule_none}", value)
        return value if isinstance(value, float) else float(value)  # type: ignore[arg-type]
    if hint is int:
        require(is_integer(value), name, f"an integer{rule_none}", value)
    elif hint is bool:
        require(isinstance(value, bool), name, "true or false", value)
    elif hint is str:
        require(isinstance(value, str), name, f"a string{rule_none}", value)
    elif isinstance(hint, type) and is_dataclass(hint):
        require(isinstance(value, hint), name, f"a {hint.__name__}", value)
    # tuples: the class checks their items (and takes lists from YAML)
    return value


def is_finite(value: object) -> bool:
    """A real number that is neither NaN nor infinite (bools are refused: ``True`` is no distance)."""
    return isinstance(value, numbers.Real) and not isinstance(value, bool) and math.isfinite(value)


def is_integer(value: object) -> bool:
    """An integer, NumPy's included, but not a bool."""
    return isinstance(value, numbers.Integral) and not isinstance(value, bool)


def field_docs(cls: type) -> dict[str, str]:
    """``{field: its documentation}``, the string literal under each field in the class's source (and its
    bases'), whitespace collapsed; a field without one is left out (read once per class)."""
    if cls not in _DOCS:
        _DOCS[cls] = _read_docs(cls)
    return _DOCS[cls]


def _read_docs(cls: type) -> dict[str, str]:
    out: dict[str, str] = {}
    for klass in reversed(cls.__mro__):
        if not is_dataclass(klass):
            continue
        try:
            source = textwrap.dedent(inspect.getsource(klass))
        except (OSError, TypeError):  # defined where no source is kept (an interactive session)
            continue
        node = ast.parse(source).body[0]
        if not isinstance(node, ast.ClassDef):
            continue
        for a, b in zip(node.body, node.body[1:], strict=False):
            if (
                isinstance(a, ast.AnnAssign)
                and isinstance(a.target, ast.Name)
                and isinstance(b, ast.Expr)
                and isinstance(b.value, ast.Constant)
                and isinstance(b.value.value, str)
            ):
                out[a.target.id] = " ".join(b.value.value.split())
    return out


@dataclass(frozen=True)
class Setting:
    """One leaf setting of a settings tree: where it is and what its declaration says."""

    path: str
    """Dotted, from the root: ``sim.sensor.range_m``."""
    owner: type
    """The settings class that declares it."""
    name: str
    """The field's name in ``owner``."""
    hint: Any
    """The field's type."""
    default: Any
    """The value in the tree it was read from (the defaults, for a default tree)."""
    doc: str
    """The field's documentation."""
    rule: Constraint | None
    """Its allowed values, None where any value of its type is."""

    @property
    def env(self) -> str | None:
        """The environment variable that may set it, if any."""
        return self.owner.env_var(self.name)  # type: ignore[attr-defined]

    @property
    def default_text(self) -> str:
        """The value as the YAML file writes it (``null``, ``[]``, ``0.05``)."""
        return _yaml_scalar(self.default)


def settings_of(cfg: Any, prefix: str = "") -> Iterator[Setting]:
    """Every leaf setting of a settings tree, depth first in declaration order."""
    hints = type_hints(type(cfg))
    docs = field_docs(type(cfg))
    for f in fields(cfg):
        value = getattr(cfg, f.name)
        if is_dataclass(value):
            yield from settings_of(value, f"{prefix}{f.name}.")
        else:
            rule = type(cfg)._constraints.get(f.name)
            yield Setting(prefix + f.name, type(cfg), f.name, hints[f.name], value, docs.get(f.name, ""), rule)


def parse_setting(setting: Setting, text: str) -> Any:
    """The value of ``text`` for ``setting``, read by the field's type (a number as a number, ``null`` or
    ``none`` as None where allowed, a list as YAML); the field's own rule checked where it needs no other
    field. Raises :class:`MrExploreError` ``must be RULE, got 'TEXT'``."""
    from mrexplore.config.safe_yaml import load_yaml_text

    hint, optional = _optional(setting.hint)
    rule = setting.rule
    if optional and text.strip().lower() in ("null", "none", "~"):
        return None
    value: Any
    try:
        if hint is float:
            value = float(text)
        elif hint is int:
            value = int(text)
        elif hint is str or typing.get_origin(hint) is typing.Literal:
            value = text
        else:
            value = load_yaml_text(text, "the value")
    except (ValueError, MrExploreError):
        value = None
    kind = {float: "a number", int: "an integer", bool: "true or false", str: "text"}.get(hint, "a value")
    if rule is None:
        words = kind + (" or null" if optional else "")
    else:
        words = (f"{kind} " if isinstance(rule, Interval) else "") + rule.describe()
    try:
        if value is None:
            raise MrExploreError(kind)
        value = _check_type(setting.name, value, setting.hint)
    except MrExploreError:
        raise MrExploreError(f"must be {words}, got {text!r}") from None
    if rule is not None and rule.standalone and not rule.holds(value, None):
        raise MrExploreError(f"must be {words}, got {text!r}")
    return value


def with_settings(cfg: Any, values: dict[str, Any]) -> Any:
    """``cfg`` with each dotted setting of ``values`` replaced, checked as a YAML file's would be (an unknown
    name, or a value out of range, is the same one-line error).

    Examples
    --------
    >>> from mrexplore.config import RunConfig
    >>> with_settings(RunConfig(), {"sim.sensor.range_m": 4.0}).sim.sensor.range_m
    4.0
    >>> try:
    ...     with_settings(RunConfig(), {"sim.sensor.rang_m": 4.0})
    ... except MrExploreError as exc:
    ...     print(str(exc)[:55])
    unknown SensorConfig keys sim.sensor.rang_m; known: ran
    """
    data = config_to_dict(cfg)
    for path, value in values.items():
        keys = path.split(".")
        node = data
        for depth, key in enumerate(keys[:-1]):
            if key in node and not isinstance(node[key], dict):
                where = ".".join(keys[: depth + 1])
                raise MrExploreError(f"{where} is a setting, not a section; name it alone: {where}=VALUE")
            node = node.setdefault(key, {})
        if isinstance(node.get(keys[-1]), dict):
            raise MrExploreError(f"{path} is a section, not a setting; name one of its fields: {path}.FIELD=VALUE")
        node[keys[-1]] = value
    return config_from_dict(type(cfg), data)


def config_from_dict(cls: type[Any], data: dict[str, Any], where: str = "") -> Any:
    """Rebuild a settings dataclass from :func:`config_to_dict` output (nested settings too); unknown keys
    are refused by name (``where`` prefixes the names in messages, e.g. ``sim.``)."""
    if not isinstance(data, dict):
        raise MrExploreError(
            f"{where.rstrip('.') or 'the config'} must be a mapping of {cls.__name__} fields, got {data!r}"
        )
    names = {f.name: f for f in dataclasses.fields(cls)}
    unknown = sorted(str(k) for k in set(data) - set(names))
    if unknown:
        raise MrExploreError(
            f"unknown {cls.__name__} keys {', '.join(where + k for k in unknown)}; known: {', '.join(names)}"
        )
    hints = type_hints(cls)
    kwargs: dict[str, Any] = {}
    for k, v in data.items():
        sub = hints[k]
        if isinstance(sub, type) and dataclasses.is_dataclass(sub):
            kwargs[k] = config_from_dict(sub, v, f"{where}{k}.")
        else:
            kwargs[k] = v
    try:
        return cls(**kwargs)
    except MrExploreError as exc:
        raise MrExploreError(f"{where}{exc}" if where else str(exc)) from None


def config_to_dict(cfg: Any) -> dict[str, Any]:
    """Plain ``dict`` of a settings dataclass (nested), for result files and checkpoints."""
    return asdict(cfg)


def config_yaml(cfg: Any) -> str:
    """A settings tree as YAML, each field with its documentation, allowed values and environment variable
    as a comment: what ``mrexplore config`` prints and ``--config`` reads back (tuples written as lists)."""
    lines: list[str] = []

    def emit(obj: Any, indent: int) -> None:
        pad = "  " * indent
        docs = field_docs(type(obj))
        for f in fields(obj):
            value = getattr(obj, f.name)
            doc = docs.get(f.name, "")
            env = obj.env_var(f.name)
            if env is not None:
                doc = f"{doc} The environment variable {env} sets it where this file and the flags do not.".strip()
            rule = obj._constraints.get(f.name)
            if rule is not None:
                doc = f"{doc} Allowed: {rule.describe()}.".strip()
            if doc:
                lines.append(f"{pad}# {doc}")
            if is_dataclass(value):
                lines.append(f"{pad}{f.name}:")
                emit(value, indent + 1)
            else:
                lines.append(f"{pad}{f.name}: {_yaml_scalar(value)}")

    emit(cfg, 0)
    return "\n".join(lines) + "\n"


def _yaml_scalar(value: Any) -> str:
    import yaml

    plain = [list(v) if isinstance(v, tuple) else v for v in value] if isinstance(value, tuple) else value
    return str(yaml.safe_dump(plain, default_flow_style=True, width=10**6)).strip().removesuffix("...").strip()
