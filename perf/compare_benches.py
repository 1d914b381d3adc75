"""Compare one strategy run by separate benches on the same episodes: policies (the edge-feature
ablation) or settings (``--config``).

Each ``--runs LABEL=DIR`` names a folder ``mrexplore bench`` wrote, all with the same maps, team sizes and
seeds; ``--strategy`` picks the strategy's rows (default hier), ``LABEL=DIR@STRATEGY`` another's for one
label (a yardstick such as hier-heuristic); each ``--train LABEL=DIR`` (optional) the
``mrexplore train`` folder that made the label's policy, whose ``stages.csv`` gives the kept stage and its
validation steps. The first label is the reference: the paired differences hold it against every other,
episode by episode. Benches over different maps are compared on the episodes they share with ``--common``
(the means too, else they would average different maps).

    python perf/compare_benches.py --runs all=BENCH_ALL no_advantage=BENCH_NOADV heuristic=BENCH_H@hier-heuristic \\
        --train all=TRAIN_ALL no_advantage=TRAIN_NOADV --out report.md
"""

from __future__ import annotations

import argparse
import csv
import sys
from pathlib import Path

from mrexplore.bench.report import paired_table, steps_table
from mrexplore.bench.runner import read_rows


def _pairs(items: list[str], flag: str) -> dict[str, str]:
    out: dict[str, str] = {}
    for item in items:
        label, sep, path = item.partition("=")
        if not sep or not label or not path:
            raise SystemExit(f"{flag} {item!r}: give LABEL=DIR")
        out[label] = path
    return out


def _episode(row: dict[str, str]) -> tuple[str, str, str]:
    return row["map_path"], row["robots"], row["seed"]


_NOT_RESULTS = frozenset(
    {"plan_ms_mean", "plan_ms_p95", "wall_s", "peak_mb", "onboard_ms_median", "onboard_ms_p95"}  # timings
    | {"strategy", "settings", "policy_sha256", "map_path", "map_resolved"}  # which run it is
)
"""Columns left out when asking whether two runs of an episode are the same mission."""


def _same_missions(rows: list[dict[str, str]], labels: list[str]) -> str:
    """Per other run: the episodes it shares with the reference, how many differ in any result (every
    column but timings and the run's identity), and the planning time of the shared episodes summed
    (``plan_ms_mean`` x ``decisions``; a timing, so it moves with the machine too)."""
    by = {label: {_episode(r): r for r in rows if r["strategy"] == label} for label in labels}
    ref = by[labels[0]]

    def planning_s(r: dict[str, str]) -> float:
        return float(r["plan_ms_mean"]) * int(r["decisions"]) / 1e3

    lines = [
        f"| run | shared episodes | results differ | planning s, {labels[0]} → run |",
        "| --- | --- | --- | --- |",
    ]
    for label in labels[1:]:
        shared = [e for e in by[label] if e in ref]
        differ = sum(any(ref[e][c] != by[label][e].get(c) for c in ref[e] if c not in _NOT_RESULTS) for e in shared)
        before = sum(planning_s(ref[e]) for e in shared)
        after = sum(planning_s(by[label][e]) for e in shared)
        lines.append(f"| {label} | {len(shared)} | {differ} | {before:,.0f} → {after:,.0f} |")
    return "\n".join(lines)


def _kept(train_dir: Path) -> tuple[str, str, str]:
    """The stage with the fewest validation steps (the trainer keeps it), its steps and the untrained
    baseline's."""
    with open(train_dir / "stages.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    best = min(rows, key=lambda r: float(r["val_steps_mean"]))
    base = next(r for r in rows if r["stage"] == "baseline")
    return best["stage"], f"{float(best['val_steps_mean']):.1f}", f"{float(base['val_steps_mean']):.1f}"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--runs", nargs="+", required=True, help="LABEL=BENCH_DIR, the reference first")
    ap.add_argument("--train", nargs="*", default=[], help="LABEL=TRAIN_DIR (optional)")
    ap.add_argument("--strategy", default="hier", help="whose rows to compare (default hier)")
    ap.add_argument("--out", type=Path, default=None, help="write the markdown here (default: print it)")
    ap.add_argument("--common", action="store_true", help="keep only the episodes every run holds")
    args = ap.parse_args(argv)
    runs, trains = _pairs(args.runs, "--runs"), _pairs(args.train, "--train")
    rows: list[dict[str, str]] = []
    for label, where in runs.items():
        folder, _, strategy = where.partition("@")
        strategy = strategy or args.strategy
        csv_path = Path(folder) / "results.csv"
        mine = [r for r in read_rows(csv_path) if r["strategy"] == strategy]
        if not mine:
            raise SystemExit(f"{csv_path} holds no {strategy} rows; bench that strategy")
        shas = {r["policy_sha256"] for r in mine}
        if len(shas) != 1:
            raise SystemExit(f"{csv_path} mixes {len(shas)} policies; give each policy its own bench folder")
        unique = {_episode(r): dict(r, strategy=label) for r in mine}
        rows += unique.values()
    labels = list(runs)
    if args.common:
        shared = set.intersection(*({_episode(r) for r in rows if r["strategy"] == label} for label in labels))
        if not shared:
            raise SystemExit("--common: the runs share no episode (map, robots, seed); bench the same maps")
        rows = [r for r in rows if _episode(r) in shared]
    parts = [
        f"# {args.strategy}: separate benches compared",
        f"Made by: `python perf/compare_benches.py {' '.join(sys.argv[1:])}`",
    ]
    if trains:
        lines = ["| policy | kept stage | validation steps | untrained | sha256 |", "| --- | --- | --- | --- | --- |"]
        for label, folder in trains.items():
            stage, steps, base = _kept(Path(folder))
            sha = next((r["policy_sha256"] for r in rows if r["strategy"] == label), "")[:12]
            lines.append(f"| {label} | {stage} | {steps} | {base} | {sha} |")
        parts += ["## Training (validation maps)", "\n".join(lines)]
    parts += [
        "## Steps by dataset (mean ± std)",
        steps_table(rows, labels, key="dataset"),
        f"## Paired: {labels[0]} against each other run (fewer steps %, 95% bootstrap interval)",
        paired_table(rows, labels[0], labels, key="dataset"),
        "At equal coverage (steps to 99%):",
        paired_table(rows, labels[0], labels, key="dataset", metric="steps_to_99"),
        f"## The same missions? Each run against {labels[0]}, episode by episode",
        _same_missions(rows, labels),
    ]
    text = "\n\n".join(parts) + "\n"
    if args.out:
        args.out.write_text(text)
    print(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
