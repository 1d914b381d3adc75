"""Bad input of every class ends in one line naming the problem and the fix, and exit code 2; --config."""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import torch
import yaml
from PIL import Image
from policy_edit import edited_policy

from mrexplore.cli import main, strict_json
from mrexplore.config import LearnedConfig, MapConfig, RunConfig, config_from_dict
from mrexplore.maps.loaders import load_map
from mrexplore.training.checkpoint import VALUE_INPUTS, load_policy, save_policy
from mrexplore.training.hier_net import MultiGraphNet
from mrexplore.types import MrExploreError

FAST = ["--resolution", "0.2", "--robots", "2", "--max-steps", "30"]


@pytest.fixture
def files(tmp_path: Path) -> Path:
    room = np.zeros((40, 40), np.uint8)
    room[5:35, 5:35] = 255
    Image.fromarray(room).save(tmp_path / "room.png")
    (tmp_path / "generated_house.png").write_bytes((tmp_path / "room.png").read_bytes())
    texts = {
        "nan.yaml": "image: room.png\nresolution: .nan\n",
        "inf_origin.yaml": "image: room.png\nresolution: 0.05\norigin: [.inf, 0, 0]\n",
        "huge_res.yaml": "image: room.png\nresolution: 1.0e9\n",
        "bomb.yaml": "a: &a [1, 1, 1]\nb: &b [*a, *a, *a]\nimage: room.png\nresolution: 0.05\n",
        "text.png": "hello, I am not an image\n",
        "nan.json": '{"verts": [[0, 0], [NaN, 0], [1, 1]]}',
        "far.json": '{"verts": [[0, 0], [100000, 0], [100000, 100000], [0, 100000]]}',
        "deep.json": "[" * 100000 + "]" * 100000,
        "cfg_key.yaml": "sim:\n  sensor:\n    rang_m: 8\n",
        "cfg_bomb.yaml": "sim: &s {robots: 2}\nmap: *s\n",
        "cfg_type.yaml": "sim:\n  sensor:\n    range_m: eight\n",
        "cfg_nan.yaml": "sim:\n  sensor:\n    range_m: .nan\n",
        "cfg_list.yaml": "- 1\n- 2\n",
    }
    for name, text in texts.items():
        (tmp_path / name).write_text(text)
    (tmp_path / "image.json").write_bytes((tmp_path / "room.png").read_bytes())
    return tmp_path


def _err(capsys) -> str:
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err
    return err.removeprefix("mrexplore: error: ").removesuffix("\n")


MAP_ERRORS = [
    ("nan.yaml", "malformed map YAML {d}/nan.yaml: resolution must be a finite number > 0 and origin [x, y, yaw]"),
    (
        "inf_origin.yaml",
        "malformed map YAML {d}/inf_origin.yaml: origin and free_thresh must be finite numbers, origin within "
        "1e+07 m; fix the numeric fields",
    ),
    (
        "huge_res.yaml",
        "map {d}/room.png at 0.2 m per cell would be 200000000000 x 200000000000 = 40000000000000000000000 cells, "
        "over the limit of 60000000 (map.max_cells); use a coarser --resolution or raise the limit in --config",
    ),
    ("bomb.yaml", "map YAML {d}/bomb.yaml uses a YAML alias (*name); write the values out instead"),
    (
        "text.png",
        "cannot read map image {d}/text.png: cannot identify image file '{d}/text.png'; give a PNG/PGM map image",
    ),
    (
        "image.json",
        "malformed HouseExpo JSON {d}/image.json: UnicodeDecodeError 'utf-8' codec can't decode byte 0x89 in "
        "position 0: invalid start byte; give a file with a 'verts' polygon",
    ),
    ("nan.json", "malformed HouseExpo JSON {d}/nan.json: 'verts' must be >= 3 [x, y] points in metres"),
    (
        "far.json",
        "map {d}/far.json is 10000050 x 10000050 = 100001000002500 pixels, over the limit of 400000000 "
        "(map.max_image_pixels); raise it in --config if the map is real",
    ),
    ("deep.json", "malformed HouseExpo JSON {d}/deep.json: nested too deeply; give a file with a 'verts' polygon"),
]


@pytest.mark.parametrize(("name", "message"), MAP_ERRORS, ids=[m[0] for m in MAP_ERRORS])
def test_hostile_map_files(files, capsys, name: str, message: str) -> None:
    assert main(["explore", *FAST, "--map", str(files / name)]) == 2
    assert _err(capsys) == message.format(d=files)


def test_limits_are_configurable_and_refuse_before_decoding(files, capsys) -> None:
    cfg = MapConfig(resolution_m=0.2, max_image_pixels=100)
    with pytest.raises(MrExploreError) as err:
        load_map(files / "room.png", cfg)
    assert str(err.value) == (
        f"map {files}/room.png is 40 x 40 = 1600 pixels, over the limit of 100 (map.max_image_pixels); "
        "raise it in --config if the map is real"
    )
    (files / "small.yaml").write_text("map:\n  max_file_bytes: 10\n")
    assert main(["explore", *FAST, "--map", str(files / "room.png"), "--config", str(files / "small.yaml")]) == 2
    size = (files / "room.png").stat().st_size
    assert _err(capsys) == (
        f"map file {files}/room.png is {size} bytes, over the limit of 10 (map.max_file_bytes); "
        "raise it in --config if the map is real"
    )


def test_a_file_named_like_the_generator_is_read_as_that_file(files, capsys) -> None:
    m = load_map(files / "generated_house.png", MapConfig(resolution_m=0.1, pixel_size_m=0.1))
    assert m.name == "generated_house" and m.shape == (40, 40)
    assert main(["explore", "--map", "generated:-4"]) == 2
    assert _err(capsys) == "bad generator spec 'generated:-4'; write generated:SEED with an integer SEED >= 0"
    assert main(["explore", "--map", "varied:x"]) == 2
    assert _err(capsys) == "bad generator spec 'varied:x'; write varied:SEED with an integer SEED >= 0"
    assert load_map("varied:3", MapConfig(resolution_m=0.1)).name == "varied:3"


CLI_ERRORS = [
    (["--seed", "-1"], "argument --seed: must be an integer >= 0, got '-1'; see 'mrexplore explore --help'"),
    (
        ["--start", "nan,1"],
        "argument --start: must be finite X,Y in metres, got 'nan,1'; see 'mrexplore explore --help'",
    ),
    (
        ["--start", "inf,1"],
        "argument --start: must be finite X,Y in metres, got 'inf,1'; see 'mrexplore explore --help'",
    ),
    (["--start", "3,3", "--start", "3,3"], "--start gives the same point twice; give each robot its own start"),
    (
        ["--start", "3.0,3.0", "--start", "3.05,3.05"],
        "--start puts two robots in one cell; give starts at least one cell apart",
    ),
    (
        ["--resolution", "nan"],
        "argument --resolution: must be a number > 0 metres, got 'nan'; see 'mrexplore explore --help'",
    ),
    (["--max-steps", "0"], "argument --max-steps: must be an integer >= 1, got '0'; see 'mrexplore explore --help'"),
    (["--gif", "/nonexistent/x.gif"], "--gif folder /nonexistent does not exist; create it first"),
    (["--png", "/"], "--png / is a folder; pass a file path"),
    (
        ["--robot-failure", "1"],
        "argument --robot-failure: must be ROBOT@STEP (integers, e.g. 1@300), got '1'; see 'mrexplore explore --help'",
    ),
    (["--robot-failure", "5@10"], "--robot-failure names robot 5, but a team of 2 has robots 0..1"),
    (
        ["--message-loss", "1"],
        "argument --message-loss: must be a number in [0, 1), got '1'; see 'mrexplore explore --help'",
    ),
    (
        ["--comm-range", "-3"],
        "argument --comm-range: must be a number > 0 metres, or null for unlimited, got '-3'; "
        "see 'mrexplore explore --help'",
    ),
    (
        ["--centre-restart", "x"],
        "argument --centre-restart: must be a step >= 0, got 'x'; see 'mrexplore explore --help'",
    ),
]


@pytest.mark.parametrize(("args", "message"), CLI_ERRORS, ids=[" ".join(a) for a, _ in CLI_ERRORS])
def test_every_argument_is_checked_before_work(capsys, args: list[str], message: str) -> None:
    assert main(["explore", "--map", "generated:3", *FAST, *args]) == 2
    assert _err(capsys) == message


def test_outputs_are_checked_before_the_mission(monkeypatch, capsys) -> None:
    def no_mission(*args, **kwargs):
        raise AssertionError("the mission ran before the output path was checked")

    monkeypatch.setattr("mrexplore.mission.run_mission", no_mission)
    for flag in ("--gif", "--png", "--save-map"):
        assert main(["explore", "--map", "generated:3", *FAST, flag, "/nonexistent/out"]) == 2
        assert _err(capsys) == f"{flag} folder /nonexistent does not exist; create it first"
    if Path("/proc/self").is_dir():  # a folder that exists and takes no file: found by creating one, before work
        assert main(["explore", "--map", "generated:3", *FAST, "--png", "/proc/x.png"]) == 2
        assert _err(capsys) == "--png /proc/x.png cannot be written (/proc takes no new files); choose a writable path"


def test_bench_and_train_arguments(tmp_path, capsys) -> None:
    out = tmp_path / "out"
    for workers in ("-1", "0"):
        assert main(["bench", "--maps", "generated:1", "--out", str(out), "--workers", workers]) == 2
        assert _err(capsys) == (
            f"argument --workers: must be an integer >= 1 (leave the flag out for one per core), got '{workers}'; "
            "see 'mrexplore bench --help'"
        )
    assert main(["bench", "--maps", "generated:1", "--out", str(out), "--team-sizes", "2,2"]) == 2
    assert _err(capsys) == "--team-sizes names a team size twice (2,2); give each size once"
    assert main(["bench", "--maps", "generated:1", "--out", str(out), "--robots", "2,3"]) == 2
    assert _err(capsys) == "argument --robots: must be an integer >= 1, got '2,3'; see 'mrexplore bench --help'"
    assert main(["bench", "--maps", "generated:1", "--out", str(out), "--robots", "2", "--team-sizes", "2,3"]) == 2
    assert _err(capsys) == "--robots and --team-sizes both give the team; give one"
    (tmp_path / "file").write_text("x")
    assert main(["bench", "--maps", "generated:1", "--out", str(tmp_path / "file")]) == 2
    assert _err(capsys) == f"--out {tmp_path / 'file'} is a file, not a folder; pass a folder"
    assert main(["bench", "--maps", "generated:1", "--out", str(out), "--seeds", "0"]) == 2
    assert _err(capsys) == "argument --seeds: must be an integer >= 1, got '0'; see 'mrexplore bench --help'"
    assert main(["train", "--out", str(out), "--seed", "-3"]) == 2
    assert _err(capsys) == "argument --seed: must be an integer >= 0, got '-3'; see 'mrexplore train --help'"


CONFIG_ERRORS = [
    (
        "cfg_key.yaml",
        "--config file {d}/cfg_key.yaml: unknown SensorConfig keys sim.sensor.rang_m; known: range_m, "
        "ray_oversampling, p_hit, p_miss, p_clamp_min, p_clamp_max, p_occupied, range_noise_m",
    ),
    ("cfg_bomb.yaml", "--config file {d}/cfg_bomb.yaml uses a YAML alias (*name); write the values out instead"),
    ("cfg_type.yaml", "--config file {d}/cfg_type.yaml: sim.sensor.range_m must be a finite number, got 'eight'"),
    ("cfg_nan.yaml", "--config file {d}/cfg_nan.yaml: sim.sensor.range_m must be a finite number, got nan"),
    ("cfg_list.yaml", "--config file {d}/cfg_list.yaml: the config must be a mapping of RunConfig fields, got [1, 2]"),
    ("missing.yaml", "--config file {d}/missing.yaml not found; 'mrexplore config > missing.yaml' writes the defaults"),
]


@pytest.mark.parametrize(("name", "message"), CONFIG_ERRORS, ids=[c[0] for c in CONFIG_ERRORS])
def test_config_file_errors(files, capsys, name: str, message: str) -> None:
    assert main(["explore", "--map", "generated:3", *FAST, "--config", str(files / name)]) == 2
    assert _err(capsys) == message.format(d=files)


def test_config_prints_defaults_that_read_back(tmp_path, capsys) -> None:
    assert main(["config"]) == 0
    text = capsys.readouterr().out
    assert "# Maximum range, metres (paper: 6 m). Allowed: > 0 metres.\n    range_m: 6.0\n" in text
    assert config_from_dict(RunConfig, yaml.safe_load(text)) == RunConfig()


def test_config_sets_the_sensor_range_and_flags_override_it(tmp_path, capsys) -> None:
    cfg = tmp_path / "c.yaml"
    cfg.write_text("sim:\n  robots: 3\n  sensor:\n    range_m: 3.0\nmission:\n  max_steps: 40\n")
    assert (
        main(
            ["explore", "--map", "generated:3", "--resolution", "0.2", "--config", str(cfg), "--robots", "1", "--json"]
        )
        == 0
    )
    rec = json.loads(capsys.readouterr().out)
    assert rec["config"]["sim"]["sensor"]["range_m"] == 3.0
    assert rec["robots"] == 1 and rec["steps"] == 40  # --robots overrides the file's 3; the budget is the file's


def test_json_is_strict() -> None:
    assert strict_json({"a": math.nan, "b": [math.inf, 1.0], "c": (np.float64(2.0), np.int64(3))}) == {
        "a": None,
        "b": [None, 1.0],
        "c": [2.0, 3],
    }
    json.dumps(strict_json({"x": -math.inf}), allow_nan=False)


def _refused(policy: Path) -> str:
    """The one-line error a policy file gets."""
    with pytest.raises(MrExploreError) as err:
        load_policy(policy)
    return str(err.value)


def test_hostile_policy_files(tmp_path, capsys) -> None:
    (tmp_path / "text.npz").write_text("not a checkpoint")
    with pytest.raises(MrExploreError, match=r"is not a mrexplore policy \(not an archive\); retrain it"):
        load_policy(tmp_path / "text.npz")
    net = MultiGraphNet(LearnedConfig(), VALUE_INPUTS)
    with torch.no_grad():
        next(iter(net.parameters())).fill_(float("nan"))
    save_policy(tmp_path / "nan.npz", net)
    assert _refused(tmp_path / "nan.npz") == (
        f"policy file {tmp_path / 'nan.npz'} has weights robot_in.0.weight holding NaN or infinite values; retrain it"
    )
    good = tmp_path / "good.npz"
    save_policy(good, MultiGraphNet(LearnedConfig(), VALUE_INPUTS))

    def huge(h: dict) -> None:
        h["learned_config"]["hidden"] = 10**6  # would allocate terabytes

    edited_policy(good, tmp_path / "huge.npz", header=huge)
    assert _refused(tmp_path / "huge.npz") == (
        f"policy file {tmp_path / 'huge.npz'} does not fit this network (hidden must be in [4, 1024], got 1000000); "
        "retrain it"
    )

    def changed(w: dict) -> None:
        next(iter(w.values())).reshape(-1)[0] += 0.5  # a changed weight, still finite

    edited_policy(good, tmp_path / "changed.npz", weights=changed)
    assert _refused(tmp_path / "changed.npz") == (
        f"policy file {tmp_path / 'changed.npz'} is corrupted: its weights do not match the digest saved with them; "
        "retrain it"
    )
    for path in (tmp_path / "huge.npz", tmp_path / "changed.npz"):
        assert main(["explore", "--map", "generated:3", *FAST, "--policy", str(path)]) == 2
        assert f"policy file {path} " in _err(capsys)


@pytest.mark.parametrize(
    "script",
    [
        "profile_decision.py",
        "step_and_decision.py",
        "fields.py",
        "meanshift.py",
        "predictor_cost.py",
        "decision_ratio.py",
    ],
)
def test_benchmarks_give_one_line_on_bad_input(script: str) -> None:
    benchmarks = Path(__file__).resolve().parents[1] / "benchmarks"
    out = subprocess.run(
        [sys.executable, str(benchmarks / script), "--map", "no_such_map.yaml"],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert out.returncode == 2
    fix = "pass an existing map file with --map"
    assert out.stderr == f"{script}: error: map file not found: no_such_map.yaml; {fix}\n"


def test_a_bandwidth_bound_must_be_positive_and_leaves_old_benches_their_hash() -> None:
    from dataclasses import replace

    from mrexplore.bench.runner import _settings_dict, settings_hash
    from mrexplore.config import PreprocessConfig, RunConfig

    with pytest.raises(
        MrExploreError, match=r"^bandwidth_max_m must be > 0 metres, or null for the percentile rule alone, got 0.0$"
    ):
        PreprocessConfig(bandwidth_max_m=0.0)
    paper = replace(RunConfig(), preprocess=PreprocessConfig(bandwidth_max_m=None))
    assert "bandwidth_max_m" not in _settings_dict(paper)["preprocess"]  # unbounded: hashed as before it existed
    assert _settings_dict(RunConfig())["preprocess"]["bandwidth_max_m"] == 6.0
    assert settings_hash(RunConfig()) != settings_hash(paper)


def test_a_policy_archive_that_unpacks_beyond_the_limit_is_refused_unread(tmp_path) -> None:
    """A small deflated archive can unpack to gigabytes: its members' sizes are read before any of them."""
    import zipfile

    from mrexplore.global_planning.learned.policy_file import MAX_POLICY_BYTES

    bomb = tmp_path / "bomb.npz"
    with zipfile.ZipFile(bomb, "w", compression=zipfile.ZIP_DEFLATED) as z:
        z.writestr("__header__.npy", b"\0" * (MAX_POLICY_BYTES + 1))
    assert bomb.stat().st_size < 1_000_000
    assert _refused(bomb) == (
        f"policy file {bomb} is not a mrexplore policy (it unpacks to {MAX_POLICY_BYTES + 1} bytes, over the "
        f"{MAX_POLICY_BYTES}-byte limit); retrain it"
    )


def test_a_team_too_large_for_its_map_is_warned_about_once(capsys) -> None:
    # generated:0 at 0.2 m holds 157 m^2 of free space: 39 robots at 4 m^2 each
    assert main(["explore", "--map", "generated:0", "--resolution", "0.2", "--robots", "60", "--max-steps", "1"]) == 0
    warnings = [line for line in capsys.readouterr().err.splitlines() if "warning" in line]
    assert len(warnings) == 1
    assert warnings[0].startswith("mrexplore: warning: map generated:0: 60 robots on ")
    assert warnings[0].endswith("m^2 each): most will wait in each other's way; 39 robots suit it")


def test_a_ros2_of_another_distribution_sourced_in_the_shell_is_one_line(tmp_path: Path) -> None:
    # A sourced ROS 2 built for another Python puts its rclpy first on PYTHONPATH; its import fails.
    import subprocess
    import sys

    fake = tmp_path / "humble" / "rclpy"
    fake.mkdir(parents=True)
    (fake / "__init__.py").write_text("from rclpy._rclpy_pybind11 import *  # built for Python 3.10\n")
    env = {**os.environ, "PYTHONPATH": str(fake.parent), "ROS_DISTRO": "humble"}
    out = subprocess.run(
        [sys.executable, "-m", "mrexplore", "ros2", "robot", "--name", "r1", "--index", "0"],
        capture_output=True,
        text=True,
        env=env,
        timeout=120,
    )
    assert out.returncode == 2 and "Traceback" not in out.stderr
    line = out.stderr.strip()
    assert line.startswith(f"mrexplore: error: rclpy at {fake / '__init__.py'} does not load in Python 3.")
    assert "(ROS_DISTRO=humble is sourced): ModuleNotFoundError: No module named 'rclpy._rclpy_pybind11'" in line
    assert line.endswith("; use a shell without that ROS 2 sourced, or one built for this Python")
