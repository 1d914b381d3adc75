"""benchmarks/team_sizes.py: paired differences by team size, checked by hand; one line on bad input."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

BENCHMARKS = Path(__file__).resolve().parents[2] / "benchmarks"


@pytest.fixture(scope="module")
def team_sizes():  # type: ignore[no-untyped-def]
    sys.path.insert(0, str(BENCHMARKS))
    try:
        import team_sizes

        yield team_sizes
    finally:
        sys.path.remove(str(BENCHMARKS))


def _row(strategy: str, robots: int, map_: str, steps: int, to99: int) -> dict[str, str]:
    return {
        "strategy": strategy, "robots": str(robots), "map_resolved": map_, "seed": "0", "dataset": "dungeon",
        "size_class": "large", "steps": str(steps), "steps_to_99": str(to99),
    }  # fmt: skip


def test_pairs_and_table_by_hand(team_sizes) -> None:  # type: ignore[no-untyped-def]
    rows = [
        _row("hier", 1, "a", 90, 90), _row("utility", 1, "a", 100, 100),
        _row("hier", 1, "b", 90, 90), _row("utility", 1, "b", 100, 100),
        _row("hier", 2, "a", 110, 80), _row("utility", 2, "a", 100, 100),
        _row("hier", 2, "b", 110, 80), _row("utility", 2, "b", 100, 100),
        _row("hier", 2, "c", 50, 50),  # no utility episode: no pair
    ]  # fmt: skip
    assert team_sizes.pairs(rows, "hier", "utility", "steps") == {
        (1, "dungeon large"): ([90.0, 90.0], [100.0, 100.0]),
        (2, "dungeon large"): ([110.0, 110.0], [100.0, 100.0]),
    }
    text, behind = team_sizes.table({"utility": team_sizes.differences(rows, "hier", "utility", "steps")})
    assert behind == 1
    assert text.splitlines()[2:] == [
        "| 1 | `utility` | +10.0 [+10.0, +10.0] |",
        "| 2 | `utility` | -10.0 [-10.0, -10.0] **behind** |",
    ]
    assert team_sizes.table({"utility": team_sizes.differences(rows, "hier", "utility", "steps_to_99")})[1] == 0


def test_a_folder_without_results_is_one_line(tmp_path: Path) -> None:
    out = subprocess.run(
        [sys.executable, str(BENCHMARKS / "team_sizes.py"), "--runs", str(tmp_path)],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert out.returncode == 2
    fix = "pass --runs a folder written by 'mrexplore bench'"
    assert out.stderr == f"team_sizes.py: error: {tmp_path / 'results.csv'} not found; {fix}\n"
