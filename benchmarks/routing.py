"""Median milliseconds of the local routing search (paper IV-C) for 30 candidates, and how often it is optimal.

Run: python benchmarks/routing.py [--candidates 30] [--instances 200] [--optimality 2000]
Target on the 2-core dev machine: <= 5 ms median for 30 candidates.
Instances: candidates uniform in a 20 m square, gains 2-60 members, Euclidean distances.
--optimality N: on N instances of 2-7 candidates, the share where the reversal search reaches the
brute-force optimum over all orders, and the median shortfall where it does not.
"""

from __future__ import annotations

import argparse
import itertools
import sys
import time

import numpy as np
from _common import run_script

from mrexplore.config import LocalPlanningConfig
from mrexplore.local_planning.routing import RouteProblem, reversal_search


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--candidates", type=int, default=30)
    ap.add_argument("--instances", type=int, default=200)
    ap.add_argument("--optimality", type=int, default=0)
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
    if args.optimality:
        optimal, gaps = 0, []
        for _ in range(args.optimality):
            n = int(rng.integers(2, 8))
            pts = rng.uniform(0, 20, (n + 1, 2))
            d = np.linalg.norm(pts[:, None] - pts[None], axis=2)
            problem = RouteProblem(rng.integers(2, 60, n).astype(float), d[0, 1:], d[1:, 1:], cfg)
            _, u = reversal_search(problem)
            best = max(problem.utility(np.array(q)) for q in itertools.permutations(range(n)))
            if u >= best - 1e-9:
                optimal += 1
            else:
                gaps.append(best - u)
        print(
            f"optimal on {optimal} of {args.optimality} instances of 2-7 candidates "
            f"({100 * optimal / args.optimality:.1f}%); median shortfall elsewhere "
            f"{np.median(gaps) if gaps else 0:.3f} utility units (a candidate's gain is 1.8-5)"
        )
    return 0


if __name__ == "__main__":
    sys.exit(run_script(main))
