"""``mrexplore report``: comparisons over benches already run (paired runs, team ratios, table time)."""

from __future__ import annotations

from pathlib import Path

import pytest

from mrexplore.cli import main


@pytest.fixture(scope="module")
def bench_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("bench")
    args = ["bench", "--maps", "generated:1", "--strategies", "utility", "--team-sizes", "2,3", "--seeds", "2"]
    assert main([*args, "--resolution", "0.2", "--max-steps", "400", "--workers", "1", "--out", str(out)]) == 0
    return out


def test_a_bench_against_itself_is_the_same_missions(bench_dir: Path, capsys: pytest.CaptureFixture[str]) -> None:
    capsys.readouterr()
    report = bench_dir / "paired.md"
    runs = [f"a={bench_dir}", f"b={bench_dir}"]
    assert main(["report", "paired", "--runs", *runs, "--strategy", "utility", "--out", str(report)]) == 0
    text = capsys.readouterr().out
    assert "| b | 4 | 0 |" in text  # 2 teams x 2 seeds shared, none differs
    assert "+0.0 [+0.0, +0.0]" in text  # no paired difference
    assert report.read_text() == text.removesuffix("\n")


def test_team_ratio_pairs_map_and_seed(bench_dir: Path, capsys: pytest.CaptureFixture[str]) -> None:
    capsys.readouterr()
    assert (
        main(["report", "teams", "--runs", str(bench_dir), "--small", "2", "--large", "3", "--strategy", "utility"])
        == 0
    )
    assert capsys.readouterr().out.startswith("utility, 3 robots against 2, 2 pairs (map, seed)")
    assert main(["report", "teams", "--runs", str(bench_dir), "--small", "3", "--large", "3"]) == 2
    assert capsys.readouterr().err == "mrexplore: error: --large must be more robots than --small, got 3 and 3\n"


def test_table_time_projects_from_the_episodes_timed(bench_dir: Path, capsys: pytest.CaptureFixture[str]) -> None:
    capsys.readouterr()
    assert main(["report", "table-time", "--runs", str(bench_dir), "--strategies", "utility", "--seeds", "4"]) == 0
    out = capsys.readouterr().out
    assert out.startswith("1 maps, 4 episodes measured; projected for 4 seeds on 2 workers")
    assert "| utility | 4 |" in out
    # strategies the folder never ran are named once, not listed as missing map by map
    assert main(["report", "table-time", "--runs", str(bench_dir), "--strategies", "utility,coscan"]) == 0
    out = capsys.readouterr().out
    assert "not measured" not in out
    assert out.rstrip().endswith("no episode of coscan in these folders: left out of the projection")


def test_report_refuses_folders_without_rows(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["report", "table-time", "--runs", str(tmp_path)]) == 2
    assert capsys.readouterr().err == (
        f"mrexplore: error: {tmp_path}: no results.csv with rows; give folders that 'mrexplore bench --out' wrote\n"
    )
    assert main(["report", "paired", "--runs", str(tmp_path)]) == 2
    assert "must be LABEL=DIR" in capsys.readouterr().err


def test_same_rows_tells_a_changed_result_from_a_changed_timing(tmp_path) -> None:
    """``benchmarks/same_rows.py``: two folders of the same episodes are the same row for row where only
    timings differ, and differ, naming the column, where a result does."""
    import csv
    import shutil
    import subprocess
    import sys
    from pathlib import Path

    before, after = tmp_path / "before", tmp_path / "after"
    args = ["bench", "--maps", "generated:1", "--strategies", "utility", "--robots", "2", "--seeds", "1"]
    assert main([*args, "--resolution", "0.2", "--max-steps", "150", "--workers", "1", "--out", str(before)]) == 0
    shutil.copytree(before, after)
    path = after / "results.csv"
    rows = list(csv.DictReader(path.open()))
    script = Path(__file__).resolve().parents[2] / "benchmarks" / "same_rows.py"

    def compare() -> subprocess.CompletedProcess[str]:
        with path.open("w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=list(rows[0]))
            w.writeheader()
            w.writerows(rows)
        return subprocess.run([sys.executable, str(script), str(before), str(after)], capture_output=True, text=True)

    rows[0]["wall_s"] = "999.0"
    same = compare()
    assert same.returncode == 0 and "1 episodes in both, 0 differ" in same.stdout
    rows[0]["steps"] = str(int(rows[0]["steps"]) + 1)
    changed = compare()
    assert changed.returncode == 1 and "utility, generated:1, robots 2, seed 0: steps" in changed.stdout
