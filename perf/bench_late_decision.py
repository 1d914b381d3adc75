"""What a decision costs late in a mission, when the known floor is as large as the map.

    python perf/bench_late_decision.py --robots 16 --coverage 0.5   # KTH 50010535_PLAN1 at 0.05 m

Runs one mission (seed 0) until the team's coverage reaches ``--coverage``, then times the next
``--decisions`` decisions at the centre: their median and p95, and the cProfile lines of that window
(``--sort``: cumulative or tottime). The first steps of a mission (``perf/bench_step_and_decision.py``)
see a small known floor; this is the other end.
"""

from __future__ import annotations

import argparse
import cProfile
import pstats
import time

import numpy as np

from mrexplore.config import MapConfig, MissionConfig, SimConfig
from mrexplore.maps.loaders import load_map
from mrexplore.mission import Mission
from mrexplore.strategies import make_strategy


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--map", default="../shared/maps/kth_floorplans/50010535_PLAN1.yaml")
    ap.add_argument("--strategy", default="hier")
    ap.add_argument("--robots", type=int, default=16)
    ap.add_argument("--resolution", type=float, default=0.05)
    ap.add_argument("--coverage", type=float, default=0.5, help="start timing at this coverage (0-1)")
    ap.add_argument("--decisions", type=int, default=20)
    ap.add_argument("--top", type=int, default=25)
    ap.add_argument("--sort", default="tottime", choices=("cumulative", "tottime"))
    args = ap.parse_args()
    truth = load_map(args.map, MapConfig(resolution_m=args.resolution))
    mission = Mission(
        truth,
        make_strategy(args.strategy),
        SimConfig(robots=args.robots),
        MissionConfig(max_steps=100_000),
        seed=0,
        progress=False,
    )
    t0 = time.perf_counter()
    while mission.advance():
        mission.decide()
        if mission.curve[-1] >= args.coverage:
            break
    print(
        f"{truth.name}, {truth.shape[0] * truth.shape[1] / 1e6:.1f} M cells, {args.robots} robots, {args.strategy}: "
        f"coverage {mission.curve[-1]:.3f} at step {mission.steps} ({time.perf_counter() - t0:.0f} s)"
    )
    first = len(mission.plan_ms)
    profile = cProfile.Profile()
    profile.enable()
    for _ in range(args.decisions):
        if not mission.advance():
            break
        mission.decide()
    profile.disable()
    ms = np.asarray(mission.plan_ms[first:])
    print(
        f"{len(ms)} decisions from there: median {np.median(ms):.0f} ms, p95 {np.percentile(ms, 95):.0f} ms "
        f"(coverage {mission.curve[-1]:.3f} at step {mission.steps})"
    )
    pstats.Stats(profile).sort_stats(args.sort).print_stats(args.top)


if __name__ == "__main__":
    main()
