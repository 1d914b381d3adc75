"""Median milliseconds of the local routing search (paper IV-C) for 30 candidates.

Run: python perf/bench_routing.py [--candidates 30] [--instances 200]
Target on the 2-core dev machine: <= 5 ms median for 30 candidates.
Instances: candidates uniform in a 20 m square, gains 2-60 members, Euclidean distances.
"""

from __future__ import annotations

import argparse
import sys
import time

import numpy as np

from mrexplore.config import LocalPlanningConfig
from mrexplore.local_planning.routing import RouteProblem, reversal_search


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--candidates", type=int, default=30)
    ap.add_argument("--instances", type=int, default=200)
    args = ap.parse_args()
    rng = np.random.default_rng(0)
    cfg = LocalPlanningConfig()
    times = []
    for k in range(args.instances + 1):
        pts = rng.uniform(0, 20, (args.candidates + 1, 2))
        d = np.linalg.norm(pts[:, None] - pts[None], axis=2)
        problem = RouteProblem(rng.integers(2, 60, args.candidates).astype(float), d[0, 1:], d[1:, 1:], cfg)
        t = time.perf_counter()
        reversal_search(problem)
        if k:  # the first call compiles
            times.append((time.perf_counter() - t) * 1e3)
    print(
        f"{args.candidates} candidates, {args.instances} instances: median {np.median(times):.2f} ms, "
        f"p95 {np.percentile(times, 95):.2f} ms"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
