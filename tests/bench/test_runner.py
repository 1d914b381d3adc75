"""The benchmark runner: CSV schema, resume after a kill, map folders, the report."""

from __future__ import annotations

import csv
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from mrexplore.bench.runner import (
    COLUMNS,
    EpisodeSpec,
    _area_hint,
    _settings_dict,
    dataset_of,
    drop_partial_tail,
    expand_maps,
    parse_curve,
    read_rows,
    run_bench,
    size_class,
)
from mrexplore.cli import main
from mrexplore.config import FaultConfig, MapConfig, MissionConfig, RunConfig
from mrexplore.types import MrExploreError

FAST = dict(run=RunConfig(map=MapConfig(resolution_m=0.2), mission=MissionConfig(max_steps=3000)))


def test_size_classes() -> None:
    assert [size_class(a) for a in (99.9, 100.0, 300.0, 300.1)] == ["small", "middle", "middle", "large"]


def test_rows_follow_the_schema_and_finished_episodes_are_skipped(tmp_path) -> None:
    specs = [EpisodeSpec("generated:1", s, 2, seed, **FAST) for s in ("nearest", "hier") for seed in (0, 1)]
    out = tmp_path / "results.csv"
    assert run_bench(specs[:2], out, workers=1) == 2
    assert run_bench(specs, out, workers=2) == 2  # only the two new ones
    with open(out, newline="") as f:
        reader = csv.DictReader(f)
        assert reader.fieldnames == COLUMNS
        rows = list(reader)
    assert sorted((r["strategy"], r["seed"]) for r in rows) == [
        ("hier", "0"),
        ("hier", "1"),
        ("nearest", "0"),
        ("nearest", "1"),
    ]
    assert all(float(r["coverage"]) >= 0.99 for r in rows)
    assert run_bench(specs, out) == 0
    assert run_bench(specs + specs, tmp_path / "twice.csv", workers=1) == 4  # a spec given twice runs once
    assert len(read_rows(tmp_path / "twice.csv")) == 4


def test_resume_after_kill_loses_nothing(tmp_path) -> None:
    out = tmp_path / "b"
    cmd = [
        sys.executable,
        "-m",
        "mrexplore",
        "bench",
        "--maps",
        "generated:1",
        "generated:2",
        "generated:3",
        "--strategies",
        "nearest",
        "--seeds",
        "2",
        "--resolution",
        "0.2",
        "--workers",
        "1",
        "--out",
        str(out),
    ]
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.time() + 120
    while time.time() < deadline and len(read_rows(out / "results.csv")) < 2:
        time.sleep(0.2)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    before = read_rows(out / "results.csv")
    assert 2 <= len(before) < 6
    done = subprocess.run(cmd, capture_output=True, text=True, check=True)
    assert done.stdout.startswith(f"{6 - len(before)} episodes run, {len(before)} already done")
    after = read_rows(out / "results.csv")
    assert len(after) == 6 and after[: len(before)] == before
    assert len({(r["map"], r["seed"]) for r in after}) == 6


def test_area_hint_from_image_headers(tmp_path) -> None:
    # The area hint from image headers: 20 x 20 px at 1 m (YAML) = 400 m^2; 50 x 50 px at the loader's
    # 0.1 m default = 25 m^2; unknown formats 0. The runner starts the largest first.
    Image.fromarray(np.zeros((20, 20), np.uint8)).save(tmp_path / "big.png")
    (tmp_path / "big.yaml").write_text("image: big.png\nresolution: 1.0\n")
    Image.fromarray(np.zeros((50, 50), np.uint8)).save(tmp_path / "small.png")
    assert _area_hint(str(tmp_path / "big.yaml")) == 400.0
    assert _area_hint(str(tmp_path / "small.png")) == pytest.approx(25.0)
    assert _area_hint("generated:0") == 0.0


def test_expand_maps_skips_label_images_and_yaml_images(tmp_path) -> None:
    img = np.zeros((10, 10), np.uint8)
    for name in ("a.png", "a_spaces.png", "b.png", "c.json"):
        Image.fromarray(img).save(tmp_path / name) if name.endswith(".png") else (tmp_path / name).write_text("{}")
    (tmp_path / "b.yaml").write_text("image: b.png\nresolution: 0.1\n")
    got = [Path(p).name for p in expand_maps([str(tmp_path), str(tmp_path / "b.yaml")])]
    assert got == ["a.png", "b.yaml", "c.json"]
    with pytest.raises(MrExploreError, match="map not found: nope; pass map files or folders with --maps"):
        expand_maps(["nope"])


def test_bench_cli_writes_report(tmp_path, capsys) -> None:
    args = [
        "bench",
        "--maps",
        "generated:2",
        "--strategies",
        "hier,hier-nolocal",
        "--seeds",
        "1",
        "--resolution",
        "0.2",
        "--workers",
        "1",
        "--out",
        str(tmp_path),
    ]
    assert main(args) == 0
    report = (tmp_path / "report.md").read_text()
    assert "Made by: `mrexplore bench --maps generated:2" in report
    assert "| hier | " in report and "| hier-nolocal | " in report
    assert "## Table II: bytes sent per episode" in report and "| generated middle | 2 |" in report
    assert "![coverage.png](coverage.png)" in report
    for name in ("coverage.png", "steps.png"):
        with Image.open(tmp_path / name) as img:
            assert img.size[0] > 250


@pytest.mark.slow
def test_bench_through_ray_on_a_local_instance(tmp_path) -> None:
    pytest.importorskip("ray", reason="Ray is the optional scale-out path: pip install 'mrexplore[ray]'")
    specs = [EpisodeSpec("generated:1", "nearest", 2, seed, **FAST) for seed in (0, 1)]
    out = tmp_path / "results.csv"
    assert run_bench(specs, out, workers=2, ray_address="local") == 2
    local = tmp_path / "local.csv"
    run_bench(specs, local, workers=1)
    drop = {"wall_s", "plan_ms_mean", "plan_ms_p95", "peak_mb", "onboard_ms_median", "onboard_ms_p95"}
    by_seed = [
        sorted(({k: v for k, v in r.items() if k not in drop} for r in read_rows(p)), key=str) for p in (out, local)
    ]
    assert by_seed[0] == by_seed[1]  # the same episodes, whichever runner ran them


def test_old_results_file_is_refused(tmp_path) -> None:
    out = tmp_path / "results.csv"
    out.write_text("map,strategy\n")
    with pytest.raises(MrExploreError, match="has other columns than this version writes; pass a new --out folder"):
        run_bench([EpisodeSpec("generated:1", "nearest", 2, 0, **FAST)], out, workers=1)


def test_dataset_and_curve_fields() -> None:
    assert dataset_of("../shared/maps/houseexpo/png/x.png") == "houseexpo"
    assert dataset_of("/data/kth_floorplans/a.yaml") == "kth" and dataset_of("generated:3") == "generated"
    steps, cov = parse_curve("0:0.1000 50:0.5000 73:1.0000")
    assert steps.tolist() == [0, 50, 73] and cov.tolist() == [0.1, 0.5, 1.0]


def test_bench_refuses_unknown_strategy(tmp_path, capsys) -> None:
    assert main(["bench", "--maps", "generated:2", "--strategies", "coscan2", "--out", str(tmp_path)]) == 2
    assert (
        capsys.readouterr().err == "mrexplore: error: unknown strategy 'coscan2'; choose one of "
        "hier, hier-heuristic, hier-predict-heuristic, hier-predict, hier-plan, team-plan, hier-search, nearest, "
        "utility, coscan, ncm, ncm-sampled, ncm-matched, oracle\n"
    )


def test_a_half_written_last_row_is_dropped_and_its_episode_rerun(tmp_path) -> None:
    specs = [EpisodeSpec("generated:1", "nearest", 2, seed, **FAST) for seed in (0, 1, 2)]
    out = tmp_path / "results.csv"
    assert run_bench(specs[:2], out, workers=1) == 2
    text = out.read_bytes()
    cut = text[: len(text) - 40]  # a kill in the middle of writing the second row
    out.write_bytes(cut)
    assert drop_partial_tail(out) == len(cut) - cut.rfind(b"\n") - 1
    assert len(read_rows(out)) == 1
    out.write_bytes(cut)
    assert run_bench(specs, out, workers=1) == 2  # the cut episode again, and the new one
    rows = read_rows(out)
    assert sorted(int(r["seed"]) for r in rows) == [0, 1, 2]
    assert out.read_bytes().count(b"\n") == 4 and out.read_bytes().endswith(b"\n")


def test_other_settings_in_the_same_folder_are_refused(tmp_path) -> None:
    out = tmp_path / "results.csv"
    assert run_bench([EpisodeSpec("generated:1", "nearest", 2, 0, **FAST)], out, workers=1) == 1
    other = RunConfig(map=MapConfig(resolution_m=0.25), mission=MissionConfig(max_steps=3000))
    with pytest.raises(MrExploreError) as err:
        run_bench([EpisodeSpec("generated:1", "nearest", 2, 0, run=other)], out, workers=1)
    assert str(err.value) == (
        f"{tmp_path} holds episodes run with other settings (map.resolution_m 0.2 there, 0.25 now); "
        "pass a new --out folder, or rerun with the same settings"
    )
    assert (tmp_path / "settings.yaml").read_text().startswith("# settings of every episode in this folder")


def test_the_resume_key_holds_the_resolved_map_and_the_settings(tmp_path, monkeypatch) -> None:
    Image.fromarray(np.where(np.pad(np.ones((30, 30)), 5) > 0, 255, 0).astype(np.uint8)).save(tmp_path / "m.png")
    monkeypatch.chdir(tmp_path)
    a = EpisodeSpec("m.png", "nearest", 2, 0, **FAST)
    b = EpisodeSpec(str(tmp_path / "m.png"), "nearest", 2, 0, **FAST)
    assert a.key == b.key and a.map_resolved == str((tmp_path / "m.png").resolve())
    faulty = RunConfig(map=FAST["run"].map, mission=MissionConfig(max_steps=3000, faults=FaultConfig(message_loss=0.1)))
    assert EpisodeSpec("m.png", "nearest", 2, 0, run=faulty).settings != a.settings
    assert EpisodeSpec("m.png", "hier", 2, 0, **FAST).policy_sha256 != "" and a.policy_sha256 == ""
    # a predictive strategy's key holds its predictor: the file's sha256, or 'none'
    none = EpisodeSpec("m.png", "hier-predict-heuristic", 2, 0, **FAST, predictor="none")
    shipped = EpisodeSpec("m.png", "hier-predict-heuristic", 2, 0, **FAST)
    assert none.policy_sha256 == "none" and len(shipped.policy_sha256) == 64 and none.key != shipped.key
    assert "+" not in EpisodeSpec("m.png", "hier", 2, 0, **FAST, predictor="none").policy_sha256  # reads none


def test_a_bench_without_the_grid_baselines_keeps_its_own_key_and_leaves_them_empty(tmp_path) -> None:
    # The setting came after benches were kept: at its default it stays out of the resume key, so their
    # rows keep theirs; off, it is a setting of its own, and the rows leave the three grid fields and the
    # whole maps' bytes empty.
    assert "baseline_bytes" not in _settings_dict(RunConfig())["mission"]
    off = RunConfig(mission=MissionConfig(baseline_bytes=False))
    assert _settings_dict(off)["mission"]["baseline_bytes"] is False
    assert (
        EpisodeSpec("generated:1", "nearest", 2, 0, run=off).settings
        != EpisodeSpec("generated:1", "nearest", 2, 0).settings
    )
    args = ["bench", "--maps", "generated:1", "--strategies", "nearest", "--seeds", "1", "--resolution", "0.2"]
    assert main([*args, "--workers", "1", "--no-baseline-bytes", "--out", str(tmp_path)]) == 0
    (rec,) = read_rows(tmp_path / "results.csv")
    assert [rec[k] for k in ("bytes_grid", "bytes_grid_zlib", "bytes_grid_delta_zlib")] == ["", "", ""]
    assert rec["bytes_sparse"] == "" and int(rec["bytes_sparse_delta"]) > 0 and int(rec["steps"]) > 0
    assert "| generated middle | 1 | – | – | – |" in (tmp_path / "report.md").read_text()


def _children(pid: int) -> list[int]:
    out = []
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        if int(fields[1]) == pid:
            out.append(int(stat.parent.name))
    return out


def _alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state != "Z"


@pytest.mark.skipif(not Path("/proc").is_dir(), reason="reads the process table from /proc (Linux)")
def test_no_worker_outlives_a_killed_parent(tmp_path) -> None:
    cmd = [sys.executable, "-m", "mrexplore", "bench", "--maps", "generated:1", "generated:2", "generated:3"]
    cmd += ["--strategies", "nearest,utility", "--seeds", "3", "--resolution", "0.1", "--workers", "2"]
    proc = subprocess.Popen([*cmd, "--out", str(tmp_path)], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.time() + 120
    workers: list[int] = []
    while time.time() < deadline and len(workers) < 2:
        time.sleep(0.2)
        workers = _children(proc.pid)
    assert len(workers) >= 2, "the bench never started its workers"
    proc.send_signal(signal.SIGKILL)  # no chance to clean up
    proc.wait()
    deadline = time.time() + 10
    while time.time() < deadline and any(_alive(w) for w in workers):
        time.sleep(0.2)
    assert not any(_alive(w) for w in workers)


def test_the_default_settings_keep_the_hash_benches_were_kept_under() -> None:
    """The settings were regrouped (the predictor's episodes a section of their own, a runtime section): the
    hash of the defaults is the one it was, so that benches run before resume."""
    from mrexplore.bench.runner import settings_hash
    from mrexplore.config import RunConfig

    assert settings_hash(RunConfig()) == "33b270b8fd3ca680"
