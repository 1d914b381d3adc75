"""The command line: a smoke run, JSON output, pictures, and one-line errors with exit code 2."""

from __future__ import annotations

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


def test_human_summary_and_pictures(tmp_path, capsys) -> None:
    gif, png = tmp_path / "run.gif", tmp_path / "final.png"
    assert main(["explore", *FAST, "--gif", str(gif), "--png", str(png)]) == 0
    out = capsys.readouterr().out
    assert out.startswith("explored generated:3 with 2 robots (hier, seed 0)")
    with Image.open(gif) as g:
        assert g.n_frames > 3
    assert Image.open(png).size[0] >= 400


def test_no_local_switch(capsys) -> None:
    assert main(["explore", *FAST, "--json", "--no-local"]) == 0
    rec = json.loads(capsys.readouterr().out)
    assert rec["strategy"] == "hier-nolocal" and rec["config"]["local"] is None


def test_given_starts(capsys) -> None:
    assert main(["explore", *FAST, "--json", "--start", "3.0,3.0"]) == 0
    rec = json.loads(capsys.readouterr().out)
    assert abs(rec["starts_xy"][0][0] - 3.05) < 1e-6 and abs(rec["starts_xy"][0][1] - 3.05) < 1e-6


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--robots", "0"], "mrexplore: error: robots must be >= 1, got 0"),
        (
            ["--map", "missing.yaml"],
            "mrexplore: error: map file not found: missing.yaml; pass an existing map file with --map",
        ),
        (
            ["--strategy", "greedy"],
            "mrexplore: error: unknown strategy 'greedy'; choose one of hier, nearest, utility, coscan, oracle",
        ),
        (
            ["--start", "0.01,0.01"],
            "mrexplore: error: start (0.01, 0.01) lies inside a wall; give --start X,Y on free space",
        ),
        (["--resolution", "0"], "mrexplore: error: resolution must be > 0 metres, got 0.0"),
        (["--commitment", "2"], "mrexplore: error: commitment must be in [0, 1] or None, got 2.0"),
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
    assert capsys.readouterr().err.startswith(f"mrexplore: error: malformed map YAML {tmp_path / 'bad.yaml'}")
    Image.fromarray(np.zeros((10, 10), np.uint8)).save(tmp_path / "black.png")
    assert main(["explore", "--map", str(tmp_path / "black.png")]) == 2
    assert capsys.readouterr().err == (
        "mrexplore: error: map black has no free space inside its border; check the file's free/occupied values\n"
    )


def test_real_process_no_traceback() -> None:
    proc = subprocess.run(
        [sys.executable, "-m", "mrexplore", "explore", "--robots", "-1"], capture_output=True, text=True, check=False
    )
    assert proc.returncode == 2
    assert proc.stderr == "mrexplore: error: robots must be >= 1, got -1\n" and proc.stdout == ""


def test_unknown_option_is_one_line(capsys) -> None:
    with pytest.raises(SystemExit) as exit_info:
        main(["explore", "--frobnicate"])
    assert exit_info.value.code == 2
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
