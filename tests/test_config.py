"""Settings: each field's constraint, declared once, both refuses a bad value and documents the field."""

from __future__ import annotations

import dataclasses
import re

import pytest

from mrexplore.config import (
    EpisodesConfig,
    GlobalPlanningConfig,
    PreprocessConfig,
    RunConfig,
    SensorConfig,
    TrainConfig,
    config_yaml,
)
from mrexplore.types import MrExploreError


@pytest.mark.parametrize(
    ("make", "message"),
    [
        (lambda: SensorConfig(p_hit=1.0), "p_hit must be in (0.5, 1), got 1.0"),
        (lambda: SensorConfig(range_m=0.0), "range_m must be > 0 metres, got 0.0"),
        (lambda: PreprocessConfig(closing_size_cells=2), "closing_size_cells must be odd and >= 1, got 2"),
        (lambda: GlobalPlanningConfig(portal_sector_blocks=1), "portal_sector_blocks must be 0 or >= 2, got 1"),
        (lambda: EpisodesConfig(robots_min=3, robots_max=2), "robots_max must be >= robots_min (3), got 2"),
        (lambda: TrainConfig(search_elites=9), "search_elites must be in [1, search_population (8)], got 9"),
        (lambda: EpisodesConfig(plans="grid"), "plans must be 'varied' or 'generated', got 'grid'"),
    ],
)
def test_a_value_outside_its_constraint_is_refused_in_words(make, message) -> None:
    with pytest.raises(MrExploreError) as err:
        make()
    assert str(err.value) == message


def test_edges_of_intervals_follow_their_brackets() -> None:
    assert SensorConfig(p_miss=0.25).p_miss == 0.25
    GlobalPlanningConfig(commitment=0.0), GlobalPlanningConfig(commitment=1.0), GlobalPlanningConfig(commitment=None)
    PreprocessConfig(bandwidth_percentile=100.0)  # (0, 100]
    with pytest.raises(MrExploreError, match=r"bandwidth_percentile must be in \(0, 100\], got 0.0"):
        PreprocessConfig(bandwidth_percentile=0.0)


def _configs(cfg: object) -> list[object]:
    """A config and every config nested in it."""
    out = [cfg]
    for f in dataclasses.fields(cfg):  # type: ignore[arg-type]
        value = getattr(cfg, f.name)
        if dataclasses.is_dataclass(value):
            out += _configs(value)
    return out


def test_mrexplore_config_documents_every_constraint_from_its_declaration() -> None:
    text = config_yaml(RunConfig())
    for cfg in _configs(RunConfig()):
        for name, rule in type(cfg)._constraints.items():  # type: ignore[attr-defined]
            assert re.search(rf"Allowed: {re.escape(rule.describe())}\.\n *{name}: ", text), name
    assert "# P(occupied | beam ends in cell) (OctoMap's default). Allowed: in (0.5, 1)." in text
    assert "Allowed: >= robots_min." in text  # a bound that is another field, by name
