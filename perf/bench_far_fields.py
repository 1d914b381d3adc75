"""Exact fields against near/far ones late in a mission: time per decision and the error of the estimates.

    python perf/bench_far_fields.py --robots 16 --coverage 0.3 0.5
    python perf/bench_far_fields.py --map ../shared/maps/kth_floorplans/50010536_PLAN3.yaml --robots 8

Runs one `hier` mission (0.05 m, seed 0, distances exact throughout) until the team's coverage reaches each
``--coverage``, and at the next decision computes every robot's distances both ways on the same grid: the
exact fields (stopped at every cluster centre and member, as the centre did before) and the near/far fields
of `paths/far_field.py` (exact within ``--radius-m``, blocks of ``--block-m`` beyond). Prints the time of
each (best of ``--repeats``, on the threads ``MREXPLORE_THREADS`` allows) and, over every robot-centre
pair, the relative error of the far distances (estimate / exact - 1) and how many pairs are exact.
"""

from __future__ import annotations

import argparse
import sys
import time

import numpy as np

from mrexplore.cli import run_script
from mrexplore.config import GlobalPlanningConfig, MapConfig, MissionConfig, SimConfig
from mrexplore.maps.loaders import load_map
from mrexplore.mission import Mission, MissionSpec
from mrexplore.paths.distance_field import distance_fields
from mrexplore.paths.far_field import far_fields
from mrexplore.pipeline import ExplorationPipeline, make_strategy


def _best_ms(repeats: int, fn, *args) -> tuple[float, list]:  # type: ignore[no-untyped-def]
    best, out = np.inf, []
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = fn(*args)
        best = min(best, (time.perf_counter() - t0) * 1e3)
    return best, out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--map", default="../shared/maps/kth_floorplans/50010535_PLAN1.yaml")
    ap.add_argument("--robots", type=int, default=16)
    ap.add_argument("--coverage", type=float, nargs="+", default=[0.3, 0.5])
    ap.add_argument("--radius-m", type=float, default=GlobalPlanningConfig().exact_radius_m)
    ap.add_argument("--block-m", type=float, default=GlobalPlanningConfig().coarse_cell_m)
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args()
    res = 0.05
    truth = load_map(args.map, MapConfig(resolution_m=res))
    exact_only = GlobalPlanningConfig(far_above_cells=2**62)
    strategy = make_strategy("hier", exact_only)
    caught: list[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]] = []
    real = ExplorationPipeline._fields

    def spy(self, passable, robots_rc, targets_rc, must_rc, own_rc, resolution_m, computed):  # type: ignore[no-untyped-def]
        caught.append((passable.copy(), robots_rc.copy(), targets_rc.copy(), must_rc.copy()))
        return real(self, passable, robots_rc, targets_rc, must_rc, own_rc, resolution_m, computed)

    ExplorationPipeline._fields = spy  # type: ignore[method-assign]
    mission = Mission(
        MissionSpec(truth, strategy, SimConfig(robots=args.robots), MissionConfig(max_steps=100_000)), progress=False
    )
    radius, factor = round(args.radius_m / res), round(args.block_m / res)
    print(f"{truth.name}, {args.robots} robots, exact within {radius} cells, blocks of {factor} cells")
    for target in sorted(args.coverage):
        while mission.advance():
            caught.clear()
            mission.decide()
            if mission.record.curve[-1] >= target and caught:
                break
        if not caught:
            print(f"coverage {target}: the mission ended first")
            break
        passable, robots, targets, centres = caught[-1]
        t_exact, exact = _best_ms(args.repeats, distance_fields, passable, robots, targets)
        t_far, far = _best_ms(args.repeats, far_fields, passable, robots, radius, factor, centres)
        e = np.stack([f.at(centres) for f in exact])
        a = np.stack([f.at(centres) for f in far])
        ok = np.isfinite(e) & np.isfinite(a)
        rel = a[ok] / np.maximum(e[ok], 1e-9) - 1.0
        exact_pairs = int(np.count_nonzero(e[ok] <= radius))
        q = np.percentile(rel, [50, 90, 99, 100])
        print(
            f"coverage {mission.record.curve[-1]:.3f} (step {mission.steps}), {len(centres)} centres, "
            f"{np.count_nonzero(passable):,} passable cells: exact fields {t_exact:.0f} ms, near/far {t_far:.0f} ms; "
            f"pairs {ok.sum()} ({exact_pairs} within the radius), estimate/exact - 1: median {q[0]:.4f}, "
            f"p90 {q[1]:.4f}, p99 {q[2]:.4f}, max {q[3]:.4f}, min {rel.min():.2e}; "
            f"finite exact but inf estimate: {int((np.isfinite(e) & ~np.isfinite(a)).sum())}"
        )


if __name__ == "__main__":
    sys.exit(run_script(main))
