"""Report tables on hand-made rows: improvements, byte reductions and bound ratios checkable by hand."""

from __future__ import annotations

import pytest

from mrexplore.bench.report import bound_table, bytes_table, paired_bootstrap, paired_table, steps_table


def row(strategy: str, steps: int, cls: str = "small", **extra: str) -> dict[str, str]:
    base = {
        "strategy": strategy,
        "steps": str(steps),
        "size_class": cls,
        "dataset": "houseexpo",
        "coverage": "1.0",
        "lower_bound_steps": "50",
        "bytes_grid": "10000",
        "bytes_grid_zlib": "2000",
        "bytes_sparse": "4000",
        "bytes_sparse_delta": "500",
        "reconstruction_iou_min": "0.99",
        "reconstruction_iou_mean": "0.999",
        "done_reason": "no_frontiers",
    }
    return base | extra


def test_improvement_is_against_the_best_other_strategy_not_yardsticks() -> None:
    rows = [row("hier", 80), row("hier", 100), row("utility", 100), row("nearest", 200), row("oracle", 40)]
    table = steps_table(rows, ["hier", "utility", "nearest", "oracle"]).splitlines()
    # hier 90 mean vs utility 100: +10 %; utility vs hier 90: -11.1 %; oracle's 40 never counts as "other".
    assert table[2] == "| hier | 100.00 | 90.0 ± 10.0 | +10.0 |"
    assert table[3] == "| utility | 100.00 | 100.0 ± 0.0 | -11.1 |"
    assert table[5] == "| oracle | 100.00 | 40.0 ± 0.0 | +55.6 |"


def test_budget_cut_episodes_counted_and_tables_by_dataset() -> None:
    rows = [
        row("hier", 2000, done_reason="max_steps", coverage="0.5"),
        row("hier", 1000),
        row("hier", 300, dataset="kth", cls="large"),
    ]
    by_class = steps_table(rows, ["hier"]).splitlines()
    assert by_class[2] == "| hier | 75.00 | 1500.0 ± 500.0 (1 cut) | – | 100.00 | 300.0 ± 0.0 | – |"
    all_cut = [row("hier", 2000, done_reason="max_steps"), row("utility", 2000, done_reason="max_steps")]
    assert steps_table(all_cut, ["hier", "utility"]).splitlines()[2] == "| hier | 100.00 | 2000.0 ± 0.0 (1 cut) | – |"
    by_dataset = steps_table(rows, ["hier"], key="dataset").splitlines()
    assert by_dataset[0].startswith("| strategy | houseexpo small cov. % |") and "kth large steps" in by_dataset[0]


def test_bytes_table_reductions() -> None:
    line = bytes_table([row("hier", 10), row("hier", 10, bytes_sparse="2000")]).splitlines()[2]
    # grid 10 kB, zlib 2 kB, sparse 3 kB mean, delta 0.5 kB: 70 % and 95 % below the grid, 75 % below zlib;
    # rows from before the grid-delta competitor was counted show '–' there.
    assert line == (
        "| houseexpo small | 2 | 10.0 | 2.0 | – | 3.0 | 0.5 | 70.00% ↓ | 95.00% ↓ | 75.00% ↓ | – | 0.9900 | 0.99900 |"
    )
    rows = [row("hier", 10, bytes_grid_delta_zlib="400"), row("hier", 10, bytes_grid_delta_zlib="600")]
    line = bytes_table(rows).splitlines()[2]
    # the grid's changed cells, zlib: 0.5 kB, as much as the sparse delta; 0.4 kB would be 25 % less (↑).
    assert line.split(" | ")[4] == "0.5" and line.split(" | ")[10] == "0.00% ↓"
    assert bytes_table([row("hier", 10, bytes_grid_delta_zlib="400")]).splitlines()[2].split(" | ")[10] == "25.00% ↑"


def test_bytes_table_without_the_grid_baselines() -> None:
    # A run with --no-baseline-bytes leaves the grid fields empty: the sparse columns and the IoU stay,
    # every grid column and every reduction against a grid reads '–'.
    none = {"bytes_grid": "", "bytes_grid_zlib": "", "bytes_grid_delta_zlib": ""}
    line = bytes_table([row("hier", 10, **none), row("hier", 10, bytes_sparse="2000", **none)]).splitlines()[2]
    assert line == "| houseexpo small | 2 | – | – | – | 3.0 | 0.5 | – | – | – | – | 0.9900 | 0.99900 |"
    # A group that mixes counted and uncounted rows is not averaged over the counted ones alone.
    mixed = bytes_table([row("hier", 10), row("hier", 10, **none)]).splitlines()[2]
    assert mixed.split(" | ")[2:5] == ["–", "–", "–"]


def test_bound_ratio() -> None:
    assert "| hier | 1.80× |" in bound_table([row("hier", 80), row("hier", 100)], ["hier"])


def test_paired_bootstrap_by_hand() -> None:
    est, lo, hi = paired_bootstrap([80.0, 100.0, 90.0], [100.0, 100.0, 100.0])
    assert est == pytest.approx(10.0)  # (100 - 90) / 100
    assert 0.0 <= lo <= est <= hi <= 20.0  # resampling pairs of saved 20, 0 and 10 %
    assert paired_bootstrap([90.0, 90.0], [100.0, 100.0]) == (10.0, 10.0, 10.0)
    est, lo, hi = paired_bootstrap([0.0, 90.0], [0.0, 100.0])  # resamples of the 0-step pair alone drop out
    assert (est, lo, hi) == pytest.approx((10.0, 10.0, 10.0))  # every other resample saves 10 %
    with pytest.raises(ValueError, match="two equal, non-empty samples, got 2 and 1"):
        paired_bootstrap([1.0, 2.0], [1.0])


def test_paired_table_pairs_episodes_of_the_same_map_team_and_seed() -> None:
    def row(strategy: str, seed: int, steps: int) -> dict[str, str]:
        return {"map_path": "m", "robots": "3", "seed": str(seed), "strategy": strategy, "steps": str(steps),
                "coverage": "1.0", "dataset": "dungeon", "size_class": "large"}  # fmt: skip

    rows = [row("a", 0, 90), row("b", 0, 100), row("a", 1, 90), row("b", 1, 100), row("b", 2, 500)]
    table = paired_table(rows, "a", ["a", "b"])
    assert "| dungeon large | +10.0 [+10.0, +10.0] | +0.00 | 2 |" in table  # seed 2 has no pair


def test_paired_table_at_equal_coverage_reads_steps_to_99() -> None:
    def row(strategy: str, seed: int, steps: int, to99: str) -> dict[str, str]:
        return {"map_path": "m", "robots": "3", "seed": str(seed), "strategy": strategy, "steps": str(steps),
                "steps_to_99": to99, "coverage": "1.0", "dataset": "dungeon", "size_class": "large"}  # fmt: skip

    # a ends later (90 against 80 and 100: 0% fewer) but reaches 99% sooner (60 against 75); b's seed-1
    # episode never got to 99% and counts with its 100 steps: 60 against (75 + 100) / 2 = 87.5, 31.4% fewer.
    rows = [row("a", 0, 90, "60"), row("b", 0, 80, "75"), row("a", 1, 90, "60"), row("b", 1, 100, "")]
    assert "| dungeon large | +0.0 [" in paired_table(rows, "a", ["a", "b"])
    table = paired_table(rows, "a", ["a", "b"], metric="steps_to_99")
    assert "| dungeon large | +31.4 [+20.0, +40.0] | +0.00 | 2 |" in table


def test_every_learned_strategy_gets_its_paired_section() -> None:
    from mrexplore.bench.report import _focuses

    assert _focuses(["coscan", "ncm", "ncm-sampled", "utility", "ncm-matched", "hier-nolocal"]) == [
        "coscan", "ncm", "ncm-sampled", "ncm-matched", "hier-nolocal"
    ]  # fmt: skip
    assert _focuses(["hier", "hier-heuristic", "utility"]) == ["hier"]  # the learned report keeps one section
