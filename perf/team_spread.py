"""How a team spreads over the frontier, phase by phase: what limits a large team on a whole floor.

    python perf/team_spread.py --map ../shared/maps/kth_floorplans/50010535_PLAN1.yaml --robots 16
    python perf/team_spread.py --map ../shared/maps/kth_floorplans/50010535_PLAN1.yaml --robots 8 --seed 1

Runs one whole mission with the strategy's own decisions and, for every decision, reads what the centre
offered and chose: the candidate clusters, how many robots got a cluster of their own, and each robot's
straight-line distance from its goal to the nearest other robot's goal. Decisions are grouped by the
team's coverage when they were taken (below 25%, 25-75%, 75-99%, the tail). Two robots whose goals lie
within a sensor range (6 m) of each other largely see the same cells when they get there.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path
from typing import NamedTuple

import numpy as np

from mrexplore.cli import run_script
from mrexplore.config import MapConfig, SimConfig
from mrexplore.global_planning.protocol import UNASSIGNED
from mrexplore.maps.loaders import load_map
from mrexplore.mission import Mission
from mrexplore.strategies import make_strategy

PHASES = ((0.0, 0.25), (0.25, 0.75), (0.75, 0.99), (0.99, 1.01))
"""Coverage bounds of the phases, [low, high)."""


class _Seen(NamedTuple):
    """What one decision offered and chose."""

    coverage: float
    clusters: int
    assigned: int
    """Robots given a cluster."""
    distinct: int
    """Distinct clusters among theirs."""
    nearest_m: np.ndarray
    """Each goal's distance to the nearest other goal (:func:`nearest_other_m`)."""


def nearest_other_m(goals_rc: np.ndarray, resolution_m: float) -> np.ndarray:
    """``(k,) float64`` each goal's straight-line distance to the nearest other goal, metres (``inf`` alone).

    Examples
    --------
    >>> nearest_other_m(np.array([[0, 0], [0, 30], [40, 0]]), 0.1).tolist()
    [3.0, 3.0, 4.0]
    """
    g = np.asarray(goals_rc, dtype=np.float64) * resolution_m
    d = np.hypot(g[:, None, 0] - g[None, :, 0], g[:, None, 1] - g[None, :, 1])
    np.fill_diagonal(d, np.inf)
    return d.min(axis=1) if len(g) else np.zeros(0)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--map", type=Path, required=True)
    ap.add_argument("--strategy", default="hier")
    ap.add_argument("--robots", type=int, default=16)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--resolution", type=float, default=0.05)
    ap.add_argument("--sensor-m", type=float, default=6.0, help="the distance counted as seeing the same cells")
    args = ap.parse_args()
    truth = load_map(args.map, MapConfig(resolution_m=args.resolution))
    mission = Mission(
        truth, make_strategy(args.strategy), SimConfig(robots=args.robots), seed=args.seed, progress=False
    )
    t0 = time.perf_counter()
    rows: list[_Seen] = []
    while mission.advance():
        coverage = mission.curve[-1]
        decision = mission.decide()
        if decision is None or decision.done_reason is not None:
            continue
        chosen = decision.assignment.cluster_of_robot
        chosen = chosen[chosen != UNASSIGNED]
        goals = decision.goals_rc[decision.goals_rc[:, 0] >= 0]
        near = nearest_other_m(goals, truth.resolution_m)
        rows.append(_Seen(coverage, len(decision.clusters), len(chosen), len(set(chosen.tolist())), near))
    print(
        f"{truth.name}, {args.strategy}, {args.robots} robots, seed {args.seed}: {mission.steps} steps, "
        f"{len(rows)} decisions, {time.perf_counter() - t0:.0f} s\n"
    )
    print(
        "| coverage | decisions | clusters | distinct clusters chosen per robot | nearest other goal, median m "
        f"| goals within {args.sensor_m:g} m of another |"
    )
    print("| --- | --- | --- | --- | --- | --- |")
    for lo, hi in PHASES:
        sel = [r for r in rows if lo <= r.coverage < hi]
        if not sel:
            continue
        near = np.concatenate([r.nearest_m for r in sel])
        near = near[np.isfinite(near)]
        own = np.mean([r.distinct / max(r.assigned, 1) for r in sel])
        print(
            f"| {lo:.2f}-{min(hi, 1.0):.2f} | {len(sel)} | {np.mean([r.clusters for r in sel]):.1f} | {own:.2f} "
            f"| {np.median(near):.1f} | {np.mean(near <= args.sensor_m):.2f} |"
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(run_script(main))
