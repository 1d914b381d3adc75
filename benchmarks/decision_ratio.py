"""Decision time of strategies against a reference, side by side: in each round every strategy runs the same
timed mission in turn (seed 0, same map and team), and each one's median decision is divided by the
reference's of the same round.

Run: python benchmarks/decision_ratio.py [--strategies hier,hier-predict-heuristic,hier-predict]
     [--robots 8] [--steps 300] [--rounds 5] [--map MAP] [--resolution 0.05]
The first strategy is the reference; the map defaults to the largest HouseExpo one. A machine's speed drifts
from one minute to the next (one decision's median moved by a third between two runs of the same code on the
2-core machine), so a ratio is taken within a round, where the strategies ran one after another, and the
summary gives the median of the rounds' ratios with their smallest and largest.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
from _common import houseexpo_dir, largest_houseexpo, run_script, skip, time_mission

from mrexplore.pipeline import make_strategy
from mrexplore.types import MrExploreError


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--strategies", default="hier,hier-predict-heuristic,hier-predict", help="the first: reference")
    ap.add_argument("--robots", type=int, default=8)
    ap.add_argument("--steps", type=int, default=300)
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--map", type=Path, default=None, help="default: the largest HouseExpo map")
    ap.add_argument("--resolution", type=float, default=0.05, help="cell size, metres (default 0.05)")
    a = ap.parse_args()
    names = [s.strip() for s in a.strategies.split(",") if s.strip()]
    if len(names) < 2:
        raise MrExploreError(f"--strategies needs a reference and at least one more, got {a.strategies!r}")
    if a.rounds < 1 or a.steps < 1 or a.robots < 1:
        raise MrExploreError("--rounds, --steps and --robots must be >= 1")
    for name in names:
        make_strategy(name)  # an unknown name fails here, before any mission runs
    if a.map is None and not houseexpo_dir().is_dir():
        return skip("HouseExpo maps", houseexpo_dir())
    path = a.map or largest_houseexpo()
    if not Path(path).is_file():
        raise MrExploreError(f"map file not found: {path}; pass an existing map file with --map")
    for name in names:  # compile the numba kernels and warm the caches outside the timings
        time_mission(path, 2, 20, name, a.resolution)
    print(f"map {path.stem}, {a.robots} robots, {a.resolution} m, {a.steps} steps; median decision ms per round")
    print(
        "round  "
        + "  ".join(f"{n:>24s}" for n in names)
        + "  "
        + "  ".join(f"{n + ' / ' + names[0]:>36s}" for n in names[1:])
    )
    ratios: list[list[float]] = []
    for r in range(a.rounds):
        ms = [time_mission(path, a.robots, a.steps, n, a.resolution)["decision_ms_median"] for n in names]
        ratios.append([m / ms[0] for m in ms[1:]])
        print(
            f"{r + 1:5d}  " + "  ".join(f"{m:24.2f}" for m in ms) + "  " + "  ".join(f"{x:36.2f}" for x in ratios[-1])
        )
        sys.stdout.flush()
    arr = np.array(ratios)
    for j, n in enumerate(names[1:]):
        col = arr[:, j]
        spread = f"from {col.min():.2f} to {col.max():.2f}"
        print(f"{n} / {names[0]}: median {np.median(col):.2f}x over {a.rounds} rounds ({spread})")
    return 0


if __name__ == "__main__":
    sys.exit(run_script(main))
