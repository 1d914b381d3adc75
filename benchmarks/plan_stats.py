"""Layout statistics of map sets: how the procedural training plans compare with the dev HouseExpo plans.

Run: python benchmarks/plan_stats.py [--plans 200] [--resolution 0.1] [--sets houseexpo generated varied] [--png PATH]
(--png: also draw the first 18 plans of the last procedural set named.)
For each set it prints the 10th / 50th / 90th percentiles over its maps of:
- ``box m2``: the bounding box of the explorable free space, m²;
- ``free m2``: the explorable free area (reachable from the start), m²;
- ``fill``: free area / bounding-box area (1 for a rectangular building; HouseExpo's outlines are not);
- ``rooms``: pieces of free space left when every cell within 0.55 m of a wall is removed, of 1 m² or more
  (doors and passages under 1.1 m cut them apart; an estimate, the same rule for every set);
- ``room m2``: mean free area per room;
- ``clear m``: median clearance (distance to the nearest wall) over free cells: corridors are low, halls high;
- ``wall m/m2``: free-cell edges against walls per m² of free space (rooms, clutter and detail raise it).
Sets: ``houseexpo`` (the dev plans in ../shared/maps/houseexpo), ``generated`` (``generated:SEED``, the fixed
16 x 12 m built-in plan), ``varied`` (``varied:SEED``, the training plans), seeds 0 .. plans - 1.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
from _common import run_script
from scipy import ndimage

from mrexplore.bench.runner import expand_maps
from mrexplore.config import MapConfig
from mrexplore.maps.ground_truth import explorable_region
from mrexplore.maps.loaders import load_map
from mrexplore.runtime.example_maps import maps_dir
from mrexplore.sim.starts import draw_starts
from mrexplore.types import MrExploreError

HOUSEEXPO = maps_dir() / "houseexpo"
ROOM_CLEARANCE_M = 0.55
SETS = ("houseexpo", "generated", "varied")
STATS = ("box m2", "free m2", "fill", "rooms", "room m2", "clear m", "wall m/m2")


def plan_stats(spec: str, res: float) -> dict[str, float]:
    """The statistics of one map (see the module's docstring)."""
    truth = load_map(spec, MapConfig(resolution_m=res))
    starts = draw_starts(truth, 1, 1.0, np.random.default_rng(0))
    free = explorable_region(truth.occupied, starts) & ~truth.occupied
    rows, cols = np.nonzero(free)
    box = (rows.max() - rows.min() + 1) * (cols.max() - cols.min() + 1) * res * res
    area = float(free.sum()) * res * res
    clearance = ndimage.distance_transform_edt(np.pad(free, 1)) * res
    core = clearance > ROOM_CLEARANCE_M
    labels, n = ndimage.label(core, structure=np.ones((3, 3), bool))
    sizes = np.bincount(labels.ravel())[1:] * res * res
    rooms = max(1, int((sizes >= 1.0).sum()))
    padded = np.pad(free, 1)
    edges = sum(int((padded & ~np.roll(padded, s, axis=a)).sum()) for a in (0, 1) for s in (1, -1))
    return {
        "box m2": box,
        "free m2": area,
        "fill": area / box,
        "rooms": rooms,
        "room m2": area / rooms,
        "clear m": float(np.median(clearance[padded])),
        "wall m/m2": edges * res / area,
    }


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--plans", type=int, default=200, help="procedural plans per set (seeds 0 .. plans - 1)")
    ap.add_argument("--resolution", type=float, default=0.1, help="cell size, metres (default 0.1)")
    ap.add_argument("--sets", nargs="+", default=list(SETS), choices=SETS)
    ap.add_argument("--png", type=Path, default=None, help="draw the first 18 plans of the last procedural set")
    args = ap.parse_args()
    if args.png is not None and not args.png.parent.is_dir():
        raise MrExploreError(f"no folder {args.png.parent} for --png; create it or pick another path")
    print(f"percentiles 10 / 50 / 90 over each set's maps at {args.resolution} m")
    print(f"{'set':10s} {'maps':>5s}  " + "  ".join(f"{s:>18s}" for s in STATS))
    for name in args.sets:
        if name == "houseexpo":
            if not HOUSEEXPO.is_dir():
                print(f"skipped houseexpo: maps not found at {HOUSEEXPO}", file=sys.stderr)
                continue
            specs = expand_maps([str(HOUSEEXPO)])
        else:
            specs = [f"{name}:{i}" for i in range(args.plans)]
        rows = [plan_stats(s, args.resolution) for s in specs]
        cells = []
        for stat in STATS:
            p10, p50, p90 = np.percentile([r[stat] for r in rows], [10, 50, 90])
            fmt = ".2f" if max(abs(p10), abs(p90)) < 10 else ".0f"
            cells.append(f"{p10:{fmt}} / {p50:{fmt}} / {p90:{fmt}}".rjust(18))
        print(f"{name:10s} {len(rows):5d}  " + "  ".join(cells))
    drawn = [s for s in args.sets if s != "houseexpo"]
    if args.png is not None and drawn:
        draw(drawn[-1], args.resolution, args.png)
        print(f"wrote {args.png}")
    return 0


def draw(name: str, res: float, path: Path) -> None:
    """The first 18 plans of a procedural set, free space white, in metres."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(3, 6, figsize=(15, 7.5))
    for i, ax in enumerate(axes.ravel()):
        truth = load_map(f"{name}:{i}", MapConfig(resolution_m=res))
        h, w = truth.shape
        ax.imshow(~truth.occupied, cmap="gray", origin="lower", extent=(0, w * res, 0, h * res))
        ax.set_title(f"{name}:{i}", fontsize=9)
        ax.tick_params(labelsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=60)
    plt.close(fig)


if __name__ == "__main__":
    sys.exit(run_script(main))
