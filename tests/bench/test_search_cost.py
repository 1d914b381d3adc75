"""benchmarks/search_cost.py: a decision's cost against the drive between decisions, on rows checkable by hand."""

from __future__ import annotations

import csv
import subprocess
import sys
from pathlib import Path

SCRIPT = Path(__file__).resolve().parents[2] / "benchmarks" / "search_cost.py"


def _run(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, str(SCRIPT), *args], capture_output=True, text=True, timeout=120)


def test_the_share_of_the_drive_between_decisions(tmp_path) -> None:
    # Two episodes: 100 steps in 10 decisions and 300 in 30: 10 steps between decisions, 1 m at 0.1 m a step,
    # 2 s at 0.5 m/s; decisions of 40 and 60 ms on average (p95 80 and 100): 50 ms, 2.5% of 2 s.
    path = tmp_path / "results.csv"
    fields = ["strategy", "steps", "decisions", "plan_ms_mean", "plan_ms_p95"]
    rows = [["slow", 100, 10, 40.0, 80.0], ["slow", 300, 30, 60.0, 100.0], ["idle", 5, 0, 0.0, 0.0]]
    with path.open("w", newline="") as f:
        w = csv.writer(f)
        w.writerow(fields)
        w.writerows(rows)
    out = _run(str(path))
    assert out.returncode == 0, out.stderr
    line = next(x for x in out.stdout.splitlines() if x.startswith("slow"))
    assert line.split() == ["slow", "2", "50.0", "90.0", "10.0", "2.00", "2.5%"]
    assert not any(x.startswith("idle") for x in out.stdout.splitlines())  # no decision: nothing to say


def test_a_missing_file_is_one_line() -> None:
    out = _run("no_such_results.csv")
    assert out.returncode == 2
    assert out.stderr == (
        "search_cost.py: error: results file not found: no_such_results.csv; "
        "pass the results.csv of a 'mrexplore bench' run\n"
    )
