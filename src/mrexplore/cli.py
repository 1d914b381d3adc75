"""Command line: parses arguments into configs and calls the library; bad input is one line and exit 2."""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any, NoReturn

import numpy as np
import yaml

from mrexplore.bench.report import write_report
from mrexplore.bench.runner import EpisodeSpec, expand_maps, run_bench
from mrexplore.config import (
    GlobalPlanningConfig,
    MapConfig,
    MissionConfig,
    SimConfig,
    TrainConfig,
    config_from_dict,
    config_to_dict,
)
from mrexplore.maps.loaders import DEFAULT_MAP, load_map
from mrexplore.maps.map_saver import save_ros_map
from mrexplore.mission import run_mission
from mrexplore.render import GifRecorder, save_png
from mrexplore.sim.starts import draw_starts, starts_from_xy
from mrexplore.strategies import make_strategy, strategy_names
from mrexplore.types import MrExploreError

__all__ = ["main", "build_parser"]

EXIT_BAD_INPUT = 2
DEFAULT_STRATEGY = "hier"
COMMITMENT_HELP = "goal hysteresis in [0, 1] (1: none; default: 0.5 for nearest/utility, 1 for hier)"
POLICY_HELP = "weights of the learned strategy (hier), written by 'mrexplore train' (default: the shipped policy)"
DEFAULT_TRAIN_MAPS = Path("..") / "shared" / "maps" / "train"
MIN_REPLAN_HELP = (
    "steps a robot whose goal was seen drives on before the team replans "
    f"(default {MissionConfig.min_replan_steps}; 1: at once)"
)


class _Parser(argparse.ArgumentParser):
    """argparse with one-line errors (no usage block), exit code 2."""

    def error(self, message: str) -> NoReturn:
        self.exit(EXIT_BAD_INPUT, f"mrexplore: error: {message}; see '{self.prog} --help'\n")


def _xy(text: str) -> tuple[float, float]:
    try:
        x, y = (float(v) for v in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"start must be X,Y in metres, got {text!r}") from None
    return (x, y)


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="mrexplore", description="Multi-robot exploration with a hierarchical planner.")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)
    ex = sub.add_parser("explore", help="explore one map and report the measures")
    ex.add_argument(
        "--map",
        default=DEFAULT_MAP,
        help=f"map file (.yaml, .png/.pgm, HouseExpo .json) or generated:SEED (default {DEFAULT_MAP})",
    )
    ex.add_argument("--robots", type=int, default=SimConfig.robots, help="team size (default 3)")
    ex.add_argument(
        "--strategy",
        default=DEFAULT_STRATEGY,
        help=f"one of {', '.join(strategy_names())} (default {DEFAULT_STRATEGY})",
    )
    ex.add_argument(
        "--no-local", action="store_true", help="turn the local routing layer off: robots go to cluster centres"
    )
    ex.add_argument("--commitment", type=float, default=None, help=COMMITMENT_HELP)
    ex.add_argument("--policy", default=None, help=POLICY_HELP)
    ex.add_argument("--seed", type=int, default=0, help="seed of starts and sensor noise (default 0)")
    ex.add_argument("--max-steps", type=int, default=MissionConfig.max_steps, help="step budget (default 20000)")
    ex.add_argument("--min-replan-steps", type=int, default=MissionConfig.min_replan_steps, help=MIN_REPLAN_HELP)
    ex.add_argument(
        "--resolution", type=float, default=MapConfig.resolution_m, help="working cell size in metres (default 0.05)"
    )
    ex.add_argument(
        "--pixel-size",
        type=float,
        default=None,
        help="metres per pixel of an image without YAML (default 0.01 grayscale, 0.1 DungeonMaps)",
    )
    ex.add_argument(
        "--start",
        type=_xy,
        action="append",
        metavar="X,Y",
        help="start of a robot in metres (map frame); once per robot, or once to place the team near it",
    )
    ex.add_argument("--gif", help="write an animation of the run to this path")
    ex.add_argument("--png", help="write a picture of the final map to this path")
    ex.add_argument(
        "--save-map",
        metavar="PATH",
        help="write the centre's final map as ROS map_server PATH.yaml + PATH.pgm",
    )
    ex.add_argument(
        "--transmission",
        choices=("delta", "full"),
        default=MissionConfig.transmission,
        help="what the centre rebuilds from: sparse-map deltas (default) or whole sparse maps (the paper's)",
    )
    ex.add_argument("--json", action="store_true", help="print one JSON object with the measures on stdout")
    ex.add_argument(
        "--progress",
        action=argparse.BooleanOptionalAction,
        default=None,
        help="show a progress bar (default: only on a terminal)",
    )
    be = sub.add_parser("bench", help="run many episodes in parallel, append results.csv, write report.md")
    be.add_argument("--maps", required=True, nargs="+", help="map files and/or folders (searched recursively)")
    be.add_argument("--strategies", default="hier,nearest,utility", help="comma-separated strategy names")
    be.add_argument("--robots", default="3", help="comma-separated team sizes (default 3)")
    be.add_argument("--seeds", type=int, default=3, help="seeds 0..N-1 per map (default 3)")
    be.add_argument("--out", required=True, help="folder for results.csv and report.md")
    be.add_argument("--workers", type=int, default=0, help="worker processes (default: one per core)")
    be.add_argument(
        "--ray-address",
        default=None,
        help="run the episodes as Ray tasks: 'local' starts Ray here, 'auto' or HOST:PORT joins a cluster",
    )
    be.add_argument("--commitment", type=float, default=None, help=COMMITMENT_HELP)
    be.add_argument("--policy", default=None, help=POLICY_HELP)
    be.add_argument("--resolution", type=float, default=MapConfig.resolution_m, help="cell size, metres")
    be.add_argument("--max-steps", type=int, default=MissionConfig.max_steps, help="step budget per episode")
    be.add_argument("--min-replan-steps", type=int, default=MissionConfig.min_replan_steps, help=MIN_REPLAN_HELP)
    be.add_argument(
        "--progress",
        action=argparse.BooleanOptionalAction,
        default=None,
        help="show a progress bar (default: only on a terminal)",
    )
    tr = sub.add_parser("train", help="train the learned global layer (imitation of a lookahead expert, then PPO)")
    tr.add_argument("--out", required=True, help="folder for policy.pt, checkpoints, log.csv and stages.csv")
    tr.add_argument("--config", default=None, help="YAML file of TrainConfig fields (see 'mrexplore train --help')")
    budget = tr.add_mutually_exclusive_group()
    budget.add_argument("--minutes", type=float, default=None, help="stop starting stages after this many minutes")
    budget.add_argument("--episodes", type=int, default=None, help="stop after this many training episodes")
    tr.add_argument("--workers", type=int, default=0, help="worker processes (default: one per core)")
    tr.add_argument("--ray-address", default=None, help="run episodes as Ray tasks: 'local', 'auto' or HOST:PORT")
    tr.add_argument("--resume", action="store_true", help="continue the run in --out after its last finished stage")
    tr.add_argument("--seed", type=int, default=0, help="seed of the run (default 0)")
    tr.add_argument(
        "--train-maps",
        default=str(DEFAULT_TRAIN_MAPS),
        help="folder of training maps (DungeonMaps PNGs; default ../shared/maps/train); procedural plans always",
    )
    tr.add_argument(
        "--progress",
        action=argparse.BooleanOptionalAction,
        default=None,
        help="show a progress bar (default: only on a terminal)",
    )
    return parser


def _ints(text: str, name: str) -> list[int]:
    try:
        return [int(v) for v in text.split(",") if v]
    except ValueError:
        raise MrExploreError(f"{name} must be comma-separated integers, got {text!r}") from None


def _bench(args: argparse.Namespace, argv: Sequence[str]) -> str:
    strategies = [s for s in args.strategies.split(",") if s]
    robots = _ints(args.robots, "--robots")
    if args.seeds < 1:
        raise MrExploreError(f"--seeds must be >= 1, got {args.seeds}")
    for n in robots:
        SimConfig(robots=n)
    MapConfig(resolution_m=args.resolution)
    MissionConfig(max_steps=args.max_steps, min_replan_steps=args.min_replan_steps)
    GlobalPlanningConfig(commitment=args.commitment)
    maps = expand_maps(args.maps)
    specs = [
        EpisodeSpec(m, s, n, seed, args.resolution, args.max_steps, args.commitment, args.min_replan_steps, args.policy)
        for m in maps
        for s in strategies
        for n in robots
        for seed in range(args.seeds)
    ]
    out = Path(args.out)
    ran = run_bench(specs, out / "results.csv", args.workers, args.progress, args.ray_address)
    command = "mrexplore " + " ".join(argv)
    write_report(out / "results.csv", out / "report.md", strategies, command)
    return f"{ran} episodes run, {len(specs) - ran} already done; wrote {out / 'results.csv'} and {out / 'report.md'}"


def _train_config(path: str | None) -> TrainConfig:
    if path is None:
        return TrainConfig()
    p = Path(path)
    if not p.is_file():
        raise MrExploreError(f"--config file {p} not found; pass a YAML file of TrainConfig fields")
    try:
        data = yaml.safe_load(p.read_text())
    except yaml.YAMLError as exc:
        raise MrExploreError(f"--config file {p} is not valid YAML ({type(exc).__name__}); fix it") from None
    if data is None:
        return TrainConfig()
    if not isinstance(data, dict):
        raise MrExploreError(f"--config file {p} must hold a mapping of TrainConfig fields, got {type(data).__name__}")
    try:
        return config_from_dict(TrainConfig, data)
    except TypeError as exc:
        raise MrExploreError(f"--config file {p}: {exc}") from None


def _train(args: argparse.Namespace) -> str:
    from mrexplore.global_planning.learned.trainer import train

    cfg = _train_config(args.config)
    if args.minutes is not None and not args.minutes > 0:
        raise MrExploreError(f"--minutes must be > 0, got {args.minutes}")
    if args.episodes is not None and args.episodes < 1:
        raise MrExploreError(f"--episodes must be >= 1, got {args.episodes}")
    if args.workers < 0:
        raise MrExploreError(f"--workers must be >= 0, got {args.workers}")
    train_dir = Path(args.train_maps)
    result = train(
        cfg,
        Path(args.out),
        train_dir if train_dir.is_dir() else None,
        minutes=args.minutes,
        episodes=args.episodes,
        workers=args.workers,
        ray_address=args.ray_address,
        resume=args.resume,
        seed=args.seed,
        progress=args.progress,
        say=lambda s: print(s, file=sys.stderr),
    )
    best = min(result.stages, key=lambda r: r["val_steps_mean"] if r["stage"] == result.best_stage else float("inf"))
    return (
        f"kept stage {result.best_stage} (validation {best['val_steps_mean']:.1f} steps); "
        f"wrote {result.policy_path} and {result.policy_path.parent / 'stages.csv'}"
    )


def _explore(args: argparse.Namespace) -> dict[str, Any]:
    map_cfg = MapConfig(resolution_m=args.resolution, pixel_size_m=args.pixel_size)
    sim_cfg = SimConfig(robots=args.robots)
    mission_cfg = MissionConfig(
        max_steps=args.max_steps, min_replan_steps=args.min_replan_steps, transmission=args.transmission
    )
    strategy = make_strategy(
        args.strategy, GlobalPlanningConfig(commitment=args.commitment), local=not args.no_local, policy=args.policy
    )
    if args.save_map and not Path(args.save_map).resolve().parent.is_dir():
        raise MrExploreError(f"--save-map folder {Path(args.save_map).parent} does not exist; create it first")
    truth = load_map(args.map, map_cfg)
    starts = None
    if args.start:
        given = starts_from_xy(truth, args.start)
        if len(given) == sim_cfg.robots:
            starts = given
        elif len(given) == 1:
            rng = np.random.default_rng(args.seed)
            starts = draw_starts(truth, sim_cfg.robots, sim_cfg.start_spread_m, rng, tuple(given[0]))
        else:
            raise MrExploreError(f"--start must be given once or once per robot ({sim_cfg.robots}), got {len(given)}")
    recorder = GifRecorder() if (args.gif or args.png) else None
    result = run_mission(
        truth,
        strategy,
        sim_cfg,
        mission_cfg,
        seed=args.seed,
        starts_rc=starts,
        observer=recorder,
        progress=args.progress,
    )
    if recorder is not None and args.gif:
        recorder.save_gif(args.gif)
    if recorder is not None and args.png:
        save_png(recorder.final_frame(), args.png)
    if args.save_map:
        save_ros_map(result.final_state, truth.frame, args.save_map)
    record: dict[str, Any] = {
        "strategy": strategy.name,
        "map": truth.name,
        "robots": sim_cfg.robots,
        "seed": args.seed,
        **result.measures.to_dict(),
        "starts_xy": [list(truth.frame.rc_to_xy((int(r), int(c)))) for r, c in result.starts_rc],
        "policy": strategy.policy,
        "config": {
            "map": config_to_dict(map_cfg),
            "sim": config_to_dict(sim_cfg),
            "mission": config_to_dict(mission_cfg),
            "preprocess": config_to_dict(strategy.preprocess),
            "commitment": strategy.commitment,
            "local": config_to_dict(strategy.local.cfg) if strategy.local is not None else None,
        },
    }
    return record


def _kb(n: int) -> str:
    return f"{n / 1e3:.1f} kB"


def _summary(rec: dict[str, Any]) -> str:
    def at(key: str) -> str:
        return "never" if rec[key] is None else str(rec[key])

    return "\n".join(
        [
            f"explored {rec['map']} with {rec['robots']} robots ({rec['strategy']}, seed {rec['seed']})",
            f"  coverage {100 * rec['coverage']:.2f}% in {rec['steps']} steps "
            f"(90% at {at('steps_to_90')}, 95% at {at('steps_to_95')}, 99% at {at('steps_to_99')})",
            f"  driven: longest {rec['path_len_max_m']:.1f} m, team {rec['path_len_sum_m']:.1f} m; "
            f"overlap {rec['overlap']:.2f}",
            f"  {rec['decisions']} decisions, {rec['plan_ms_mean']:.1f} ms mean, {rec['plan_ms_p95']:.1f} ms p95; "
            f"wall {rec['wall_s']:.1f} s; ended: {rec['done_reason']}",
            f"  sent over {rec['rounds']} rounds: sparse {_kb(rec['bytes_sparse'])}, delta "
            f"{_kb(rec['bytes_sparse_delta'])}; grid {_kb(rec['bytes_grid'])}, zlib {_kb(rec['bytes_grid_zlib'])}; "
            f"centre map IoU min {rec['reconstruction_iou_min']:.4f}",
        ]
    )


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``mrexplore`` command; returns the exit code."""
    argv = list(sys.argv[1:] if argv is None else argv)
    args = build_parser().parse_args(argv)
    try:
        if args.command == "explore":
            rec = _explore(args)
            print(json.dumps(rec) if args.json else _summary(rec))
        elif args.command == "bench":
            print(_bench(args, argv))
        elif args.command == "train":
            print(_train(args))
    except MrExploreError as exc:
        print(f"mrexplore: error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    return 0


if __name__ == "__main__":
    sys.exit(main())
