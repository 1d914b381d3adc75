"""Where a mission's time goes on a large map: cProfile of the first steps of one mission, top lines.

    python perf/profile_decision.py --map ../shared/maps/kth_floorplans/50010536_PLAN3.yaml --robots 8

Prints the map size, the mean decision time at the centre, and the profile's top functions by cumulative
time (``--sort tottime``: by time spent in the function itself).
"""

from __future__ import annotations

import argparse
import cProfile
import pstats
import time

from mrexplore.config import MapConfig, MissionConfig, SimConfig
from mrexplore.maps.loaders import load_map
from mrexplore.mission import Mission
from mrexplore.strategies import make_strategy


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--map", default="../shared/maps/kth_floorplans/50010536_PLAN3.yaml")
    ap.add_argument("--strategy", default="utility")
    ap.add_argument("--robots", type=int, default=8)
    ap.add_argument("--resolution", type=float, default=0.05)
    ap.add_argument("--steps", type=int, default=300)
    ap.add_argument("--top", type=int, default=22)
    ap.add_argument("--sort", default="cumulative", choices=("cumulative", "tottime"), help="order of the lines")
    args = ap.parse_args()
    truth = load_map(args.map, MapConfig(resolution_m=args.resolution))
    print(f"{truth.name}: {truth.shape[0]} x {truth.shape[1]} = {truth.shape[0] * truth.shape[1]} cells")
    mission = Mission(
        truth,
        make_strategy(args.strategy),
        SimConfig(robots=args.robots),
        MissionConfig(max_steps=args.steps),
        seed=0,
        progress=False,
    )
    profile = cProfile.Profile()
    t0 = time.perf_counter()
    profile.enable()
    while mission.advance():
        mission.decide()
    profile.disable()
    ms = mission.plan_ms
    print(
        f"{mission.steps} steps, {len(ms)} decisions in {time.perf_counter() - t0:.1f} s; "
        f"centre decision {sum(ms) / len(ms):.1f} ms mean"
    )
    pstats.Stats(profile).sort_stats(args.sort).print_stats(args.top)


if __name__ == "__main__":
    main()
