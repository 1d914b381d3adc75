"""The team plan's solver against OR-Tools' routing solver on the same min-max open routing instances: the
makespan each finds and the milliseconds it takes.

Run: python benchmarks/team_plan.py [--instances 30] [--sizes 3x20,8x60] [--limit-ms 100]
Instances: robots and cluster centres uniform in a 40 m square, Euclidean distances. OR-Tools (``pip install
ortools``, not a dependency of the package) runs twice: its first solution (path cheapest arc) improved by its
default local search until a local optimum, with no time limit, and guided local search stopped after
``--limit-ms``; each route ends at a free dummy node (open routes), the makespan is its span cost (global span
coefficient), distances in centimetres.
"""

from __future__ import annotations

import argparse
import sys
import time

import numpy as np
from _common import run_script

from mrexplore.global_planning.team_plan import plan_routes


def ortools_makespan(start: np.ndarray, between: np.ndarray, limit_ms: int | None) -> float:
    """The makespan of OR-Tools' plan (metres): its local optimum where ``limit_ms`` is None, else guided local
    search for ``limit_ms``."""
    from ortools.constraint_solver import pywrapcp, routing_enums_pb2

    n_r, n_k = start.shape
    # Nodes: clusters 0..K-1, each robot's start K..K+R-1, one shared free end K+R.
    n = n_k + n_r + 1
    d = np.zeros((n, n))
    d[:n_k, :n_k] = between
    d[n_k : n_k + n_r, :n_k] = start
    d[:, n_k + n_r] = 0.0  # ending anywhere is free
    d[n_k + n_r, :] = 0.0
    cm = np.round(d * 100).astype(np.int64)
    manager = pywrapcp.RoutingIndexManager(n, n_r, [n_k + i for i in range(n_r)], [n_k + n_r] * n_r)
    routing = pywrapcp.RoutingModel(manager)

    def cost(i: int, j: int) -> int:
        return int(cm[manager.IndexToNode(i), manager.IndexToNode(j)])

    transit = routing.RegisterTransitCallback(cost)
    routing.SetArcCostEvaluatorOfAllVehicles(transit)
    routing.AddDimension(transit, 0, int(cm.sum()) + 1, True, "distance")
    routing.GetDimensionOrDie("distance").SetGlobalSpanCostCoefficient(100)
    params = pywrapcp.DefaultRoutingSearchParameters()
    params.first_solution_strategy = routing_enums_pb2.FirstSolutionStrategy.PATH_CHEAPEST_ARC
    if limit_ms is not None:
        params.local_search_metaheuristic = routing_enums_pb2.LocalSearchMetaheuristic.GUIDED_LOCAL_SEARCH
        params.time_limit.FromMilliseconds(limit_ms)
    solution = routing.SolveWithParameters(params)
    dim = routing.GetDimensionOrDie("distance")
    return max(solution.Value(dim.CumulVar(routing.End(v))) for v in range(n_r)) / 100.0


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--instances", type=int, default=30)
    ap.add_argument("--sizes", default="3x20,8x60", help="comma-separated ROBOTSxCLUSTERS")
    ap.add_argument("--limit-ms", type=int, default=100)
    args = ap.parse_args()
    try:
        import ortools  # noqa: F401
    except ImportError:
        print("skipped: OR-Tools is not installed (pip install ortools)", file=sys.stderr)
        return 0
    rng = np.random.default_rng(0)
    plan_routes(np.ones((1, 1)), np.zeros((1, 1)))  # compiled before timing
    print("| robots x clusters | solver | makespan / ours (mean) | ms (median) |")
    print("| --- | --- | --- | --- |")
    for size in args.sizes.split(","):
        n_r, n_k = (int(v) for v in size.split("x"))
        rows: dict[str, list[tuple[float, float]]] = {"ours": [], "OR-Tools local optimum": [], "OR-Tools GLS": []}
        for _ in range(args.instances):
            pts, robots = rng.uniform(0, 40, (n_k, 2)), rng.uniform(0, 40, (n_r, 2))
            start = np.linalg.norm(robots[:, None] - pts[None], axis=2)
            between = np.linalg.norm(pts[:, None] - pts[None], axis=2)
            t = time.perf_counter()
            ours = plan_routes(start, between).makespan
            rows["ours"].append((ours, time.perf_counter() - t))
            for name, limit in (("OR-Tools local optimum", None), ("OR-Tools GLS", args.limit_ms)):
                t = time.perf_counter()
                value = ortools_makespan(start, between, limit)
                rows[name].append((value, time.perf_counter() - t))
        base = np.array([v for v, _ in rows["ours"]])
        for name, got in rows.items():
            ratio = np.mean(np.array([v for v, _ in got]) / base)
            print(f"| {n_r} x {n_k} | {name} | {ratio:.3f} | {1e3 * np.median([s for _, s in got]):.2f} |")
    return 0


if __name__ == "__main__":
    sys.exit(run_script(main))
