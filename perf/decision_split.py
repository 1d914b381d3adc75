"""Where a centre decision's time goes, part by part, without a profiler's overhead: wall-clock timers
wrapped around the decision's parts for the first steps of one mission.

    python perf/decision_split.py                                   # utility, 8 robots, largest HouseExpo map
    python perf/decision_split.py --strategy hier --robots 8 --steps 300
    python perf/decision_split.py --map ../shared/maps/kth_floorplans/50010535_PLAN1.yaml --strategy hier \
        --from-coverage 0.5 --decisions 20

Parts: the centre's merged state (``state``: each robot's map brought up to date, ``update``, where
its delta fell, or ``rebuild`` whole; the closing and the frontiers redone round what changed; parts an
older checkout lacks are left out), frontier detection where the strategy does it, Mean-Shift, the
robots' distance fields, the global assignment, layer 3 (``route``, one call per robot; for ``hier`` its
sub-clustering, candidate distances and order search) and the paths read off the fields; on a large floor
the pooled coarse grid (with the portal graph brought up to date) and the near/far fields (the searches
over blocks or over the portal graph, and the portal graph's reads). Prints the decision's median and each part's
milliseconds per decision. Parts nest (indented under the part that holds them), so they do not add up
to the decision. With ``--from-coverage`` the mission first runs untimed
until the team's coverage reaches it, then the next ``--decisions`` decisions are timed (the mission's own
replanning, as :mod:`profile_decision` does): late decisions on a whole floor.
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
from bench_step_and_decision import largest_houseexpo

import mrexplore.local_planning.router as router
import mrexplore.paths.far_field as far_field
import mrexplore.preprocessing.reconstruction as reconstruction
import mrexplore.strategies as strategies
from mrexplore.cli import run_script
from mrexplore.config import MapConfig, MissionConfig, RunConfig, SimConfig, read_config_file
from mrexplore.maps.loaders import load_map
from mrexplore.mission import Mission

try:
    import mrexplore.paths.portals as portals
except ImportError:  # an older checkout (``PYTHONPATH`` at it) has no portal graph
    portals = None

PARTS: tuple[tuple[Any, str, str], ...] = (
    (reconstruction.CentreMap, "state", "state"),
    (reconstruction.CentreMap, "_update", "  update (per robot)"),
    (reconstruction, "_rebuild_into", "  rebuild (whole robot)"),
    (reconstruction, "close_unknown_holes", "  closing"),
    (reconstruction, "redetect_frontiers", "  frontiers"),
    (strategies, "detect_frontiers", "frontiers"),
    (strategies, "cluster_frontiers", "mean-shift"),
    (strategies, "distance_fields", "distance fields"),
    (strategies, "coarse_grid", "coarse grid"),
    (portals and portals.PortalGraph, "refresh", "  portal graph kept"),
    (strategies, "far_fields", "near/far fields"),
    (far_field, "_seeded_search", "  coarse searches"),
    (portals and portals.PortalGraph, "search_from", "  portal searches"),
    (portals and portals.PortalField, "values", "  portal reads"),
    (far_field.CoarseGrid, "exact_at", "  exact searches back"),
    (far_field, "distance_fields", "  exact near fields, paths"),
    (strategies.ExplorationPipeline, "assign", "assignment"),
    (strategies.ExplorationPipeline, "route", "route (per robot)"),
    (router, "cluster_frontiers", "  sub-clustering"),
    (router, "pairwise_distances", "  candidate distances"),
    (router, "reversal_search", "  order search"),
    (strategies, "descend_path", "paths"),
)


def timed(fn: Callable[..., Any], spent: list[float]) -> Callable[..., Any]:
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        t = time.perf_counter()
        try:
            return fn(*args, **kwargs)
        finally:
            spent.append(time.perf_counter() - t)

    return wrapper


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--map", type=Path, default=None, help="default: the largest HouseExpo map")
    ap.add_argument("--strategy", default="utility")
    ap.add_argument("--robots", type=int, default=8)
    ap.add_argument("--steps", type=int, default=300)
    ap.add_argument("--resolution", type=float, default=0.05)
    ap.add_argument("--from-coverage", type=float, default=None, help="time from this coverage (0-1) on")
    ap.add_argument("--decisions", type=int, default=20, help="decisions timed with --from-coverage")
    ap.add_argument("--config", type=Path, help="a run config (YAML) whose planning settings to use")
    args = ap.parse_args()
    cfg = read_config_file(args.config) if args.config else RunConfig()
    late = args.from_coverage is not None
    spent: dict[str, list[float]] = {}
    truth = load_map(args.map or largest_houseexpo(), MapConfig(resolution_m=args.resolution))
    mission = Mission(
        truth,
        strategies.make_strategy(
            args.strategy, cfg.global_planning, cfg.preprocess, cfg.local_planning, coscan_cfg=cfg.coscan
        ),
        SimConfig(robots=args.robots),
        MissionConfig(100_000) if late else MissionConfig(args.steps, 10),
        0,
        progress=False,
    )
    if late:
        while mission.advance():
            mission.decide()
            if mission.curve[-1] >= args.from_coverage:
                break
    for owner, name, label in PARTS:
        if hasattr(owner, name):  # parts an older checkout lacks (``PYTHONPATH`` at it) are left out
            spent[label] = []
            setattr(owner, name, timed(getattr(owner, name), spent[label]))
    first = len(mission.plan_ms)
    while (not late or len(mission.plan_ms) - first < args.decisions) and mission.advance():
        mission.decide()
    ms = np.asarray(mission.plan_ms[first:])
    n = len(ms)
    when = f"from coverage {args.from_coverage}" if late else f"{args.steps} steps"
    print(f"{truth.name}, {args.strategy}, {args.robots} robots, {when}: {n} decisions to step {mission.steps}")
    print(f"decision median {np.median(ms):.2f} ms, mean {np.mean(ms):.2f} ms, p95 {np.percentile(ms, 95):.2f} ms")
    print(f"{'part':24s} {'calls':>6s} {'ms per decision':>16s}")
    for label, times in spent.items():
        if times:
            print(f"{label:24s} {len(times):6d} {1e3 * sum(times) / max(n, 1):16.2f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(run_script(main))
