"""Every setting reaches the command line from its declaration: ``--set`` for all of them, aliases for the
common ones, the same one-line error as a YAML file's, and a mission that runs with what was set."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from mrexplore.cli import main
from mrexplore.cli.settings_flags import ALIASES, setting_named
from mrexplore.config import RunConfig, settings_of
from mrexplore.config.schema import _yaml_scalar

FAST = ["--map", "generated:3", "--robots", "2", "--resolution", "0.2", "--max-steps", "400"]


def _run_of(argv: list[str]) -> RunConfig:
    from mrexplore.cli.main import build_parser
    from mrexplore.cli.settings_flags import run_config

    return run_config(build_parser().parse_args(["explore", *argv]))


@pytest.mark.parametrize("setting", list(settings_of(RunConfig())), ids=lambda s: s.path)
def test_every_setting_mrexplore_config_prints_can_be_set(setting, monkeypatch) -> None:
    """Each line of ``mrexplore config`` given back as ``--set PATH=VALUE`` (the value as that file writes
    it) makes the same settings: every setting is reachable, and its text read by its type."""
    for var in ("MREXPLORE_THREADS", "MREXPLORE_MAPS"):
        monkeypatch.delenv(var, raising=False)  # runtime settings are handed on to the environment
    run = _run_of(["--set", f"{setting.path}={_yaml_scalar(setting.default)}"])
    assert run == RunConfig()


def test_set_changes_nested_settings_and_aliases_name_one_setting() -> None:
    run = _run_of(
        ["--set", "sim.sensor.range_m=4", "--set", "mission.faults.centre_restarts=[10, 20]", "--robots", "5"]
    )
    assert run.sim.sensor.range_m == 4.0 and isinstance(run.sim.sensor.range_m, float)
    assert run.mission.faults.centre_restarts == (10, 20) and run.sim.robots == 5
    assert _run_of(["--set", "global_planning.commitment=null"]).global_planning.commitment is None
    assert _run_of(["--set", "train.learned.hidden=16"]).train.learned.hidden == 16
    for flag, alias in ALIASES.items():  # every alias stands for a declared setting
        assert setting_named(alias.path).path == alias.path, flag


def _error(capsys) -> str:
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err
    return err.removeprefix("mrexplore: error: ").rstrip("\n")


@pytest.mark.parametrize(
    ("yaml_text", "item"),
    [
        ("sim:\n  sensor:\n    rang_m: 8\n", "sim.sensor.rang_m=8"),
        ("sim:\n  sensor:\n    range_m: eight\n", "sim.sensor.range_m=eight"),
        ("sim:\n  sensor:\n    range_m: -1\n", "sim.sensor.range_m=-1"),
        ("preprocess:\n  closing_size_cells: 2\n", "preprocess.closing_size_cells=2"),
        ("mission:\n  transmission: half\n", "mission.transmission=half"),
    ],
)
def test_a_wrong_set_gives_the_yaml_file_s_error(tmp_path: Path, capsys, yaml_text: str, item: str) -> None:
    (tmp_path / "bad.yaml").write_text(yaml_text)
    assert main(["explore", *FAST, "--config", str(tmp_path / "bad.yaml")]) == 2
    from_file = _error(capsys).removeprefix(f"--config file {tmp_path / 'bad.yaml'}: ")
    assert main(["explore", *FAST, "--set", item]) == 2
    assert _error(capsys) == f"--set {item.partition('=')[0]}: {from_file}"


def test_set_refuses_a_section_a_malformed_item_and_a_setting_given_twice(capsys) -> None:
    assert main(["explore", *FAST, "--set", "sim.sensor=4"]) == 2
    assert (
        _error(capsys)
        == "--set sim.sensor: sim.sensor is a section, not a setting; name one of its fields: sim.sensor.FIELD=VALUE"
    )
    assert main(["explore", *FAST, "--set", "sim.robots"]) == 2
    assert _error(capsys) == "--set 'sim.robots' must be SECTION.FIELD=VALUE, e.g. --set sim.sensor.range_m=8"
    assert main(["explore", *FAST, "--set", "sim.robots=3"]) == 2
    assert _error(capsys) == "--robots and --set sim.robots both set sim.robots; give it once"


def test_a_mission_explores_with_what_set_gives(capsys) -> None:
    """``--set sim.sensor.range_m=4`` explores with a 4 m sensor: the record holds it, and the mission differs
    from the default 6 m one on the same map, seed and starts."""
    assert main(["explore", *FAST, "--json", "--no-progress"]) == 0
    default = json.loads(capsys.readouterr().out)
    assert main(["explore", *FAST, "--set", "sim.sensor.range_m=4", "--json", "--no-progress"]) == 0
    short = json.loads(capsys.readouterr().out)
    assert default["config"]["sim"]["sensor"]["range_m"] == 6.0 and short["config"]["sim"]["sensor"]["range_m"] == 4.0
    assert short["starts_xy"] == default["starts_xy"]
    assert short["steps"] > default["steps"] and short["coverage"] >= 0.99
