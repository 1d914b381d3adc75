"""How long a whole bench table would take, projected from benches already run: each (map, strategy)'s mean
episode wall time over the seeds measured, times the seeds asked for, summed, over the workers.

    python perf/table_time.py --runs DIR [DIR ...] [--seeds 3] [--workers 2] [--strategies a,b,...]

A later folder's episode replaces an earlier one's for the same (map, strategy, robots, seed), so newer
code goes last. Episode wall times are what each worker measured (`wall_s`), so the projection assumes the
workers stay busy and the machine is as fast as when the rows were made (it moves by half between
sessions). Every (map, strategy) pair of the maps seen that no folder holds is listed: the projection leaves
it out, so it is then a lower bound.
"""

from __future__ import annotations

import argparse
import statistics
import sys
from collections import defaultdict
from pathlib import Path

from mrexplore.bench.runner import read_rows

TABLE_I = ("hier", "hier-heuristic", "utility", "coscan", "nearest", "ncm", "oracle")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--runs", nargs="+", required=True, type=Path, help="bench folders, oldest first")
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--strategies", default=",".join(TABLE_I), help="comma-separated (default Table I's seven)")
    args = ap.parse_args(argv)
    wanted = args.strategies.split(",")
    episodes: dict[tuple[str, str, str, str], float] = {}
    for folder in args.runs:
        rows = read_rows(folder / "results.csv")
        if not rows:
            raise SystemExit(f"{folder}: no results.csv with rows; give bench folders")
        for r in rows:
            if r["strategy"] in wanted:
                episodes[(r["map"], r["strategy"], r["robots"], r["seed"])] = float(r["wall_s"])
    walls: dict[tuple[str, str], list[float]] = defaultdict(list)
    for (m, s, _, _), w in episodes.items():
        walls[(m, s)].append(w)
    maps = sorted({m for m, _ in walls})
    per_strategy: dict[str, float] = defaultdict(float)
    measured: dict[str, int] = defaultdict(int)
    missing = [f"{m} {s}" for m in maps for s in wanted if (m, s) not in walls]
    for (_m, s), ws in walls.items():
        per_strategy[s] += statistics.mean(ws) * args.seeds
        measured[s] += len(ws)
    total = sum(per_strategy.values())
    print(f"{len(maps)} maps, {len(episodes)} episodes measured; projected for {args.seeds} seeds", end="")
    print(f" on {args.workers} workers\n")
    print("| strategy | episodes measured | worker-minutes projected | share |")
    print("| --- | --- | --- | --- |")
    for s in wanted:
        if measured[s]:
            print(f"| {s} | {measured[s]} | {per_strategy[s] / 60:.1f} | {per_strategy[s] / total:.0%} |")
    print(f"\nprojected: {total / args.workers / 60:.1f} minutes")
    if missing:
        print(f"not measured (left out, so a lower bound): {', '.join(missing)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
