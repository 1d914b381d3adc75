"""``mrexplore report``: compare benches or policies already run (paired, teams, table-time, policies)."""

from __future__ import annotations

import argparse
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from mrexplore.cli.common import COUNT, DEFAULT_STRATEGY, SEED, WORKERS, Parser, need_torch
from mrexplore.cli.train import train_maps
from mrexplore.pipeline.registry import TABLE_I
from mrexplore.types import MrExploreError

__all__ = ["add_report", "run_report"]


def add_report(sub: Any) -> None:
    rp = sub.add_parser("report", help="compare benches or policies already run (paired, teams, table-time, policies)")
    kinds = rp.add_subparsers(dest="report", required=True, parser_class=Parser)
    pa = kinds.add_parser("paired", help="one strategy across separate benches, paired episode by episode")
    pa.add_argument(
        "--runs",
        nargs="+",
        required=True,
        metavar="LABEL=DIR[@STRATEGY]",
        help="bench folders of the same episodes, the reference first; @STRATEGY: another strategy's rows",
    )
    pa.add_argument("--train", nargs="*", default=[], metavar="LABEL=DIR", help="the train folder of a label's policy")
    pa.add_argument("--strategy", default=DEFAULT_STRATEGY, help=f"whose rows to compare (default {DEFAULT_STRATEGY})")
    pa.add_argument("--common", action="store_true", help="keep only the episodes every run holds")
    pa.add_argument("--out", default=None, help="also write the markdown here")
    te = kinds.add_parser("teams", help="steps a larger team needs against a smaller one, paired by map and seed")
    te.add_argument("--runs", nargs="+", required=True, help="bench folders, oldest first (later rows win)")
    te.add_argument("--small", type=COUNT, default=8, help="the smaller team (default 8)")
    te.add_argument("--large", type=COUNT, default=16, help="the larger team (default 16)")
    te.add_argument("--strategy", default=DEFAULT_STRATEGY, help=f"default {DEFAULT_STRATEGY}")
    tt = kinds.add_parser("table-time", help="how long a whole table would take, from episodes already timed")
    tt.add_argument("--runs", nargs="+", required=True, help="bench folders, oldest first (later rows win)")
    tt.add_argument("--seeds", type=COUNT, default=3, help="seeds of the table (default 3)")
    tt.add_argument("--workers", type=COUNT, default=2, help="workers of the table (default 2)")
    tt.add_argument("--strategies", default=",".join(TABLE_I), help="comma-separated (default Table I's seven)")
    po = kinds.add_parser("policies", help="policy files against the heuristic on maps no dev set holds")
    po.add_argument("policies", nargs="+", help="policy files (.npz), the first is the yardstick")
    po.add_argument("--fresh", type=SEED, default=0, help="N fresh varied: plans instead of the validation maps")
    po.add_argument("--robots", type=COUNT, default=None, help="robots per episode (default: train.val_robots)")
    po.add_argument("--workers", type=WORKERS, default=None, help="worker processes (default: one per core)")
    po.add_argument("--train-maps", default=None, help="folder of training maps (default: train/ of the example maps)")
    po.add_argument("--csv", default=None, help="write every map's results per policy here")


def _labelled(items: Sequence[str], flag: str) -> dict[str, str]:
    out: dict[str, str] = {}
    for item in items:
        label, sep, path = item.partition("=")
        if not sep or not label or not path:
            raise MrExploreError(f"{flag} {item!r} must be LABEL=DIR; name each folder")
        out[label] = path
    return out


def _folders(items: Sequence[str]) -> list[Path]:
    for item in items:
        if not Path(item).is_dir():
            raise MrExploreError(f"--runs folder {item} not found; give folders that 'mrexplore bench --out' wrote")
    return [Path(i) for i in items]


def run_report(args: argparse.Namespace, argv: Sequence[str]) -> str:
    if args.report == "paired":
        runs = _labelled(args.runs, "--runs")
        trains = {k: Path(v) for k, v in _labelled(args.train, "--train").items()}
        from mrexplore.bench.compare import compare_runs

        text = compare_runs(runs, args.strategy, trains, args.common, "mrexplore " + " ".join(argv))
        if args.out:
            Path(args.out).write_text(text)
        return text
    if args.report == "teams":
        from mrexplore.bench.compare import team_ratio

        return team_ratio(_folders(args.runs), args.small, args.large, args.strategy)
    if args.report == "table-time":
        from mrexplore.bench.compare import table_time

        return table_time(_folders(args.runs), args.seeds, args.workers, [s for s in args.strategies.split(",") if s])
    import csv

    need_torch()
    from mrexplore.training.compare import compare_policies

    lines, per_map = compare_policies(
        [Path(p) for p in args.policies], train_maps(args.train_maps), args.fresh, args.robots, args.workers or 0
    )
    if args.csv is not None:
        with open(args.csv, "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=list(per_map[0]))
            w.writeheader()
            w.writerows(per_map)
    return "\n".join(lines)
