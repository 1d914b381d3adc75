"""How many of a small team's steps a larger team needs, with a bootstrap interval over the seeds: issue 13's
"16 robots need at most 0.6x the steps of 8 to reach 99% coverage".

    python perf/team_ratio.py --runs docs/results/table005/teams --small 8 --large 16

Reads the rows ``mrexplore bench --robots 8,16`` wrote (one or more folders; a later folder's episode
replaces an earlier one's). Episodes are paired by map and seed: the same map and seed, so the first robot
starts on the same cell and the others within the same spread of it (``draw_starts``). The ratio is the
large team's mean steps over the small team's, to 99% coverage and at the end; its 95% interval is the
paired percentile bootstrap of ``mrexplore.bench.report.paired_bootstrap`` (resampling the pairs), read as a
ratio.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from mrexplore.bench.report import paired_bootstrap, steps_of
from mrexplore.bench.runner import read_rows

METRICS = (("steps_to_99", "to 99%"), ("steps", "at the end"))


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--runs", nargs="+", required=True, type=Path, help="bench folders, oldest first")
    ap.add_argument("--small", type=int, default=8, help="the smaller team (default 8)")
    ap.add_argument("--large", type=int, default=16, help="the larger team (default 16)")
    ap.add_argument("--strategy", default="hier")
    args = ap.parse_args(argv)
    episodes: dict[tuple[str, int, str], dict[str, str]] = {}
    for folder in args.runs:
        rows = read_rows(folder / "results.csv")
        if not rows:
            raise SystemExit(f"{folder}: no results.csv with rows; give folders 'mrexplore bench --out' wrote")
        for r in rows:
            if r["strategy"] == args.strategy:
                episodes[r["map"], int(r["robots"]), r["seed"]] = r
    pairs = sorted((m, s) for (m, n, s) in episodes if n == args.small and (m, args.large, s) in episodes)
    if not pairs:
        raise SystemExit(
            f"no map and seed with both {args.small} and {args.large} robots of {args.strategy!r}: "
            f"run 'mrexplore bench --robots {args.small},{args.large}'"
        )
    print(f"{args.strategy}, {args.large} robots against {args.small}, {len(pairs)} pairs (map, seed)\n")
    print(f"| metric | mean steps, {args.small} | mean steps, {args.large} | ratio [95% CI] | per pair |")
    print("| --- | --- | --- | --- | --- |")
    for metric, label in METRICS:
        small = [steps_of(episodes[m, args.small, s], metric) for m, s in pairs]
        large = [steps_of(episodes[m, args.large, s], metric) for m, s in pairs]
        est, lo, hi = paired_bootstrap(large, small)
        # paired_bootstrap gives % fewer steps than the small team; the ratio is 1 - that / 100.
        per = ", ".join(f"{b / a:.2f}" for a, b in zip(small, large, strict=True))
        print(
            f"| {label} | {sum(small) / len(small):,.1f} | {sum(large) / len(large):,.1f} | "
            f"{1 - est / 100:.3f} [{1 - hi / 100:.3f}, {1 - lo / 100:.3f}] | {per} |"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
