"""Learned global layer speed: policy inference per decision (NumPy, as the strategies decide, beside torch,
as they train), and a whole decision of learned hier against utility and hier-heuristic on the largest
HouseExpo map.

Run: python benchmarks/policy_inference.py [--robots 8] [--clusters 60] [--steps 300]
Targets on the 2-core dev machine: inference <= 5 ms per decision at 8 robots and 60 clusters, NumPy no
slower than torch. A whole decision of learned hier at 8 robots is reported beside utility's and
hier-heuristic's (the local layer's routes are most of what it adds).
"""

from __future__ import annotations

import argparse
import sys
import time

import numpy as np
from _common import houseexpo_dir, largest_houseexpo, run_script

from mrexplore.config import MissionConfig, SimConfig
from mrexplore.global_planning.learned.ncm_planner import NcmPlanner
from mrexplore.global_planning.learned.policy import LearnedPlanner
from mrexplore.global_planning.learned.policy_file import load_ncm_policy_np, load_policy_np
from mrexplore.global_planning.protocol import AssignmentProblem
from mrexplore.maps.loaders import load_map
from mrexplore.mission import Mission, MissionSpec
from mrexplore.pipeline import make_strategy
from mrexplore.preprocessing.clustering import Clusters


def planner_of(strategy: str, backend: str) -> LearnedPlanner | NcmPlanner:
    """The shipped policy of ``strategy`` (hier, or ncm) on the NumPy network or the torch one."""
    if backend == "torch":
        from mrexplore.training.checkpoint import load_ncm_policy, load_policy

        return LearnedPlanner(load_policy().net) if strategy == "hier" else NcmPlanner(load_ncm_policy().net)
    return LearnedPlanner(load_policy_np().net) if strategy == "hier" else NcmPlanner(load_ncm_policy_np().net)


def inference_ms(
    robots: int, clusters: int, strategy: str = "hier", backend: str = "numpy", repeats: int = 200
) -> tuple[float, float]:
    """Median and p95 ms of a learned planner's assign() (inputs, network, decoding) on random problems."""
    rng = np.random.default_rng(0)
    planner = planner_of(strategy, backend)
    times = []
    for _ in range(repeats):
        centres = rng.integers(0, 400, size=(clusters, 2)).astype(np.int32)
        sizes = rng.integers(2, 80, size=clusters).astype(np.int32)
        labels = np.repeat(np.arange(clusters, dtype=np.int32), sizes)
        c = Clusters(centres, sizes, np.repeat(centres, sizes, 0), labels)
        dist = rng.uniform(5, 400, size=(robots, clusters))
        p = AssignmentProblem(
            rng.integers(0, 400, size=(robots, 2)).astype(np.int32),
            c,
            dist,
            0.05,
            np.zeros((400, 400), np.uint8),
            current_cluster=rng.integers(-1, clusters, size=robots),
        )
        t = time.perf_counter()
        planner.assign(p)
        times.append((time.perf_counter() - t) * 1e3)
    return float(np.median(times[10:])), float(np.percentile(times[10:], 95))


def decision_ms(strategy: str, robots: int, steps: int) -> float:
    """Median ms of the centre's decisions over the first ``steps`` steps of a mission."""
    truth = load_map(largest_houseexpo())
    m = Mission(
        MissionSpec(truth, make_strategy(strategy), SimConfig(robots=robots), MissionConfig(steps, 10), 0),
        progress=False,
    )
    while m.advance():
        m.decide()
    return float(np.median(m.record.plan_ms))


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--robots", type=int, default=8)
    ap.add_argument("--clusters", type=int, default=60)
    ap.add_argument("--steps", type=int, default=300)
    args = ap.parse_args()
    print(f"policy inference, {args.robots} robots x {args.clusters} clusters (median, p95 ms):")
    for strategy in ("hier", "ncm"):
        got = {}
        for backend in ("numpy", "torch"):
            inference_ms(2, 5, strategy, backend, 20)  # warm up
            got[backend] = inference_ms(args.robots, args.clusters, strategy, backend)
        (nm, np95), (tm, tp95) = got["numpy"], got["torch"]
        print(f"  {strategy:5s} numpy {nm:6.2f} {np95:6.2f}   torch {tm:6.2f} {tp95:6.2f}   numpy/torch {nm / tm:.2f}")
    if not houseexpo_dir().is_dir():
        print(f"skipped the decision timings: HouseExpo maps not found at {houseexpo_dir()}", file=sys.stderr)
        return 0
    decision_ms("utility", 2, 20)  # compile the numba kernels outside the timings
    print(f"decision on {largest_houseexpo().stem}, {args.robots} robots, first {args.steps} steps (median ms):")
    base = decision_ms("utility", args.robots, args.steps)
    for s in ("utility", "hier-heuristic", "hier"):
        ms = base if s == "utility" else decision_ms(s, args.robots, args.steps)
        print(f"  {s:15s} {ms:7.2f}  ({ms / base:.2f}x utility)")
    return 0


if __name__ == "__main__":
    sys.exit(run_script(main))
