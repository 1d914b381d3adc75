"""Every setting of a run in one tree (the YAML file of ``--config``), and how this process runs."""

from __future__ import annotations

import dataclasses
import functools
import os
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Any

from mrexplore.config.mission import MissionConfig
from mrexplore.config.planning import CoScanConfig, GlobalPlanningConfig, LocalPlanningConfig, PreprocessConfig
from mrexplore.config.schema import Checked, at_least, config_from_dict, parse_setting, settings_of
from mrexplore.config.training import PredictorTrainConfig, TrainConfig
from mrexplore.config.world import MapConfig, SimConfig
from mrexplore.types import MrExploreError

__all__ = [
    "RuntimeConfig",
    "RunConfig",
    "read_config_file",
    "runtime_from_env",
    "runtime_value",
    "apply_runtime",
    "CONFIG_HEADER",
]

CONFIG_HEADER = (
    "mrexplore settings: every field with its default. Keep the lines you change, pass the file with "
    "--config FILE to explore, bench, train or a ros2 command; --set SECTION.FIELD=VALUE and the flags override it."
)


@dataclass(frozen=True)
class RuntimeConfig(Checked):
    """How this process runs: none of it changes a mission's result. Each field may also come from an
    environment variable (read where the setting is used, and handed to worker processes the same way);
    None leaves it to that variable, else to the default named."""

    threads: int | None = None
    """Threads of the shared pool that runs the work releasing the GIL (beam casting, distance fields, the map
    predictor beside a decision); None: one per core. The benchmark's and training's worker processes run one
    thread each."""
    maps_dir: str | None = None
    """Folder of the example maps (the dev maps; the training maps in its ``train/``); None: ``../shared/maps``
    from the working directory."""

    _constraints = {
        "threads": at_least(1, none="one per core"),
    }
    _env = {"MREXPLORE_THREADS": "threads", "MREXPLORE_MAPS": "maps_dir"}


_RUNTIME_VARS = {name: var for var, name in RuntimeConfig._env.items()}
"""Each runtime setting's environment variable."""


def runtime_from_env() -> RuntimeConfig:
    """The runtime settings the environment variables give (each unset one None); one line naming the
    variable where one holds a value its setting refuses.

    Examples
    --------
    >>> os.environ["MREXPLORE_THREADS"] = "2"
    >>> runtime_from_env().threads
    2
    >>> os.environ["MREXPLORE_THREADS"] = "0"
    >>> try:
    ...     runtime_from_env()
    ... except MrExploreError as exc:
    ...     print(exc)
    MREXPLORE_THREADS must be an integer >= 1, got '0'; unset it for the default
    >>> del os.environ["MREXPLORE_THREADS"]
    """
    return RuntimeConfig(**{f.name: runtime_value(f.name) for f in fields(RuntimeConfig)})


def runtime_value(name: str) -> Any:
    """One runtime setting as its environment variable gives it now (None where unset), checked as
    :func:`runtime_from_env` checks it; cheap enough for every call of the code that reads it."""
    return _parsed_env(name, os.environ.get(_RUNTIME_VARS[name], ""))


@functools.lru_cache(maxsize=64)
def _parsed_env(name: str, text: str) -> Any:
    if not text:
        return None
    setting = next(s for s in settings_of(RuntimeConfig()) if s.name == name)
    if setting.rule is not None:  # "null" is no word for a variable: unset, it gives the default
        setting = dataclasses.replace(setting, rule=dataclasses.replace(setting.rule, none=None))
    try:
        return parse_setting(setting, text)
    except MrExploreError as exc:
        raise MrExploreError(f"{setting.env} {exc}; unset it for the default") from None


def apply_runtime(runtime: RuntimeConfig) -> None:
    """Make the runtime settings given (those not None) hold in this process and the workers it starts: each
    goes to its environment variable, where the code that uses it reads it."""
    for f in fields(runtime):
        value = getattr(runtime, f.name)
        if value is not None:
            os.environ[_RUNTIME_VARS[f.name]] = str(value)


@dataclass(frozen=True)
class RunConfig(Checked):
    """Every setting of a run, one section per part: the YAML file that ``--config`` reads on explore,
    bench, train and the ros2 commands (``mrexplore config`` prints the defaults). A section or field left out
    keeps its default; ``--set`` and the flags given on the command line override the file."""

    map: MapConfig = field(default_factory=MapConfig)
    sim: SimConfig = field(default_factory=SimConfig)
    mission: MissionConfig = field(default_factory=MissionConfig)
    preprocess: PreprocessConfig = field(default_factory=PreprocessConfig)
    global_planning: GlobalPlanningConfig = field(default_factory=GlobalPlanningConfig)
    local_planning: LocalPlanningConfig = field(default_factory=LocalPlanningConfig)
    coscan: CoScanConfig = field(default_factory=CoScanConfig)
    train: TrainConfig = field(default_factory=TrainConfig)
    """Training only (``mrexplore train``), which also reads ``sim`` and ``mission`` (its faults and
    replanning; the step budget is ``train.episodes.max_steps``)."""
    predictor: PredictorTrainConfig = field(default_factory=PredictorTrainConfig)
    """The map predictor's training only (``mrexplore train --target predictor``), which also reads ``sim``."""
    runtime: RuntimeConfig = field(default_factory=RuntimeConfig)
    """How this process runs (threads, the maps' folder); no result depends on it."""


def read_config_file(path: str | Path, max_bytes: int = 1 << 20) -> RunConfig:
    """The :class:`RunConfig` of a YAML file; any problem is one :class:`MrExploreError` naming the file.

    Only plain YAML is read (no tags, no aliases), at most ``max_bytes``."""
    from mrexplore.config.safe_yaml import load_yaml_file

    p = Path(path)
    if not p.is_file():
        raise MrExploreError(f"--config file {p} not found; 'mrexplore config > {p.name}' writes the defaults")
    data = load_yaml_file(p, f"--config file {p}", max_bytes)
    if data is None:
        return RunConfig()
    try:
        return config_from_dict(RunConfig, data)
    except MrExploreError as exc:
        raise MrExploreError(f"--config file {p}: {exc}") from None
