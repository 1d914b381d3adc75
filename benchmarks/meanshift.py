"""Mean-Shift on real frontiers: the package's ``mean_shift`` against scikit-learn's ``MeanShift``.

Run: python benchmarks/meanshift.py [--map PATH] [--robots 8] [--steps 300] [--repeats 3]
     python benchmarks/meanshift.py --map ../shared/maps/kth_floorplans/50010535_PLAN1.yaml --from-coverage 0.6

The F_un cells of every decision of one mission (``utility``, 0.05 m, the largest HouseExpo map by default)
are clustered with the bandwidth rule of layer 1 (its bound included) by both implementations; the modes
and labels must be equal (the script stops otherwise), and the mean milliseconds per clustering are
printed, with the bin seeding's share. With ``--from-coverage`` the mission first runs untimed until the
team's coverage reaches it, then the F_un cells of the next ``--sets`` decisions are kept: a late
mission's frontiers, spread over the floor.
"""

from __future__ import annotations

import argparse
import sys
import time
import warnings
from pathlib import Path

import numpy as np
from _common import largest_houseexpo, run_script
from sklearn.cluster import MeanShift

from mrexplore.config import MapConfig, MissionConfig, PreprocessConfig, SimConfig
from mrexplore.maps.loaders import load_map
from mrexplore.mission import Mission, MissionSpec
from mrexplore.pipeline import make_strategy
from mrexplore.preprocessing.clustering import bin_seeds, bounded_bandwidth, mean_shift
from mrexplore.preprocessing.frontiers import detect_frontiers


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--map", type=Path, default=None, help="default: the largest HouseExpo map")
    ap.add_argument("--robots", type=int, default=8)
    ap.add_argument("--steps", type=int, default=300)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--from-coverage", type=float, default=None, help="keep frontiers from this coverage (0-1) on")
    ap.add_argument("--sets", type=int, default=10, help="frontier sets kept with --from-coverage")
    args = ap.parse_args()
    truth = load_map(args.map or largest_houseexpo(), MapConfig(resolution_m=0.05))
    late = args.from_coverage is not None
    budget = MissionConfig(100_000) if late else MissionConfig(args.steps)
    mission = Mission(
        MissionSpec(truth, make_strategy("utility"), SimConfig(robots=args.robots), budget, 0), progress=False
    )
    sets: list[np.ndarray] = []
    while (not late or len(sets) < args.sets) and mission.advance():
        mission.decide()
        if late and mission.record.curve[-1] < args.from_coverage:
            continue
        cells = detect_frontiers(mission.state).un_rc.astype(np.float64)
        if len(cells) > 2:
            sets.append(cells)
    cfg = PreprocessConfig()
    bound = None if cfg.bandwidth_max_m is None else cfg.bandwidth_max_m / truth.resolution_m
    ours = theirs = binning = 0.0
    for pts in sets:
        bw = max(bounded_bandwidth(pts, cfg.bandwidth_percentile, cfg.bandwidth_sample, bound), 1.0)
        for _ in range(args.repeats):
            t = time.perf_counter()
            modes, labels = mean_shift(pts, bw)
            ours += time.perf_counter() - t
            t = time.perf_counter()
            bin_seeds(pts, bw)
            binning += time.perf_counter() - t
        t = time.perf_counter()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # sklearn warns where binning leaves one seed per point
            ref = MeanShift(bandwidth=bw, bin_seeding=True).fit(pts)
        theirs += time.perf_counter() - t
        if not (np.allclose(modes, ref.cluster_centers_) and np.array_equal(labels, ref.labels_)):
            print("mean_shift and sklearn differ on a frontier set", file=sys.stderr)
            return 1
    n = len(sets)
    print(
        f"{truth.name}: {n} frontier sets of {np.mean([len(s) for s in sets]):.0f} cells on average; "
        f"mean_shift {ours / n / args.repeats * 1e3:.2f} ms (its bin seeds {binning / n / args.repeats * 1e3:.2f}), "
        f"sklearn MeanShift {theirs / n * 1e3:.1f} ms per clustering, same modes and labels"
    )
    return 0


if __name__ == "__main__":
    sys.exit(run_script(main))
