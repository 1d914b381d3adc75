"""Median milliseconds per simulation step and per planning decision on the largest HouseExpo map.

Run: python perf/bench_step_and_decision.py [--steps 400] [--robots 3 8] [--map PATH --resolution M]
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
import csv
import sys
import time
from pathlib import Path

import numpy as np

from mrexplore.cli import run_script
from mrexplore.config import MapConfig, MissionConfig, SimConfig
from mrexplore.maps.loaders import load_map
from mrexplore.mission import Mission, MissionSpec
from mrexplore.pipeline import make_strategy
from mrexplore.sim.world import StepResult

HOUSEEXPO = Path(__file__).resolve().parents[2] / "shared" / "maps" / "houseexpo"


def largest_houseexpo() -> Path:
    with open(HOUSEEXPO / "index.csv") as f:
        rows = list(csv.DictReader(f))
    best = max(rows, key=lambda r: np.prod([int(v) for v in r["cells_at_0.05m"].split("x")]))
    return HOUSEEXPO / best["file"]


def bench(
    map_path: Path,
    robots: int,
    steps: int,
    strategy: str,
    resolution_m: float = 0.05,
    from_coverage: float | None = None,
) -> dict[str, float]:
    truth = load_map(map_path, MapConfig(resolution_m=resolution_m))
    # The package's one replanning loop, with a decision at least every 10 steps (close to missions' rate).
    budget = steps if from_coverage is None else 100_000
    m = Mission(
        MissionSpec(truth, make_strategy(strategy), SimConfig(robots=robots), MissionConfig(budget, 10), 0),
        progress=False,
    )
    if from_coverage is not None:
        while m.sim.coverage < from_coverage and m.advance():
            m.decide()
    first_step, first_decision = m.steps, len(m.record.plan_ms)
    step_ms: list[float] = []
    robot_ms: list[float] = []
    accounting_ms: list[float] = []
    plain_step = m.step

    def timed_step() -> StepResult:
        t = time.perf_counter()
        out = plain_step()
        step_ms.append((time.perf_counter() - t) * 1e3)
        return out

    m.step = timed_step  # type: ignore[method-assign]
    while m.steps - first_step < steps and m.advance():
        m.decide()
        robot_ms.append(m.link.robot_ms / robots)
        # Timed apart since c000445; before, robot_ms held it (so the script still runs on older checkouts).
        accounting_ms.append(getattr(m.link, "accounting_ms", 0.0) / robots)
    plan_ms = m.record.plan_ms[first_decision:]
    return {
        "cells": truth.shape[0] * truth.shape[1],
        "coverage": m.sim.coverage,
        "step_ms_median": float(np.median(step_ms)),
        "step_ms_p95": float(np.percentile(step_ms, 95)),
        "decision_ms_median": float(np.median(plan_ms)),
        "decision_ms_p95": float(np.percentile(plan_ms, 95)),
        "robot_ms_median": float(np.median(robot_ms)),
        "robot_ms_p95": float(np.percentile(robot_ms, 95)),
        "accounting_ms_median": float(np.median(accounting_ms)),
    }


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=400)
    ap.add_argument("--robots", type=int, nargs="+", default=[3, 8])
    ap.add_argument("--strategy", default="utility")
    ap.add_argument("--map", type=Path, default=None, help="default: the largest HouseExpo map")
    ap.add_argument("--resolution", type=float, default=0.05, help="cell size, metres (default 0.05)")
    ap.add_argument("--from-coverage", type=float, default=None, help="time the steps after this coverage (0-1)")
    args = ap.parse_args()
    if args.map is None and not HOUSEEXPO.is_dir():
        print(f"skipped: HouseExpo maps not found at {HOUSEEXPO}", file=sys.stderr)
        return 0
    path = args.map or largest_houseexpo()
    bench(path, 2, 20, args.strategy, args.resolution)  # compile the numba kernels outside the timings
    start = "" if args.from_coverage is None else f" from coverage {args.from_coverage}"
    print(f"map {path.stem} ({args.strategy}, {args.steps} steps{start}, a decision at least every 10 steps)")
    print(
        "robots  cells    coverage  step ms (median / p95)  decision ms (median / p95)  robot ms (median / p95)"
        "  accounting ms per robot (median)"
    )
    for n in args.robots:
        r = bench(path, n, args.steps, args.strategy, args.resolution, args.from_coverage)
        print(
            f"{n:6d}  {r['cells']:7d}  {r['coverage']:8.3f}  {r['step_ms_median']:8.2f} / {r['step_ms_p95']:6.2f}"
            f"       {r['decision_ms_median']:8.2f} / {r['decision_ms_p95']:6.2f}"
            f"       {r['robot_ms_median']:8.2f} / {r['robot_ms_p95']:6.2f}"
            f"      {r['accounting_ms_median']:8.2f}"
        )
    return 0


if __name__ == "__main__":
    sys.exit(run_script(main))
