"""What a strategy's decisions cost against the time the robots drive between them, from a bench already run.

Run: python benchmarks/search_cost.py RESULTS.csv [--speed 0.5] [--step 0.1]
For each strategy of a ``mrexplore bench`` results file: its decisions' mean and 95th-percentile milliseconds
(the episodes' own ``plan_ms_mean`` and ``plan_ms_p95``, averaged over episodes), the mean steps between two
decisions (steps / decisions), what those steps take a robot at ``--speed`` m/s (``--step`` metres a step, the
bench's ``sim.motion.step_m``), and the decision's mean time as a share of that drive. A centre that decides in
less than the drive between decisions keeps its robots moving: the robots drive on with their last goals while
it decides. Times are the bench machine's; compare strategies of the same file only.
"""

from __future__ import annotations

import argparse
import csv
import sys
from collections import defaultdict
from pathlib import Path

import numpy as np
from _common import run_script

from mrexplore.types import MrExploreError


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("results", type=Path, help="a bench's results.csv")
    ap.add_argument("--speed", type=float, default=0.5, help="robot speed, m/s (default 0.5)")
    ap.add_argument("--step", type=float, default=0.1, help="metres a simulation step (default 0.1)")
    a = ap.parse_args()
    if not a.results.is_file():
        raise MrExploreError(f"results file not found: {a.results}; pass the results.csv of a 'mrexplore bench' run")
    if a.speed <= 0 or a.step <= 0:
        raise MrExploreError("--speed and --step must be > 0")
    rows: dict[str, list[dict[str, str]]] = defaultdict(list)
    with a.results.open(newline="") as f:
        for r in csv.DictReader(f):
            if int(r["decisions"]) > 0:
                rows[r["strategy"]].append(r)
    if not rows:
        raise MrExploreError(f"{a.results} holds no episode with a decision; run the bench first")
    print(f"{a.results}: robots at {a.speed} m/s, {a.step} m a step")
    print(f"{'strategy':24s} {'episodes':>8s} {'ms/decision':>12s} {'p95 ms':>8s} {'steps between':>14s} "
          f"{'drive s':>8s} {'share':>7s}")  # fmt: skip
    for name, rs in rows.items():
        mean = float(np.mean([float(r["plan_ms_mean"]) for r in rs]))
        p95 = float(np.mean([float(r["plan_ms_p95"]) for r in rs]))
        between = float(np.sum([int(r["steps"]) for r in rs]) / np.sum([int(r["decisions"]) for r in rs]))
        drive_s = between * a.step / a.speed
        print(f"{name:24s} {len(rs):8d} {mean:12.1f} {p95:8.1f} {between:14.1f} {drive_s:8.2f} "
              f"{100 * mean / 1e3 / drive_s:6.1f}%")  # fmt: skip
    return 0


if __name__ == "__main__":
    sys.exit(run_script(main))
