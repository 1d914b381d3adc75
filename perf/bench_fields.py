"""Time of the distance fields a decision computes: whole fields from random free cells of a floor.

    python perf/bench_fields.py --map ../shared/maps/kth_floorplans/50010535_PLAN1.yaml --sources 16

Prints the grid, and the wall time of ``distance_fields`` from ``--sources`` cells drawn from the free
cells (seed 0), once per repeat, on the shared threads: late in a mission, when the known floor is as
large as the map, this is what each decision pays for its fields.
"""

from __future__ import annotations

import argparse
import sys
import time

import numpy as np

from mrexplore.boxes import cells_of
from mrexplore.cli import run_script
from mrexplore.config import MapConfig
from mrexplore.maps.loaders import load_map
from mrexplore.paths.distance_field import distance_fields


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--map", default="../shared/maps/kth_floorplans/50010535_PLAN1.yaml")
    ap.add_argument("--resolution", type=float, default=0.05)
    ap.add_argument("--sources", type=int, default=16)
    ap.add_argument("--repeats", type=int, default=5)
    args = ap.parse_args()
    truth = load_map(args.map, MapConfig(resolution_m=args.resolution))
    free = np.ascontiguousarray(~truth.occupied)
    cells = cells_of(free)
    sources = cells[np.random.default_rng(0).integers(0, len(cells), args.sources)]
    distance_fields(free[:40, :40], np.array([[1, 1]]))  # compile outside the timing
    times = []
    for _ in range(args.repeats):
        t = time.perf_counter()
        distance_fields(free, sources)
        times.append((time.perf_counter() - t) * 1e3)
    print(f"{truth.name}: {free.size / 1e6:.1f} M cells, {free.sum() / 1e6:.1f} M free, {args.sources} fields")
    print("ms per call: " + " ".join(f"{t:.0f}" for t in times) + f"; median {np.median(times):.0f}")


if __name__ == "__main__":
    sys.exit(run_script(main))
