"""Time of the distance fields a decision computes: whole fields from random free cells of a floor.

    python benchmarks/fields.py --map ../shared/maps/kth_floorplans/50010535_PLAN1.yaml --sources 16

Prints the grid, and the wall time of ``distance_fields`` from ``--sources`` cells drawn from the free
cells (seed 0), once per repeat, on the shared threads: late in a mission, when the known floor is as
large as the map, this is what each decision pays for its fields.

    python benchmarks/fields.py --map ../shared/maps/houseexpo/png/76d71987631686644bcebcbad31c9a50.png \
        --pairwise 12 --sources 30 --repeats 60

With ``--pairwise BOX_M``: the local layer's distances between ``--sources`` candidates drawn in a box of
BOX_M metres around a random free cell, once per repeat: ``pairwise_distances`` (each pair searched once)
against one field per candidate read at all of them (what routing did before); both must agree.
"""

from __future__ import annotations

import argparse
import sys
import time

import numpy as np
from _common import run_script

from mrexplore.config import MapConfig
from mrexplore.maps.boxes import cells_of
from mrexplore.maps.loaders import load_map
from mrexplore.paths.distance_field import distance_fields, pairwise_distances


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--map", default="../shared/maps/kth_floorplans/50010535_PLAN1.yaml")
    ap.add_argument("--resolution", type=float, default=0.05)
    ap.add_argument("--sources", type=int, default=16)
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--pairwise", type=float, default=None, metavar="BOX_M", help="time candidate distances")
    args = ap.parse_args()
    if args.pairwise is not None:
        pairwise(args)
        return
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


def pairwise(args: argparse.Namespace) -> None:
    truth = load_map(args.map, MapConfig(resolution_m=args.resolution))
    free = ~truth.occupied
    rng = np.random.default_rng(0)
    cells = cells_of(free)
    half = int(args.pairwise / 2 / args.resolution)
    pairwise_distances(free[:40, :40], np.array([[1, 1], [2, 2]]))  # compile outside the timing
    fields_ms, pairs_ms = [], []
    for _ in range(args.repeats):
        c = cells[rng.integers(len(cells))]
        r0, c0 = np.maximum(c - half, 0)
        r1, c1 = np.minimum(c + half, free.shape)
        box = np.ascontiguousarray(free[r0:r1, c0:c1])
        inside = cells_of(box)
        pts = inside[rng.integers(0, len(inside), args.sources)]
        t = time.perf_counter()
        every = np.array([f.at(pts) for f in distance_fields(box, pts, pts)])
        fields_ms.append((time.perf_counter() - t) * 1e3)
        t = time.perf_counter()
        once = pairwise_distances(box, pts)
        pairs_ms.append((time.perf_counter() - t) * 1e3)
        if not np.allclose(np.minimum(every, every.T), once, rtol=1e-6):
            raise SystemExit("pairwise_distances disagrees with the fields: a bug")
    print(f"{truth.name}: {args.sources} candidates in {args.pairwise:g} m boxes, {args.repeats} boxes (seed 0)")
    print(f"median ms: a field per candidate {np.median(fields_ms):.2f}, pairwise {np.median(pairs_ms):.2f}")


if __name__ == "__main__":
    sys.exit(run_script(main))
