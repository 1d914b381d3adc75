"""Headroom of the lookahead expert: whole episodes where it takes every decision, against hier-heuristic on
the same maps, seeds and starts (paired), per dataset.

Run: python benchmarks/expert_headroom.py [--maps 6] [--robots 3] [--seeds 1] [--workers 2]
         [--datasets houseexpo,dungeon] [--world truth|known|predicted] [--predictor FILE]
         [--baselines hier-heuristic,hier,utility] [--rows FILE.jsonl]
It picks the first ``--maps`` maps by name of each dev dataset (HouseExpo PNGs, DungeonMaps) at 0.1 m
(``--maps 0``: all of them). Each baseline strategy runs the same maps, seeds and starts alone, and the expert
is compared with each, paired, per dataset and per HouseExpo size class. ``--rows`` keeps one line per
finished episode; a run given the same file again runs only the episodes it lacks. The
expert may use the simulator (training only): at each decision it runs its candidates (the heuristic's,
nearest's and noisy utility assignments) forward over the training horizon and takes the best return.

``--world known`` asks how much of that headroom needs the truth: the candidates run forward in the world
the team knows at the decision, every cell it has not observed a wall, and each is scored by the steps
until no frontier is left (the horizon where that takes longer); ties go to the heuristic's own choice.
Such an expert sees nothing a robot team could not, so what it gains a planner could gain at run time.
``--baselines search,...`` adds that search over few candidates (hier's, team-plan's, hier-plan's and
utility's assignments, hier deciding in the rollouts): what a run-time search of that kind would keep.

``--world predicted`` runs the candidates forward in the world the map predictor completes (the shipped one,
or ``--predictor FILE``): seen cells as they are, unseen ones a wall where the prediction says so; each is
scored by eq. 9's return over the horizon, the area term counting the cells newly seen in that world.
"""

from __future__ import annotations

import argparse
import json
import multiprocessing
import sys
from concurrent.futures import ProcessPoolExecutor, as_completed
from pathlib import Path

import numpy as np
from _common import run_script
from numpy.typing import NDArray

from mrexplore.bench.report import paired_bootstrap
from mrexplore.bench.runner import size_class
from mrexplore.config import GlobalPlanningConfig, MapConfig, MissionConfig, SimConfig, TrainConfig
from mrexplore.global_planning.classical import UtilityPlanner
from mrexplore.global_planning.learned.policy import LearnedPlanner
from mrexplore.global_planning.protocol import Assignment, AssignmentProblem
from mrexplore.global_planning.team_plan import PlanCostPlanner, TeamPlanPlanner
from mrexplore.maps.loaders import load_map
from mrexplore.mission import Mission, MissionSpec
from mrexplore.mission.search import search_candidates
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


EXPERT = "expert"
SEARCH = "search"
"""The seen-world search over few candidates: hier's own, team-plan's, hier-plan's and utility's assignments,
run forward with hier deciding (``--baselines search,...``; ``--world known`` only)."""


def candidates_of(problem: AssignmentProblem, learned: LearnedPlanner) -> list[NDArray[np.int64]]:
    """Distinct assignments: the learned planner's first (ties go to it), then the team plan's, the learned
    cost under the plan's and utility's."""
    cfg = GlobalPlanningConfig()
    plan, plan_cost = TeamPlanPlanner(cfg), PlanCostPlanner(learned, cfg)
    return search_candidates(problem, (learned, plan, plan_cost, UtilityPlanner(cfg)))


def episode(args: tuple[str, int, int, str, str, str | None]) -> dict[str, object]:
    """One episode: the expert deciding (``who`` = ``expert``, hier-heuristic continuing its rollouts) or a
    strategy alone; its steps, coverage and the map's free area."""
    path, robots, seed, who, world, predictor_file = args
    predictor = load_predictor(predictor_file) if world == "predicted" else None
    cfg = TrainConfig()
    truth = load_map(path, MapConfig(resolution_m=cfg.episodes.resolution_m))
    pipeline = make_strategy({EXPERT: "hier-heuristic", SEARCH: "hier"}.get(who, who))
    m = Mission(
        MissionSpec(truth, pipeline, SimConfig(robots=robots), MissionConfig(max_steps=2000), seed), progress=False
    )
    rng = np.random.default_rng(seed)
    lookahead = known_world_returns if world == "known" else lookahead_returns
    while who not in (EXPERT, SEARCH) and m.advance():
        m.decide()
    while who == SEARCH and m.advance():
        problem = m.pose()
        if problem is None:
            break
        assert isinstance(pipeline.planner, LearnedPlanner)
        cands = candidates_of(problem, pipeline.planner)
        choice = Assignment(cands[0])
        if len(cands) > 1:
            returns = known_world_returns(m, cands, cfg.horizon_steps, pipeline.planner)
            choice = Assignment(cands[int(np.argmax(returns))])
        m.commit(choice)
    while who == EXPERT and m.advance():
        problem = m.pose()
        if problem is None:
            break
        own = pipeline.planner.assign(problem)
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
    area = float((m.sim.explorable & ~truth.occupied).sum()) * truth.resolution_m**2
    return {
        "map": Path(path).name,
        "robots": robots,
        "seed": seed,
        "who": who,
        "world": world,
        "steps": m.steps,
        "coverage": round(float(m.sim.coverage), 6),
        "free_m2": round(area, 2),
    }


def _classes(name: str, rows: list[dict[str, object]]) -> dict[str, list[str]]:
    maps = sorted({str(r["map"]) for r in rows})
    if name != "houseexpo":
        return {name: maps}
    area = {str(r["map"]): float(r["free_m2"]) for r in rows}  # type: ignore[arg-type]
    out: dict[str, list[str]] = {name: maps}
    for cls in ("small", "middle", "large"):
        out[f"{name} {cls}"] = [m for m in maps if size_class(area[m]) == cls]
    return out


def report(name: str, rows: list[dict[str, object]], baselines: list[str], robots: int) -> None:
    """Per class: each strategy's mean steps, and the expert's paired gain on each (and the search's, where it
    ran), with its interval."""
    steps = {(str(r["map"]), int(str(r["seed"])), str(r["who"])): float(str(r["steps"])) for r in rows}
    for cls, maps in _classes(name, rows).items():
        keys = sorted({(m, s) for (m, s, _) in steps if m in maps})
        keys = [k for k in keys if all((*k, w) in steps for w in (EXPERT, *baselines))]
        if not keys:
            continue
        for focus in (EXPERT, *(b for b in baselines if b == SEARCH)):
            mine = [steps[(*k, focus)] for k in keys]
            print(f"{cls}, {robots} robots: {len(keys)} episodes, {focus} {np.mean(mine):.1f} steps")
            for b in (EXPERT, *baselines):
                if b == focus:
                    continue
                base = [steps[(*k, b)] for k in keys]
                est, lo, hi = paired_bootstrap(mine, base)
                better = sum(e < x for e, x in zip(mine, base, strict=True))
                print(
                    f"  against {b} ({np.mean(base):.1f}): {est:+.1f}% fewer [{lo:+.1f}, {hi:+.1f}], better in {better}"
                )


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--maps", type=int, default=6, help="first N maps of each dataset by name (0: all)")
    ap.add_argument("--robots", type=int, default=3)
    ap.add_argument("--seeds", type=int, default=1)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--datasets", default="houseexpo,dungeon", help="comma-separated: houseexpo, dungeon")
    ap.add_argument(
        "--baselines", default="hier-heuristic", help=f"comma-separated strategies run alone, or {SEARCH!r}"
    )
    ap.add_argument("--rows", type=Path, default=None, help="JSON lines of finished episodes, read and appended")
    ap.add_argument(
        "--world", choices=("truth", "known", "predicted"), default="truth", help="where candidates run forward"
    )
    ap.add_argument("--predictor", default=None, help="predictor file of --world predicted (default: the shipped one)")
    args = ap.parse_args()
    if not MAPS.is_dir():
        print(f"skipped: dev maps not found at {MAPS}", file=sys.stderr)
        return 0
    n = args.maps or None
    every = {
        "houseexpo": sorted((MAPS / "houseexpo" / "png").glob("*.png"))[:n],
        "dungeon": sorted((MAPS / "dungeon").glob("*.png"))[:n],
    }
    baselines = [b for b in args.baselines.split(",") if b]
    sets = {name: every[name] for name in args.datasets.split(",") if name}
    done: list[dict[str, object]] = []
    if args.rows is not None and args.rows.exists():
        done = [json.loads(line) for line in args.rows.read_text().splitlines() if line.strip()]
    have = {(r["map"], r["robots"], r["seed"], r["who"], r["world"]) for r in done}
    ctx = multiprocessing.get_context("spawn")
    with ProcessPoolExecutor(args.workers, mp_context=ctx) as pool:
        for name, paths in sets.items():
            jobs = [
                (str(p), args.robots, s, who, args.world, args.predictor)
                for p in paths
                for s in range(args.seeds)
                for who in (EXPERT, *baselines)
                if (p.name, args.robots, s, who, args.world) not in have
            ]
            rows = [r for r in done if r["map"] in {p.name for p in paths} and r["robots"] == args.robots]
            rows = [r for r in rows if r["world"] == args.world]
            futures = [pool.submit(episode, job) for job in jobs]
            for k, fut in enumerate(as_completed(futures), 1):
                row = fut.result()
                rows.append(row)
                if args.rows is not None:
                    with args.rows.open("a") as f:
                        f.write(json.dumps(row) + "\n")
                print(
                    f"{name}: {k}/{len(jobs)} episodes ({row['who']} on {row['map']}: {row['steps']} steps)",
                    file=sys.stderr,
                    flush=True,
                )
            report(name, rows, baselines, args.robots)
    return 0


if __name__ == "__main__":
    sys.exit(run_script(main))
