"""Headroom of the lookahead expert: whole episodes where it takes every decision, against hier-heuristic on
the same maps, seeds and starts (paired), per dataset.

Run: python benchmarks/expert_headroom.py [--maps 6] [--robots 3] [--seeds 1] [--workers 2]
         [--datasets houseexpo,dungeon] [--world truth|known|predicted] [--predictor FILE]
It picks the first ``--maps`` maps by name of each dev dataset (HouseExpo PNGs, DungeonMaps) at 0.1 m. The
expert may use the simulator (training only): at each decision it runs its candidates (the heuristic's,
nearest's and noisy utility assignments) forward over the training horizon and takes the best return.

``--world known`` asks how much of that headroom needs the truth: the candidates run forward in the world
the team knows at the decision, every cell it has not observed a wall, and each is scored by the steps
until no frontier is left (the horizon where that takes longer); ties go to the heuristic's own choice.
Such an expert sees nothing a robot team could not, so what it gains a planner could gain at run time.

``--world predicted`` runs the candidates forward in the world the map predictor completes (the shipped one,
or ``--predictor FILE``): seen cells as they are, unseen ones a wall where the prediction says so; each is
scored by eq. 9's return over the horizon, the area term counting the cells newly seen in that world.
"""

from __future__ import annotations

import argparse
import multiprocessing
import sys
from concurrent.futures import ProcessPoolExecutor

import numpy as np
from _common import run_script

from mrexplore.bench.report import paired_bootstrap
from mrexplore.config import GlobalPlanningConfig, MapConfig, MissionConfig, SimConfig, TrainConfig
from mrexplore.global_planning.protocol import Assignment
from mrexplore.maps.loaders import load_map
from mrexplore.mission import Mission, MissionSpec
from mrexplore.pipeline import make_strategy
from mrexplore.prediction.network import load_predictor
from mrexplore.runtime.example_maps import maps_dir
from mrexplore.training.expert import (
    candidate_assignments,
    known_world_returns,
    lookahead_returns,
    predicted_world_returns,
)

MAPS = maps_dir()


def episode(args: tuple[str, int, int, bool, str, str | None]) -> int:
    """Steps of one episode, the expert deciding (True) or hier-heuristic alone (False)."""
    path, robots, seed, expert, world, predictor_file = args
    predictor = load_predictor(predictor_file) if world == "predicted" else None
    cfg = TrainConfig()
    truth = load_map(path, MapConfig(resolution_m=cfg.episodes.resolution_m))
    pipeline = make_strategy("hier-heuristic")
    m = Mission(
        MissionSpec(truth, pipeline, SimConfig(robots=robots), MissionConfig(max_steps=2000), seed), progress=False
    )
    rng = np.random.default_rng(seed)
    lookahead = known_world_returns if world == "known" else lookahead_returns
    while m.advance():
        problem = m.pose()
        if problem is None:
            break
        own = pipeline.planner.assign(problem)
        if expert:
            heuristic = GlobalPlanningConfig()
            cands = candidate_assignments(problem, own, heuristic, cfg.noisy_candidates, cfg.noise_m, rng)
            if len(cands) > 1:
                if predictor is not None:
                    p_free = predictor.p_free(problem.state, problem.resolution_m)
                    returns = predicted_world_returns(m, cands, cfg.horizon_steps, pipeline.planner, p_free)
                else:
                    returns = lookahead(m, cands, cfg.horizon_steps, pipeline.planner)
                own = Assignment(cands[int(np.argmax(returns))])
        m.commit(own)
    return m.steps


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--maps", type=int, default=6)
    ap.add_argument("--robots", type=int, default=3)
    ap.add_argument("--seeds", type=int, default=1)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--datasets", default="houseexpo,dungeon", help="comma-separated: houseexpo, dungeon")
    ap.add_argument(
        "--world", choices=("truth", "known", "predicted"), default="truth", help="where candidates run forward"
    )
    ap.add_argument("--predictor", default=None, help="predictor file of --world predicted (default: the shipped one)")
    args = ap.parse_args()
    if not MAPS.is_dir():
        print(f"skipped: dev maps not found at {MAPS}", file=sys.stderr)
        return 0
    every = {
        "houseexpo": sorted((MAPS / "houseexpo" / "png").glob("*.png"))[: args.maps],
        "dungeon": sorted((MAPS / "dungeon").glob("*.png"))[: args.maps],
    }
    sets = {name: every[name] for name in args.datasets.split(",") if name}
    ctx = multiprocessing.get_context("spawn")
    with ProcessPoolExecutor(args.workers, mp_context=ctx) as pool:
        for name, paths in sets.items():
            runs = [(str(p), s) for p in paths for s in range(args.seeds)]
            jobs = [(path, args.robots, s, e, args.world, args.predictor) for path, s in runs for e in (False, True)]
            steps = list(pool.map(episode, jobs))
            base, exp = steps[0::2], steps[1::2]
            est, lo, hi = paired_bootstrap(exp, base)
            better = sum(e < b for e, b in zip(exp, base, strict=True))
            print(
                f"{name}: {len(base)} episodes, hier-heuristic {np.mean(base):.1f} steps, expert {np.mean(exp):.1f}: "
                f"{est:+.1f}% fewer [{lo:+.1f}, {hi:+.1f}], expert better in {better}"
            )
    return 0


if __name__ == "__main__":
    sys.exit(run_script(main))
