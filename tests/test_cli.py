"""The command line: a smoke run, JSON output, pictures, and one-line errors with exit code 2."""

from __future__ import annotations

import csv
import json
import subprocess
import sys

import numpy as np
import pytest
from PIL import Image

from mrexplore.cli import main

FAST = ["--map", "generated:3", "--resolution", "0.1", "--robots", "2"]


def test_json_run_prints_exactly_one_object(capsys) -> None:
    assert main(["explore", *FAST, "--json"]) == 0
    out = capsys.readouterr().out
    rec = json.loads(out)
    assert out.count("\n") == 1
    for key in (
        "steps",
        "coverage",
        "steps_to_90",
        "steps_to_95",
        "steps_to_99",
        "path_len_max_m",
        "path_len_sum_m",
        "overlap",
        "decisions",
        "plan_ms_mean",
        "plan_ms_p95",
        "wall_s",
        "peak_mb",
        "done_reason",
        "rounds",
        "bytes_grid",
        "bytes_grid_zlib",
        "bytes_sparse",
        "bytes_sparse_delta",
        "reconstruction_iou_min",
        "reconstruction_iou_mean",
        "strategy",
        "map",
        "robots",
        "seed",
    ):
        assert key in rec
    assert rec["map"] == "generated:3" and rec["robots"] == 2 and rec["coverage"] >= 0.99


def test_no_baseline_bytes_leaves_the_grid_fields_out(capsys) -> None:
    assert main(["explore", *FAST, "--json", "--no-baseline-bytes"]) == 0
    rec = json.loads(capsys.readouterr().out)
    assert rec["config"]["mission"]["baseline_bytes"] is False and rec["bytes_sparse_delta"] > 0
    assert (rec["bytes_grid"], rec["bytes_grid_zlib"], rec["bytes_grid_delta_zlib"]) == (None, None, None)
    assert rec["bytes_sparse"] is None  # the whole maps the other mode would have sent
    assert main(["explore", *FAST, "--no-baseline-bytes"]) == 0
    assert "whole grids: not counted,\n    zlib-compressed not counted); " in capsys.readouterr().out


def test_human_summary_and_pictures(tmp_path, capsys) -> None:
    gif, png = tmp_path / "run.gif", tmp_path / "final.png"
    assert main(["explore", *FAST, "--gif", str(gif), "--png", str(png)]) == 0
    out = capsys.readouterr().out
    assert out.startswith("explored generated:3 with 2 robots (hier-plan-nolocal, seed 0)")
    with Image.open(gif) as g:
        assert g.n_frames > 3
    assert Image.open(png).size[0] >= 400


def test_no_local_switch(capsys) -> None:
    assert main(["explore", *FAST, "--strategy", "hier", "--json", "--no-local"]) == 0
    rec = json.loads(capsys.readouterr().out)
    assert rec["strategy"] == "hier-nolocal" and rec["config"]["strategy"]["local"] is None


def test_given_starts(capsys) -> None:
    assert main(["explore", *FAST, "--json", "--start", "3.0,3.0"]) == 0
    rec = json.loads(capsys.readouterr().out)
    assert abs(rec["starts_xy"][0][0] - 3.05) < 1e-6 and abs(rec["starts_xy"][0][1] - 3.05) < 1e-6


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (
            ["--robots", "0"],
            "mrexplore: error: argument --robots: must be an integer >= 1, got '0'; see 'mrexplore explore --help'",
        ),
        (
            ["--map", "missing.yaml"],
            "mrexplore: error: map file not found: missing.yaml; pass an existing map file with --map",
        ),
        (
            ["--strategy", "greedy"],
            "mrexplore: error: unknown strategy 'greedy'; choose one of "
            "hier, hier-heuristic, hier-predict-heuristic, hier-predict, hier-plan, team-plan, hier-search, nearest, "
            "utility, coscan, ncm, ncm-sampled, ncm-matched, oracle",
        ),
        (
            ["--start", "0.01,0.01"],
            "mrexplore: error: start (0.01, 0.01) lies inside a wall; give --start X,Y on free space",
        ),
        (
            ["--resolution", "0"],
            "mrexplore: error: argument --resolution: must be a number > 0 metres, got '0'; "
            "see 'mrexplore explore --help'",
        ),
        (
            ["--commitment", "2"],
            "mrexplore: error: argument --commitment: must be a number in [0, 1], or null for the strategy's "
            "default, got '2'; see 'mrexplore explore --help'",
        ),
        (
            ["--save-map", "no/such/folder/map"],
            "mrexplore: error: --save-map folder no/such/folder does not exist; create it first",
        ),
    ],
)
def test_bad_input_one_line_exit_2(capsys, args: list[str], message: str) -> None:
    assert main(["explore", *FAST, *args]) == 2
    err = capsys.readouterr().err
    assert err == message + "\n"


def test_malformed_and_empty_maps(tmp_path, capsys) -> None:
    (tmp_path / "bad.yaml").write_text("image: [")
    assert main(["explore", "--map", str(tmp_path / "bad.yaml")]) == 2
    assert capsys.readouterr().err == (
        f"mrexplore: error: map YAML {tmp_path / 'bad.yaml'} is not valid YAML at line 1; fix it\n"
    )
    Image.fromarray(np.zeros((10, 10), np.uint8)).save(tmp_path / "black.png")
    assert main(["explore", "--map", str(tmp_path / "black.png")]) == 2
    assert capsys.readouterr().err == (
        "mrexplore: error: map black has no free space enclosed by walls (no wall outline found); check the "
        "file's free/occupied values\n"
    )


def test_real_process_no_traceback() -> None:
    proc = subprocess.run(
        [sys.executable, "-m", "mrexplore", "explore", "--robots", "-1"], capture_output=True, text=True, check=False
    )
    assert proc.returncode == 2
    assert proc.stdout == ""
    assert proc.stderr == (
        "mrexplore: error: argument --robots: must be an integer >= 1, got '-1'; see 'mrexplore explore --help'\n"
    )


def test_unknown_option_is_one_line(capsys) -> None:
    assert main(["explore", "--frobnicate"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "unrecognized arguments: --frobnicate" in err


def test_saved_centre_map_loads_back(tmp_path, capsys) -> None:
    assert main(["explore", *FAST, "--json", "--save-map", str(tmp_path / "centre")]) == 0
    rec = json.loads(capsys.readouterr().out)
    assert (tmp_path / "centre.yaml").exists() and (tmp_path / "centre.pgm").exists()
    # The explored map is a map like any other: exploring it again covers it.
    assert main(["explore", "--map", str(tmp_path / "centre.yaml"), "--resolution", "0.1", "--json"]) == 0
    again = json.loads(capsys.readouterr().out)
    assert again["map"] == "centre" and again["coverage"] >= 0.99 and rec["coverage"] >= 0.99


def test_train_smoke_then_explore_with_that_policy(tmp_path, capsys) -> None:
    cfg = tmp_path / "tiny.yaml"
    cfg.write_text(
        "train:\n  episodes: {resolution_m: 0.2, robots_max: 2, max_steps: 60}\n  val_maps: 1\n  dagger_rounds: 1\n"
        "  episodes_per_round: 1\n  horizon_steps: 15\n  imitation_epochs: 1\n  ppo_iterations: 0\n"
        "  search_generations: 1\n  search_population: 2\n  search_elites: 1\n  search_episodes: 1\n"
        "  learned:\n    hidden: 8\n"
    )
    out = tmp_path / "run"
    args = ["train", "--out", str(out), "--config", str(cfg), "--workers", "1", "--train-maps", str(tmp_path / "none")]
    assert main(args) == 0
    captured = capsys.readouterr()
    assert "procedural floor plans only" in captured.err
    with open(out / "stages.csv", newline="") as f:
        kept = [r["stage"] for r in csv.DictReader(f) if r["kept"] == "1"]
    assert len(kept) == 1
    if kept == ["baseline"]:
        assert captured.out.startswith("kept the baseline, no trained stage beat it on validation")
    else:
        assert captured.out.startswith(f"kept stage {kept[0]} (validation ")
    assert (out / "policy.npz").is_file() and (out / "log.csv").is_file()
    assert main(["explore", *FAST, "--strategy", "hier", "--policy", str(out / "policy.npz"), "--json"]) == 0
    rec = json.loads(capsys.readouterr().out)
    import hashlib

    assert rec["policy"]["sha256"] == hashlib.sha256((out / "policy.npz").read_bytes()).hexdigest()
    assert rec["coverage"] >= 0.99


def test_a_run_that_keeps_its_baseline_says_so(tmp_path, capsys) -> None:
    """One episode of budget: no trained stage beats the baseline, and the last line and stages.csv say the
    policy is the untrained start."""
    cfg = tmp_path / "tiny.yaml"
    cfg.write_text("train:\n  episodes: {resolution_m: 0.2, robots_max: 2, max_steps: 60}\n  val_maps: 1\n")
    out = tmp_path / "run"
    args = ["train", "--out", str(out), "--config", str(cfg), "--workers", "1", "--episodes", "1"]
    assert main([*args, "--train-maps", str(tmp_path / "none")]) == 0
    line = capsys.readouterr().out.strip()
    assert line.startswith("kept the baseline, no trained stage beat it on validation (")
    assert "): the policy is the untrained start (hier-heuristic's cost); train longer; wrote " in line
    with open(out / "stages.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert rows[0]["stage"] == "baseline" and [r["stage"] for r in rows if r["kept"] == "1"] == ["baseline"]


def test_train_and_policy_errors_are_one_line(tmp_path, capsys) -> None:
    bad = tmp_path / "bad.yaml"
    bad.write_text("train:\n  horizon: 3\n")
    assert main(["train", "--out", str(tmp_path / "o"), "--config", str(bad)]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"mrexplore: error: --config file {bad}: unknown TrainConfig keys train.horizon; known:")
    assert err.count("\n") == 1
    assert main(["train", "--out", str(tmp_path / "o"), "--config", str(tmp_path / "missing.yaml")]) == 2
    assert "--config file" in capsys.readouterr().err
    assert main(["explore", *FAST, "--policy", str(tmp_path / "none.pt")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("mrexplore: error: policy file") and "not found" in err and err.count("\n") == 1
    assert main(["train", "--out", str(tmp_path / "o"), "--minutes", "0"]) == 2
    assert capsys.readouterr().err == "mrexplore: error: --minutes must be > 0, got 0.0\n"


def test_ncm_explores_and_benches_with_a_given_policy(tmp_path, capsys) -> None:
    """All three NCM decodings run from the CLI with a policy file (here an untrained network); a run with both
    learned kinds names each file; a file of the other kind is refused in one line."""
    import hashlib

    import torch

    from mrexplore.training.checkpoint import default_policy_path, save_policy
    from mrexplore.training.ncm_net import NcmNet

    torch.manual_seed(0)
    ncm = tmp_path / "ncm.npz"
    save_policy(ncm, NcmNet(), {"stage": "baseline"})
    for name in ("ncm", "ncm-sampled", "ncm-matched"):
        assert main(["explore", *FAST, "--strategy", name, "--policy", str(ncm), "--json"]) == 0
        rec = json.loads(capsys.readouterr().out)
        assert rec["strategy"] == name and rec["coverage"] >= 0.99 and rec["policy"]["path"] == str(ncm)
    both = f"hier={default_policy_path()},ncm={ncm}"
    out = tmp_path / "bench"
    args = ["bench", "--maps", "generated:3", "--strategies", "hier,ncm", "--robots", "2", "--seeds", "1"]
    assert main([*args, "--resolution", "0.2", "--policy", both, "--out", str(out), "--workers", "1"]) == 0
    capsys.readouterr()
    import csv

    with open(out / "results.csv", newline="") as f:
        rows = {r["strategy"]: r for r in csv.DictReader(f)}
    assert set(rows) == {"hier", "ncm"} and all(float(r["coverage"]) >= 0.99 for r in rows.values())
    assert rows["ncm"]["policy_sha256"] == hashlib.sha256(ncm.read_bytes()).hexdigest()
    assert main(["explore", *FAST, "--strategy", "ncm", "--policy", str(default_policy_path())]) == 2
    err = capsys.readouterr().err
    assert err == (
        f"mrexplore: error: policy file {default_policy_path()} is for the hier strategy, not ncm; "
        "pass one written by 'mrexplore train --strategy ncm' (--policy ncm=FILE where a run has both)\n"
    )


NAMES = """
import sys
from mrexplore.pipeline import strategy_names, strategy_spec
print(len(strategy_names()), strategy_spec("hier-nolocal").name,
      sorted(m for m in sys.modules if m.startswith("mrexplore.pipeline.") and m != "mrexplore.pipeline.registry"))
"""


def test_naming_the_strategies_imports_none_of_them() -> None:
    """The registry holds each strategy's factory by its import path: listing and checking names imports no
    pipeline (the command line checks a name before any work)."""
    out = subprocess.run([sys.executable, "-c", NAMES], capture_output=True, text=True, timeout=60, check=True)
    assert out.stdout.strip() == "14 hier []"


LIGHT = """
import sys
from mrexplore.cli import main
codes = [main(a) for a in (["--help"], ["explore", "--strategy", "heir"], ["explore", "--robots", "0"],
                           ["bench", "--maps", "x", "--strategies", "hier,nope", "--out", "o"])]
print(codes, sorted(m for m in ("numba", "scipy", "torch", "sklearn", "mrexplore.mission.loop") if m in sys.modules))
"""


def test_help_and_argument_errors_import_none_of_the_heavy_modules() -> None:
    """--help and argument errors answer before numba, SciPy, torch or the simulator are imported (what
    makes them answer at once; the time itself is a benchmark's, not a test's)."""
    out = subprocess.run([sys.executable, "-c", LIGHT], capture_output=True, text=True, timeout=60, check=True)
    assert out.stdout.strip().splitlines()[-1] == "[0, 2, 2, 2] []"
    assert "unknown strategy 'heir'" in out.stderr and "unknown strategy 'nope'" in out.stderr


def test_a_first_run_says_it_compiles(monkeypatch, tmp_path, capsys) -> None:
    """Where numba's cache holds no kernels yet, the run says so on stderr before compiling; once cached,
    nothing."""
    from mrexplore.runtime import kernel_cache

    assert kernel_cache.kernels_cached()  # this checkout ran missions before
    monkeypatch.setattr(kernel_cache, "_SENTINEL", "no-such-kernel.*.nbi")
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path))
    assert kernel_cache.say_if_compiling()
    assert capsys.readouterr().err == f"mrexplore: {kernel_cache.COMPILING}\n"
    assert kernel_cache.compiled_this_run()  # the summary then says its times include compiling
    monkeypatch.setattr(kernel_cache, "_compiling", False)
    monkeypatch.undo()
    assert not kernel_cache.say_if_compiling() and capsys.readouterr().err == ""


def test_the_predictive_strategy_runs_with_a_trained_predictor_or_none(tmp_path, capsys) -> None:
    """``train --target predictor`` writes a predictor that explore runs and names (path, sha256) in ``--json``;
    ``--predictor none`` runs without one; bad predictor input is one line."""
    cfg = tmp_path / "tiny.yaml"
    cfg.write_text(
        "predictor:\n  missions: 2\n  val_missions: 1\n  moments: 1\n  episodes: {max_steps: 100, resolution_m: 0.2}\n"
        "  width: 2\n  crop_cells: 16\n  batch: 2\n  epochs: 1\n  steps_per_epoch: 1\n"
    )
    out = tmp_path / "pred"
    args = [
        "train",
        "--target",
        "predictor",
        "--out",
        str(out),
        "--config",
        str(cfg),
        "--workers",
        "1",
        "--no-progress",
    ]
    assert main([*args, "--train-maps", str(tmp_path / "no-maps")]) == 0
    line = capsys.readouterr().out.strip()
    assert line.startswith("kept epoch 1 (validation loss ") and line.endswith(f"{out / 'log.csv'}")
    run = ["explore", *FAST, "--strategy", "hier-predict-heuristic", "--json", "--max-steps", "60"]
    assert main([*run, "--predictor", str(out / "predictor.npz")]) == 0
    rec = json.loads(capsys.readouterr().out)
    assert rec["strategy"] == "hier-predict-heuristic" and rec["predictor"]["path"] == str(out / "predictor.npz")
    assert len(rec["predictor"]["sha256"]) == 64
    assert main([*run, "--predictor", "none"]) == 0
    assert json.loads(capsys.readouterr().out)["predictor"] == {"path": "none", "sha256": ""}
    assert main([*run, "--predictor", str(tmp_path / "missing.npz")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("mrexplore: error: predictor file") and "not found" in err and err.count("\n") == 1
    assert main(["train", "--target", "predictor", "--strategy", "ncm", "--out", str(tmp_path / "o")]) == 2
    assert capsys.readouterr().err == (
        "mrexplore: error: --strategy does not apply to --target predictor (it trains on collected beliefs); drop it\n"
    )
