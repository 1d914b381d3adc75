"""Typed, frozen settings: one dataclass per part, each field with its type, unit, range and documentation,
checked on construction (:mod:`~mrexplore.config.schema`), one module per area.

Every settings class raises :class:`~mrexplore.types.MrExploreError` with the parameter name, the value
received and the allowed range, e.g. ``robots must be >= 1, got 0``. The YAML file of ``--config``, the
command line's ``--set`` and flags, ``mrexplore config`` and the ROS parameters are all derived from them.
"""

from mrexplore.config.mission import FaultConfig, MissionConfig
from mrexplore.config.planning import (
    CoScanConfig,
    GlobalPlanningConfig,
    LearnedConfig,
    LocalPlanningConfig,
    PreprocessConfig,
)
from mrexplore.config.run import (
    CONFIG_HEADER,
    RunConfig,
    RuntimeConfig,
    apply_runtime,
    read_config_file,
    runtime_from_env,
    runtime_value,
)
from mrexplore.config.schema import (
    Checked,
    Setting,
    config_from_dict,
    config_to_dict,
    config_yaml,
    field_docs,
    parse_setting,
    settings_of,
    with_settings,
)
from mrexplore.config.training import TRAINABLE, EpisodesConfig, NcmTrainConfig, PredictorTrainConfig, TrainConfig
from mrexplore.config.world import GridThresholds, MapConfig, MotionConfig, RewardConfig, SensorConfig, SimConfig

__all__ = [
    "MapConfig",
    "GridThresholds",
    "SensorConfig",
    "MotionConfig",
    "SimConfig",
    "RewardConfig",
    "PreprocessConfig",
    "GlobalPlanningConfig",
    "LocalPlanningConfig",
    "CoScanConfig",
    "FaultConfig",
    "MissionConfig",
    "LearnedConfig",
    "EpisodesConfig",
    "TrainConfig",
    "NcmTrainConfig",
    "PredictorTrainConfig",
    "TRAINABLE",
    "RuntimeConfig",
    "RunConfig",
    "CONFIG_HEADER",
    "Checked",
    "Setting",
    "settings_of",
    "field_docs",
    "parse_setting",
    "with_settings",
    "apply_runtime",
    "runtime_from_env",
    "runtime_value",
    "config_to_dict",
    "config_from_dict",
    "config_yaml",
    "read_config_file",
]
