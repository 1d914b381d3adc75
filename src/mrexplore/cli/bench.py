"""``mrexplore bench``: many episodes (maps x strategies x team sizes x seeds) in parallel, resumable, then
the report."""

from __future__ import annotations

import argparse
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from mrexplore.cli.common import (
    COUNT,
    POLICY_HELP,
    PREDICTOR_HELP,
    WORKERS,
    add_progress,
    check_failures,
    check_output,
    int_list,
)
from mrexplore.cli.settings_flags import MISSION_ALIASES, add_settings_flags, alias_given, run_config
from mrexplore.config import SimConfig
from mrexplore.pipeline.registry import strategy_spec
from mrexplore.runtime.kernel_cache import say_if_compiling
from mrexplore.types import MrExploreError

__all__ = ["add_bench", "run_bench_command"]


def add_bench(sub: Any) -> None:
    be = sub.add_parser("bench", help="run many episodes in parallel, append results.csv, write report.md")
    be.add_argument("--maps", required=True, nargs="+", help="map files and/or folders (searched recursively)")
    be.add_argument("--strategies", default="hier,nearest,utility", help="comma-separated strategy names")
    be.add_argument(
        "--team-sizes",
        default=None,
        metavar="N,N,...",
        help="comma-separated team sizes, each run on every map (default: the one team of --robots)",
    )
    be.add_argument("--seeds", type=COUNT, default=3, help="seeds 0..N-1 per map (default 3)")
    be.add_argument("--out", required=True, help="folder for results.csv and report.md")
    be.add_argument("--workers", type=WORKERS, default=None, help="worker processes (default: one per core)")
    be.add_argument(
        "--ray-address",
        default=None,
        help="run the episodes as Ray tasks: 'local' starts Ray here, 'auto' or HOST:PORT joins a cluster",
    )
    be.add_argument("--policy", default=None, help=POLICY_HELP)
    be.add_argument("--predictor", default=None, help=PREDICTOR_HELP)
    add_settings_flags(be, MISSION_ALIASES, "--set and the flags override it; the resume key holds every setting")
    add_progress(be)


def run_bench_command(args: argparse.Namespace, argv: Sequence[str]) -> str:
    strategies = [s for s in args.strategies.split(",") if s]
    if not strategies:
        raise MrExploreError(f"--strategies must name at least one strategy, got {args.strategies!r}")
    for name in strategies:
        strategy_spec(name)
    run = run_config(args)
    if args.team_sizes is not None and alias_given(args, "--robots"):
        raise MrExploreError("--robots and --team-sizes both give the team; give one")
    robots = int_list(args.team_sizes, "--team-sizes") if args.team_sizes is not None else [run.sim.robots]
    if len(set(robots)) != len(robots):
        raise MrExploreError(f"--team-sizes names a team size twice ({args.team_sizes}); give each size once")
    for n in robots:
        SimConfig(robots=n)
        check_failures(run, n)
    check_output(args.out, "--out", folder=True)
    say_if_compiling()
    from mrexplore.bench.report import write_report
    from mrexplore.bench.runner import EpisodeSpec, expand_maps, run_bench

    maps = expand_maps(args.maps)
    specs = [
        EpisodeSpec(m, s, n, seed, run, args.policy, args.predictor)
        for m in maps
        for s in strategies
        for n in robots
        for seed in range(args.seeds)
    ]
    out = Path(args.out)
    ran = run_bench(specs, out / "results.csv", args.workers or 0, args.progress, args.ray_address)
    command = "mrexplore " + " ".join(argv)
    write_report(out / "results.csv", out / "report.md", strategies, command)
    return f"{ran} episodes run, {len(specs) - ran} already done; wrote {out / 'results.csv'} and {out / 'report.md'}"
