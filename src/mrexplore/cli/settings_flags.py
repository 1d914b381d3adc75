"""Flags derived from the settings schema: ``--config FILE``, ``--set SECTION.FIELD=VALUE`` for every setting,
and a short table of aliases for the common ones; type, range and help come from the declaration.

A new setting needs no edit here: ``--set`` reaches it, and ``mrexplore config`` documents it. An alias is one
line of :data:`ALIASES`; its flag means the same setting in every command that takes it.

Examples
--------
>>> p = argparse.ArgumentParser()
>>> add_settings_flags(p, ("--robots",))
>>> run = run_config(p.parse_args(["--robots", "4", "--set", "sim.sensor.range_m=8"]))
>>> run.sim.robots, run.sim.sensor.range_m
(4, 8.0)
"""

from __future__ import annotations

import argparse
import functools
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import Any

from mrexplore.config import (
    RunConfig,
    Setting,
    apply_runtime,
    parse_setting,
    read_config_file,
    settings_of,
    with_settings,
)
from mrexplore.config.safe_yaml import load_yaml_text
from mrexplore.types import MrExploreError

__all__ = ["Alias", "ALIASES", "MISSION_ALIASES", "add_settings_flags", "alias_given", "run_config", "setting_named"]


def _failure(text: str) -> tuple[int, int]:
    robot, _, step = text.partition("@")
    try:
        pair = (int(robot), int(step))
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be ROBOT@STEP (integers, e.g. 1@300), got {text!r}") from None
    if min(pair) < 0:
        raise argparse.ArgumentTypeError(f"must be ROBOT@STEP with both >= 0, got {text!r}")
    return pair


def _step(text: str) -> int:
    try:
        step = int(text)
    except ValueError:
        step = -1
    if step < 0:
        raise argparse.ArgumentTypeError(f"must be a step >= 0, got {text!r}")
    return step


@dataclass(frozen=True)
class Alias:
    """A flag that stands for one setting."""

    path: str
    """The setting, dotted from the run's settings: ``sim.robots``."""
    const: Any = None
    """A flag without a value that sets the setting to this (``--no-baseline-bytes``: False); None: takes a value."""
    item: Callable[[str], Any] | None = None
    """A repeatable flag: how one occurrence is read; the setting is the tuple of all of them."""
    metavar: str | None = None
    help: str = ""
    """Said before the setting's own documentation."""


ALIASES: dict[str, Alias] = {
    "--robots": Alias("sim.robots", metavar="N"),
    "--resolution": Alias("map.resolution_m", metavar="M"),
    "--pixel-size": Alias("map.pixel_size_m", metavar="M"),
    "--max-steps": Alias("mission.max_steps", metavar="N"),
    "--min-replan-steps": Alias("mission.min_replan_steps", metavar="N"),
    "--transmission": Alias("mission.transmission", metavar="delta|full"),
    "--no-baseline-bytes": Alias(
        "mission.baseline_bytes",
        const=False,
        help="leave Table II's int8-grid baselines uncounted (bytes_grid* empty): the same missions, a large "
        "floor's rounds much cheaper, for runs that want Table I alone.",
    ),
    "--commitment": Alias("global_planning.commitment", metavar="C"),
    "--message-loss": Alias("mission.faults.message_loss", metavar="P"),
    "--comm-range": Alias("mission.faults.comm_range_m", metavar="M"),
    "--robot-failure": Alias(
        "mission.faults.robot_failures", item=_failure, metavar="ID@STEP", help="robot ID stops at STEP (repeatable):"
    ),
    "--centre-restart": Alias(
        "mission.faults.centre_restarts", item=_step, metavar="STEP", help="the centre restarts at STEP (repeatable):"
    ),
}
"""The common settings' short flags; every other setting is ``--set SECTION.FIELD=VALUE``."""

MISSION_ALIASES = tuple(ALIASES)
"""The aliases of the commands that run missions (explore, bench, ros2 sim and launch)."""

_DEST = "setting:"
_ALIAS = "alias:"


@dataclass(frozen=True)
class _Parse:
    """An argparse type: a setting's value from a flag's text, by the setting's type and rule."""

    setting: Setting

    def __call__(self, text: str) -> Any:
        try:
            return parse_setting(self.setting, text)
        except MrExploreError as exc:
            raise argparse.ArgumentTypeError(str(exc)) from None


@functools.cache
def _settings() -> dict[str, Setting]:
    """Every setting of a run, by its dotted path (the defaults')."""
    return {s.path: s for s in settings_of(RunConfig())}


def setting_named(path: str) -> Setting:
    """The setting at a dotted path of the run's settings; one line naming the known ones where none is."""
    setting = _settings().get(path)
    if setting is None:
        raise MrExploreError(f"no setting {path}; 'mrexplore config' lists them")
    return setting


def _first_sentence(doc: str) -> str:
    head, dot, _ = doc.partition(". ")
    return head + ("." if dot or not head.endswith(".") else "")


def add_settings_flags(
    p: argparse.ArgumentParser, aliases: Iterable[str] = (), what: str = "", own: dict[str, Alias] | None = None
) -> None:
    """``--config``, ``--set``, the named aliases (keys of :data:`ALIASES`) and a command's ``own`` aliases
    (a flag that means another thing elsewhere) on parser ``p``."""
    p.add_argument(
        "--config",
        default=None,
        metavar="FILE",
        help="YAML file of settings ('mrexplore config' prints every one with its default)"
        + (f"; {what}" if what else ""),
    )
    p.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="SECTION.FIELD=VALUE",
        help="any setting 'mrexplore config' prints, e.g. --set sim.sensor.range_m=8 (repeatable; overrides --config)",
    )
    table = {**{flag: ALIASES[flag] for flag in aliases}, **(own or {})}
    for flag, alias in table.items():
        s = setting_named(alias.path)
        if alias.const is not None:
            p.set_defaults(**{_ALIAS + flag: alias})
            p.add_argument(
                flag,
                dest=_DEST + flag,
                action="store_const",
                const=alias.const,
                default=None,
                help=f"{alias.help} Sets {s.path} to {str(alias.const).lower()}.",
            )
            continue
        text = f"{alias.help} {_first_sentence(s.doc)}".strip()
        if s.rule is not None:
            text += f" Allowed: {s.rule.describe()}."
        text += f" Sets {s.path} (default {s.default_text})."
        dest = _DEST + flag
        p.set_defaults(**{_ALIAS + flag: alias})
        if alias.item is not None:
            p.add_argument(flag, dest=dest, type=alias.item, action="append", metavar=alias.metavar, help=text)
        else:
            p.add_argument(flag, dest=dest, type=_Parse(s), default=None, metavar=alias.metavar, help=text)


def alias_given(args: argparse.Namespace, flag: str) -> bool:
    """Whether the alias ``flag`` was given on the command line."""
    return getattr(args, _DEST + flag, None) is not None


def _set_value(item: str) -> tuple[str, Any]:
    """``(path, value)`` of a ``--set PATH=VALUE``: the value read by the setting's type where the path is a
    setting, as YAML otherwise (so that the settings, not this, name what is wrong, as for a YAML file)."""
    path, eq, text = item.partition("=")
    path = path.strip()
    if not eq or not path:
        raise MrExploreError(f"--set {item!r} must be SECTION.FIELD=VALUE, e.g. --set sim.sensor.range_m=8")
    setting = _settings().get(path)
    if setting is not None:
        try:
            return path, parse_setting(setting, text)
        except MrExploreError:
            pass  # the settings say what is wrong, in the words a YAML file gets
    try:
        return path, load_yaml_text(text, f"--set {item}")
    except MrExploreError:
        return path, text


def run_config(args: argparse.Namespace) -> RunConfig:
    """The settings of this run: the ``--config`` file (or the defaults), then ``--set``, then the aliases;
    a setting given twice on the command line is refused."""
    run = read_config_file(args.config) if getattr(args, "config", None) else RunConfig()
    values: dict[str, Any] = {}
    given_by: dict[str, str] = {}
    for item in getattr(args, "set", None) or []:
        path, value = _set_value(item)
        if path in given_by:
            raise MrExploreError(f"--set gives {path} twice; give it once")
        values[path], given_by[path] = value, f"--set {path}"
    for dest, value in vars(args).items():
        if not dest.startswith(_DEST) or value is None:
            continue
        flag = dest.removeprefix(_DEST)
        alias: Alias = getattr(args, _ALIAS + flag)
        path = alias.path
        if path in given_by:
            raise MrExploreError(f"{flag} and {given_by[path]} both set {path}; give it once")
        values[path] = tuple(value) if alias.item is not None else value
        given_by[path] = flag
    if values:
        try:
            run = with_settings(run, values)
        except MrExploreError as exc:
            culprit = next((p for p in given_by if str(exc).startswith(p) or f" {p}" in str(exc)), None)
            where = given_by[culprit] if culprit is not None else "--set"
            raise MrExploreError(f"{where}: {exc}") from None
    apply_runtime(run.runtime)
    return run
