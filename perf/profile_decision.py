"""Where a mission's time goes on a large map: cProfile of one mission's decisions, top lines.

    python perf/profile_decision.py --map ../shared/maps/kth_floorplans/50010536_PLAN3.yaml --robots 8
    python perf/profile_decision.py --strategy hier --robots 16 --from-coverage 0.5 --decisions 20

Prints the map size, the decision times at the centre, and the profile's top functions by cumulative
time (``--sort tottime``: by time spent in the function itself). By default the first ``--steps`` steps
are profiled; with ``--from-coverage`` the mission first runs unprofiled until the team's coverage
reaches it, then the next ``--decisions`` decisions are timed (median, p95) and profiled: the first steps
see a small known floor, late decisions are what whole-floor runs pay.
"""

from __future__ import annotations

import argparse
import cProfile
import pstats
import sys
import time

import numpy as np

from mrexplore.cli import run_script
from mrexplore.config import MapConfig, MissionConfig, SimConfig
from mrexplore.maps.loaders import load_map
from mrexplore.mission import Mission, MissionSpec
from mrexplore.pipeline import make_strategy


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--map", default="../shared/maps/kth_floorplans/50010536_PLAN3.yaml")
    ap.add_argument("--strategy", default="utility")
    ap.add_argument("--robots", type=int, default=8)
    ap.add_argument("--resolution", type=float, default=0.05)
    ap.add_argument("--steps", type=int, default=300, help="steps profiled from the start")
    ap.add_argument("--from-coverage", type=float, default=None, help="profile from this coverage (0-1) on")
    ap.add_argument("--decisions", type=int, default=20, help="decisions profiled with --from-coverage")
    ap.add_argument("--top", type=int, default=22)
    ap.add_argument("--sort", default="cumulative", choices=("cumulative", "tottime"), help="order of the lines")
    args = ap.parse_args()
    truth = load_map(args.map, MapConfig(resolution_m=args.resolution))
    print(f"{truth.name}: {truth.shape[0]} x {truth.shape[1]} = {truth.shape[0] * truth.shape[1]} cells")
    late = args.from_coverage is not None
    mission = Mission(
        MissionSpec(
            truth,
            make_strategy(args.strategy),
            SimConfig(robots=args.robots),
            MissionConfig(max_steps=100_000 if late else args.steps),
            seed=0,
        ),
        progress=False,
    )
    t0 = time.perf_counter()
    if late:
        while mission.advance():
            mission.decide()
            if mission.record.curve[-1] >= args.from_coverage:
                break
        print(f"coverage {mission.record.curve[-1]:.3f} at step {mission.steps} ({time.perf_counter() - t0:.0f} s)")
    first, budget = len(mission.record.plan_ms), args.decisions if late else None
    profile = cProfile.Profile()
    t0 = time.perf_counter()
    profile.enable()
    while (budget is None or len(mission.record.plan_ms) - first < budget) and mission.advance():
        mission.decide()
    profile.disable()
    ms = np.asarray(mission.record.plan_ms[first:])
    print(
        f"{len(ms)} decisions to step {mission.steps} in {time.perf_counter() - t0:.1f} s; centre decision "
        f"mean {ms.mean():.1f} ms, median {np.median(ms):.1f} ms, p95 {np.percentile(ms, 95):.1f} ms"
    )
    pstats.Stats(profile).sort_stats(args.sort).print_stats(args.top)


if __name__ == "__main__":
    sys.exit(run_script(main))
