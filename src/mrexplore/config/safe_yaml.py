"""Reading YAML from users' files without surprises: plain data only, bounded size, no alias expansion."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import yaml

from mrexplore.types import MrExploreError

__all__ = ["load_yaml_text", "load_yaml_file", "MAX_YAML_BYTES"]

MAX_YAML_BYTES = 1 << 20
"""Largest YAML file read (a ROS map YAML or a config is a few hundred bytes)."""


def load_yaml_text(text: str, what: str) -> Any:
    """``yaml.safe_load(text)``, refusing aliases: a handful of nested aliases expand a small file beyond
    any memory ("billion laughs"), and no file of ours needs them. Errors are one line naming ``what``.

    Examples
    --------
    >>> load_yaml_text("a: [1, 2]", "x")
    {'a': [1, 2]}
    >>> try:
    ...     load_yaml_text("a: &x [1]\\nb: *x", "the file")
    ... except MrExploreError as exc:
    ...     print(exc)
    the file uses a YAML alias (*name); write the values out instead
    """
    try:
        for event in yaml.parse(text, Loader=yaml.SafeLoader):
            if isinstance(event, yaml.AliasEvent):
                raise MrExploreError(f"{what} uses a YAML alias (*name); write the values out instead")
        return yaml.safe_load(text)
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        at = f" at line {mark.line + 1}" if mark is not None else ""
        raise MrExploreError(f"{what} is not valid YAML{at}; fix it") from None
    except RecursionError:
        raise MrExploreError(f"{what} nests too deeply to be a config; fix it") from None


def load_yaml_file(path: Path, what: str, max_bytes: int = MAX_YAML_BYTES) -> Any:
    """The data of a YAML file of at most ``max_bytes`` (see :func:`load_yaml_text`)."""
    try:
        size = path.stat().st_size
        if size > max_bytes:
            raise MrExploreError(f"{what} is {size} bytes, over the {max_bytes}-byte limit of a YAML file")
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise MrExploreError(f"{what} cannot be read as UTF-8 text ({type(exc).__name__}); fix the path") from None
    return load_yaml_text(text, what)
