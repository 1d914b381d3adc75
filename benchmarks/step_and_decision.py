"""Median milliseconds per simulation step and per planning decision on the largest HouseExpo map.

Run: python benchmarks/step_and_decision.py [--steps 400] [--robots 3 8] [--map PATH --resolution M]
    [--from-coverage C]
(--map: any map instead of the largest HouseExpo one, e.g. a KTH floor at the paper's 0.05 m;
--from-coverage: run the mission untimed until the team's coverage reaches C, then time --steps steps.)
Targets on the 2-core dev machine: sim <= 2 ms per step at 3 robots; a decision <= 50 ms median.
A decision is the centre's whole work in one round: decode the robots' sparse frontier maps, rebuild and
merge the team grid, then frontiers, Mean-Shift, one distance field per robot, assignment and paths. The
robots' own work (their grids' update, closing, codes, messages) runs on board and is given apart, per
robot, and so is the byte accounting of the baselines Table II compares with (neither robot nor centre
work). The mission decides on its usual events and at least every 10 steps, close to the rate missions
show.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from _common import houseexpo_dir, largest_houseexpo, run_script, skip, time_mission


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=400)
    ap.add_argument("--robots", type=int, nargs="+", default=[3, 8])
    ap.add_argument("--strategy", default="utility")
    ap.add_argument("--map", type=Path, default=None, help="default: the largest HouseExpo map")
    ap.add_argument("--resolution", type=float, default=0.05, help="cell size, metres (default 0.05)")
    ap.add_argument("--from-coverage", type=float, default=None, help="time the steps after this coverage (0-1)")
    args = ap.parse_args()
    if args.map is None and not houseexpo_dir().is_dir():
        return skip("HouseExpo maps", houseexpo_dir())
    path = args.map or largest_houseexpo()
    time_mission(path, 2, 20, args.strategy, args.resolution)  # compile the numba kernels outside the timings
    start = "" if args.from_coverage is None else f" from coverage {args.from_coverage}"
    print(f"map {path.stem} ({args.strategy}, {args.steps} steps{start}, a decision at least every 10 steps)")
    print(
        "robots  cells    coverage  step ms (median / p95)  decision ms (median / p95)  robot ms (median / p95)"
        "  accounting ms per robot (median)"
    )
    for n in args.robots:
        r = time_mission(path, n, args.steps, args.strategy, args.resolution, args.from_coverage)
        print(
            f"{n:6d}  {r['cells']:7d}  {r['coverage']:8.3f}  {r['step_ms_median']:8.2f} / {r['step_ms_p95']:6.2f}"
            f"       {r['decision_ms_median']:8.2f} / {r['decision_ms_p95']:6.2f}"
            f"       {r['robot_ms_median']:8.2f} / {r['robot_ms_p95']:6.2f}"
            f"      {r['accounting_ms_median']:8.2f}"
        )
    return 0


if __name__ == "__main__":
    sys.exit(run_script(main))
