"""``mrexplore explore``: one mission on one map, its measures, pictures and the centre's final map; and the
mission's flags, which ``ros2 sim`` and ``ros2 launch`` take too."""

from __future__ import annotations

import argparse
import sys
from typing import TYPE_CHECKING, Any

from mrexplore.cli.common import (
    DEFAULT_STRATEGY,
    POLICY_HELP,
    PREDICTOR_HELP,
    SEED,
    add_progress,
    check_failures,
    check_output,
    xy,
)
from mrexplore.cli.settings_flags import MISSION_ALIASES, add_settings_flags, run_config
from mrexplore.config import FaultConfig, RunConfig
from mrexplore.mission.record import mission_record
from mrexplore.pipeline.registry import strategy_names, strategy_spec
from mrexplore.runtime.example_maps import DEFAULT_MAP
from mrexplore.runtime.kernel_cache import say_if_compiling

if TYPE_CHECKING:
    import numpy as np
    from numpy.typing import NDArray

__all__ = ["add_explore", "add_mission_flags", "mission_setup", "make_run_strategy", "run_explore"]

DESCRIPTION = """Explore one map with a team and print what was measured: coverage, steps, distance driven,
planning times and the bytes sent. Every setting can be changed: the common ones by their flags, any other
by --set SECTION.FIELD=VALUE ('mrexplore config' lists them).

examples:
  mrexplore explore --map generated:3 --robots 4 --png run.png
  mrexplore explore --map plan.yaml --strategy utility --set sim.sensor.range_m=8 --json"""


def add_mission_flags(p: argparse.ArgumentParser) -> None:
    """The mission's flags: ``explore``'s, which ``ros2 sim`` and ``ros2 launch`` take too."""
    p.add_argument(
        "--map",
        default=DEFAULT_MAP,
        help=f"map file (.yaml, .png/.pgm, HouseExpo .json), generated:SEED or varied:SEED (default {DEFAULT_MAP})",
    )
    p.add_argument(
        "--strategy",
        default=DEFAULT_STRATEGY,
        help=f"one of {', '.join(strategy_names())} (default {DEFAULT_STRATEGY})",
    )
    p.add_argument(
        "--no-local", action="store_true", help="turn the local routing layer off: robots go to cluster centres"
    )
    p.add_argument("--policy", default=None, help=POLICY_HELP)
    p.add_argument("--predictor", default=None, help=PREDICTOR_HELP)
    p.add_argument("--seed", type=SEED, default=0, help="seed of starts, sensor noise and faults (default 0)")
    p.add_argument(
        "--start",
        type=xy,
        action="append",
        metavar="X,Y",
        help="start of a robot in metres (map frame); once per robot, or once to place the team near it",
    )
    add_settings_flags(p, MISSION_ALIASES, "--set and the flags override it")


def add_explore(sub: Any) -> None:
    ex = sub.add_parser(
        "explore",
        help="explore one map and report the measures",
        description=DESCRIPTION,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    add_mission_flags(ex)
    ex.add_argument("--gif", help="write an animation of the run to this path")
    ex.add_argument("--png", help="write a picture of the final map to this path")
    ex.add_argument(
        "--save-map",
        metavar="PATH",
        help="write the centre's final map as ROS map_server PATH.yaml + PATH.pgm",
    )
    ex.add_argument("--json", action="store_true", help="print one JSON object with the measures on stdout")
    add_progress(ex)


def make_run_strategy(args: argparse.Namespace, run: RunConfig) -> Any:
    """The strategy the flags name (``--strategy``, ``--no-local``, ``--policy``) with the run's settings."""
    from mrexplore.pipeline.registry import strategy_for_run

    return strategy_for_run(
        args.strategy, run, local=not args.no_local, policy=args.policy, predictor=getattr(args, "predictor", None)
    )


def mission_setup(args: argparse.Namespace) -> tuple[RunConfig, Any, Any, NDArray[np.int32] | None]:
    """The run's settings, strategy, map and starts from the mission's flags (shared by ``ros2 sim`` and
    ``ros2 launch``), each checked before any work."""
    strategy_spec(args.strategy)
    run = run_config(args)
    say_if_compiling()
    from mrexplore.maps.loaders import load_map
    from mrexplore.sim.starts import team_starts

    strategy = make_run_strategy(args, run)
    check_failures(run, run.sim.robots)
    truth = load_map(args.map, run.map)
    from mrexplore.maps.plan_check import check_team_size

    check_team_size(int((~truth.occupied).sum()), truth.resolution_m, run.sim.robots, truth.name)
    starts = team_starts(truth, args.start or [], run.sim.robots, run.sim.start_spread_m, args.seed)
    return run, strategy, truth, starts


def run_explore(args: argparse.Namespace) -> dict[str, Any]:
    """``explore``: the mission's record (:func:`~mrexplore.mission.record.mission_record`)."""
    check_output(args.gif, "--gif")
    check_output(args.png, "--png")
    check_output(args.save_map, "--save-map")
    run, strategy, truth, starts = mission_setup(args)
    from mrexplore.maps.map_saver import save_ros_map
    from mrexplore.mission import MissionSpec, run_mission
    from mrexplore.mission.render import GIF_SECONDS, GifRecorder, save_png

    sim_cfg, mission_cfg = run.sim, run.mission
    recorder = None
    if args.gif or args.png:
        title = f"{truth.name}: {strategy.name}, {sim_cfg.robots} robot{'s' * (sim_cfg.robots != 1)}"
        recorder = GifRecorder(title=title, faults=mission_cfg.faults != FaultConfig())
    result = run_mission(
        MissionSpec(truth, strategy, sim_cfg, mission_cfg, seed=args.seed, starts_rc=starts),
        observer=recorder,
        progress=args.progress,
    )
    # A mission that ended for want of frontiers ends its pictures without the last decision's clusters.
    clusters = result.measures.done_reason not in ("no_frontiers", "no_reachable_frontiers")
    if recorder is not None and args.gif:
        n = recorder.save_gif(args.gif, progress=args.progress, clusters=clusters)
        print(
            f"wrote {args.gif}: the mission in {n} frames, about {GIF_SECONDS:.0f} s and the end held 2 s",
            file=sys.stderr,
        )
    if recorder is not None and args.png:
        final = recorder.final_frame(clusters=clusters)
        save_png(final, args.png)
        print(f"wrote {args.png}: the final map, {final.width} x {final.height} px", file=sys.stderr)
    if args.save_map:
        save_ros_map(result.final_state, truth.frame, args.save_map)
        print(f"wrote {args.save_map} and its image: the team's final map (ROS map_server)", file=sys.stderr)
    return mission_record(run, strategy, truth, args.seed, result.measures.to_dict(), result.starts_rc)
