"""Command line: parses arguments into configs and calls the library; bad input is one line and exit 2.

The modules that do the work (numba's kernels, the simulator, the bench) are imported only once the
arguments are valid, so that ``--help`` and every argument error answer at once.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import warnings
from collections.abc import Sequence
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING, Any, NoReturn

from mrexplore.config import (
    TRAINABLE,
    FaultConfig,
    MapConfig,
    MissionConfig,
    RunConfig,
    SimConfig,
    TrainConfig,
    config_to_dict,
    config_yaml,
    read_config_file,
)
from mrexplore.example_maps import DEFAULT_MAP, MAPS_ENV, maps_dir
from mrexplore.kernel_cache import say_if_compiling
from mrexplore.strategy_names import BUILTIN_STRATEGIES, TABLE_I, check_strategy_name
from mrexplore.types import MrExploreError

if TYPE_CHECKING:
    import numpy as np
    from numpy.typing import NDArray

__all__ = ["main", "build_parser", "strict_json"]

EXIT_BAD_INPUT = 2
EXIT_INTERRUPTED = 130
CONFIG_HEADER = (
    "mrexplore settings: every field with its default. Keep the lines you change, pass the file with "
    "--config FILE to explore, bench or train; flags given on the command line override it."
)
DEFAULT_STRATEGY = "hier"
TRAIN_METHOD = (
    "train the learned global layer: hier by a cross-entropy search over its edge weights, then imitation of "
    "a lookahead expert (DAgger), PPO optional; ncm (NeuralCoMapping) by PPO"
)
COMMITMENT_HELP = "goal hysteresis in [0, 1] (1: none; default: 0.5 for nearest/utility, 1 for hier)"
POLICY_HELP = (
    "weights of the learned strategies (hier, ncm), written by 'mrexplore train': FILE, or KIND=FILE pairs "
    "(hier=A.npz,ncm=B.npz) where a run has both (default: the shipped policies)"
)
TRAIN_PREDICTOR = "\0train"
"""``train --predictor`` given alone: train the map predictor."""
PREDICTOR_HELP = (
    "map predictor of the predictive strategies (hier-predict-heuristic, hier-predict): FILE written by "
    "'mrexplore train --predictor', or none (every unknown cell free); default: the shipped one"
)
MIN_REPLAN_HELP = (
    "steps a robot whose goal was seen drives on before the team replans "
    f"(default {MissionConfig.min_replan_steps}; 1: at once)"
)
BASELINE_BYTES_HELP = (
    "leave Table II's int8-grid baselines uncounted (bytes_grid* empty): the same missions, a large floor's "
    "rounds much cheaper, for runs that want Table I alone"
)


class _Parser(argparse.ArgumentParser):
    """argparse with one-line errors (no usage block), exit code 2."""

    def error(self, message: str) -> NoReturn:
        self.exit(EXIT_BAD_INPUT, f"mrexplore: error: {message}; see '{self.prog} --help'\n")


def _xy(text: str) -> tuple[float, float]:
    try:
        x, y = (float(v) for v in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be X,Y in metres, got {text!r}") from None
    if not (math.isfinite(x) and math.isfinite(y)):
        raise argparse.ArgumentTypeError(f"must be finite X,Y in metres, got {text!r}")
    return (x, y)


def _number(low: float, rule: str, *, integer: bool = False, below: float | None = None) -> Any:
    """An argparse type: a finite number >= ``low`` (and < ``below``), named ``rule`` in its error."""

    def parse(text: str) -> float | int:
        try:
            value: float | int = int(text) if integer else float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"must be {rule}, got {text!r}") from None
        if not math.isfinite(value) or value < low or (below is not None and value >= below):
            raise argparse.ArgumentTypeError(f"must be {rule}, got {text!r}")
        return value

    return parse


_POSITIVE = _number(1e-300, "a number > 0")
_SEED = _number(0, "an integer >= 0", integer=True)
_COUNT = _number(1, "an integer >= 1", integer=True)
_WORKERS = _number(0, "an integer >= 0 (0: one per core)", integer=True)
_STEP = _number(0, "a step >= 0", integer=True)
_LOSS = _number(0, "a probability in [0, 1)", below=1)


def _failure(text: str) -> tuple[int, int]:
    robot, _, step = text.partition("@")
    try:
        pair = (int(robot), int(step))
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be ROBOT@STEP (integers, e.g. 1@300), got {text!r}") from None
    if min(pair) < 0:
        raise argparse.ArgumentTypeError(f"must be ROBOT@STEP with both >= 0, got {text!r}")
    return pair


def _add_config_flags(p: argparse.ArgumentParser, what: str) -> None:
    p.add_argument(
        "--config",
        default=None,
        metavar="FILE",
        help=f"YAML file of settings ('mrexplore config' prints every one with its default); {what}",
    )
    p.add_argument(
        "--robot-failure",
        type=_failure,
        action="append",
        metavar="ID@STEP",
        help="robot ID stops for good at STEP (repeatable)",
    )
    p.add_argument(
        "--message-loss",
        type=_LOSS,
        default=None,
        metavar="P",
        help=f"each map message and acknowledgement is lost with probability P (default {FaultConfig.message_loss})",
    )
    p.add_argument(
        "--centre-restart",
        type=_STEP,
        action="append",
        metavar="STEP",
        help="the centre loses all its state at STEP (repeatable)",
    )
    p.add_argument(
        "--comm-range",
        type=_POSITIVE,
        default=None,
        metavar="M",
        help="robots farther than M metres from the relay (first start) cannot send (default: unlimited)",
    )


def _add_progress(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--progress",
        action=argparse.BooleanOptionalAction,
        default=None,
        help="--progress: a bar; --no-progress: nothing (default: a bar on a terminal, else a line every 5 s)",
    )


def _add_mission_flags(ex: argparse.ArgumentParser) -> None:
    """The mission's flags: ``explore``'s, which ``ros2 sim`` and ``ros2 launch`` take too."""
    ex.add_argument(
        "--map",
        default=DEFAULT_MAP,
        help=f"map file (.yaml, .png/.pgm, HouseExpo .json), generated:SEED or varied:SEED (default {DEFAULT_MAP})",
    )
    ex.add_argument("--robots", type=_COUNT, default=None, help=f"team size (default {SimConfig.robots})")
    ex.add_argument(
        "--strategy",
        default=DEFAULT_STRATEGY,
        help=f"one of {', '.join(BUILTIN_STRATEGIES)} (default {DEFAULT_STRATEGY})",
    )
    ex.add_argument(
        "--no-local", action="store_true", help="turn the local routing layer off: robots go to cluster centres"
    )
    ex.add_argument("--commitment", type=float, default=None, help=COMMITMENT_HELP)
    ex.add_argument("--policy", default=None, help=POLICY_HELP)
    ex.add_argument("--predictor", default=None, help=PREDICTOR_HELP)
    ex.add_argument("--seed", type=_SEED, default=0, help="seed of starts, sensor noise and faults (default 0)")
    ex.add_argument("--max-steps", type=_COUNT, default=None, help=f"step budget (default {MissionConfig.max_steps})")
    ex.add_argument("--min-replan-steps", type=_COUNT, default=None, help=MIN_REPLAN_HELP)
    ex.add_argument(
        "--resolution",
        type=_POSITIVE,
        default=None,
        help=f"working cell size in metres (default {MapConfig.resolution_m})",
    )
    ex.add_argument(
        "--pixel-size",
        type=_POSITIVE,
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
    ex.add_argument(
        "--transmission",
        choices=("delta", "full"),
        default=None,
        help="what the centre rebuilds from: sparse-map deltas (default) or whole sparse maps (the paper's)",
    )
    ex.add_argument("--no-baseline-bytes", action="store_true", help=BASELINE_BYTES_HELP)


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="mrexplore", description="Multi-robot exploration with a hierarchical planner.")
    parser.add_argument(
        "--maps-dir",
        default=None,
        help=f"where the example maps are (training maps in train/); default ${MAPS_ENV}, else ../shared/maps",
    )
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)
    ex = sub.add_parser("explore", help="explore one map and report the measures")
    _add_mission_flags(ex)
    ex.add_argument("--gif", help="write an animation of the run to this path")
    ex.add_argument("--png", help="write a picture of the final map to this path")
    ex.add_argument(
        "--save-map",
        metavar="PATH",
        help="write the centre's final map as ROS map_server PATH.yaml + PATH.pgm",
    )
    ex.add_argument("--json", action="store_true", help="print one JSON object with the measures on stdout")
    _add_config_flags(ex, "flags override it")
    _add_progress(ex)
    be = sub.add_parser("bench", help="run many episodes in parallel, append results.csv, write report.md")
    be.add_argument("--maps", required=True, nargs="+", help="map files and/or folders (searched recursively)")
    be.add_argument("--strategies", default="hier,nearest,utility", help="comma-separated strategy names")
    be.add_argument("--robots", default=None, help=f"comma-separated team sizes (default {SimConfig.robots})")
    be.add_argument("--seeds", type=_COUNT, default=3, help="seeds 0..N-1 per map (default 3)")
    be.add_argument("--out", required=True, help="folder for results.csv and report.md")
    be.add_argument("--workers", type=_WORKERS, default=0, help="worker processes (default: one per core)")
    be.add_argument(
        "--ray-address",
        default=None,
        help="run the episodes as Ray tasks: 'local' starts Ray here, 'auto' or HOST:PORT joins a cluster",
    )
    be.add_argument("--commitment", type=float, default=None, help=COMMITMENT_HELP)
    be.add_argument("--policy", default=None, help=POLICY_HELP)
    be.add_argument("--predictor", default=None, help=PREDICTOR_HELP)
    be.add_argument(
        "--resolution", type=_POSITIVE, default=None, help=f"cell size, metres (default {MapConfig.resolution_m})"
    )
    be.add_argument(
        "--max-steps",
        type=_COUNT,
        default=None,
        help=f"step budget per episode (default {MissionConfig.max_steps})",
    )
    be.add_argument("--min-replan-steps", type=_COUNT, default=None, help=MIN_REPLAN_HELP)
    be.add_argument("--no-baseline-bytes", action="store_true", help=BASELINE_BYTES_HELP)
    _add_config_flags(be, "flags override it; the resume key holds every setting")
    _add_progress(be)
    tr = sub.add_parser(
        "train",
        help=TRAIN_METHOD,
    )
    tr.add_argument("--out", required=True, help="folder for policy.npz, checkpoints, log.csv and stages.csv")
    tr.add_argument(
        "--predictor",
        nargs="?",
        const=TRAIN_PREDICTOR,
        default=None,
        metavar="FILE|none",
        help="alone: train the map predictor instead (predictor.npz, beliefs.npz, checkpoints, log.csv, "
        "curve.png) from beliefs of missions on the training maps, the truth as the label (reads the predictor "
        "and sim sections); with FILE or none: the map predictor of a policy that reads a prediction "
        "(train.learned.use_predicted_gain or use_predicted_path; default: the shipped one)",
    )
    tr.add_argument(
        "--strategy",
        choices=TRAINABLE,
        default=None,
        help="what to train: hier (the paper's mGNN) or ncm (NeuralCoMapping); default: the config's, else hier",
    )
    budget = tr.add_mutually_exclusive_group()
    budget.add_argument("--minutes", type=float, default=None, help="stop starting stages after this many minutes")
    budget.add_argument("--episodes", type=int, default=None, help="stop after this many training episodes")
    tr.add_argument("--workers", type=_WORKERS, default=0, help="worker processes (default: one per core)")
    tr.add_argument("--ray-address", default=None, help="run episodes as Ray tasks: 'local', 'auto' or HOST:PORT")
    tr.add_argument("--resume", action="store_true", help="continue the run in --out after its last finished stage")
    tr.add_argument("--seed", type=_SEED, default=0, help="seed of the run (default 0)")
    tr.add_argument(
        "--train-maps",
        default=None,
        help="folder of training maps (DungeonMaps PNGs; default: train/ of the example maps, --maps-dir); "
        "procedural plans always",
    )
    _add_config_flags(tr, "train reads its train, sim and mission sections; flags override it")
    _add_progress(tr)
    sub.add_parser(
        "config", help="print every setting with its default as a YAML file for --config", description=CONFIG_HEADER
    )
    _add_report(sub)
    _add_ros2(sub)
    return parser


def _floats(count: int, what: str) -> Any:
    """An argparse type: ``count`` comma-separated finite numbers."""

    def parse(text: str) -> tuple[float, ...]:
        try:
            values = tuple(float(v) for v in text.split(","))
        except ValueError:
            values = ()
        if len(values) != count or not all(math.isfinite(v) for v in values):
            raise argparse.ArgumentTypeError(f"must be {what}, got {text!r}")
        return values

    return parse


_ROS2_HELP = """Run the three layers on ROS 2 robots (docs/ros2.md). On each robot: 'mrexplore ros2 robot'; on the
computing centre: 'mrexplore ros2 centre'; to try them without robots: 'mrexplore ros2 launch', which starts
'mrexplore ros2 sim' (the simulator as ROS 2 robots), a robot node per robot and the centre, on this machine.

A deployment file (--deployment, YAML) holds a real team: the team grid, each robot's name, frame offset, frame
and topics, the centre's timing. Without one, --robots names the robots (one shared frame, default topics)
and --team-grid sets the grid. Traffic stays on this machine's loopback unless --network is given."""


def _add_team_flags(p: argparse.ArgumentParser, robots: bool = True) -> None:
    p.add_argument("--deployment", default=None, metavar="FILE", help="YAML deployment file (docs/ros2.md)")
    if robots:
        p.add_argument(
            "--robots", default=None, metavar="NAMES", help="comma-separated robot names, without a deployment"
        )
    p.add_argument(
        "--team-grid",
        type=_floats(4, "X0,Y0,WIDTH,HEIGHT in metres"),
        default=None,
        metavar="X0,Y0,WIDTH,HEIGHT",
        help="the team's grid in the team frame: lower-left corner and size, metres (default: the deployment's)",
    )
    p.add_argument("--resolution", type=_POSITIVE, default=None, help="cell size of the team grid, metres")
    p.add_argument(
        "--network",
        action="store_true",
        help="use the system's DDS settings (default: traffic kept on this machine's loopback)",
    )
    p.add_argument("--config", default=None, metavar="FILE", help="YAML file of settings ('mrexplore config')")


def _add_ros2(sub: Any) -> None:
    rp = sub.add_parser(
        "ros2",
        help="run the layers on ROS 2 robots (docs/ros2.md)",
        description=_ROS2_HELP,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    kinds = rp.add_subparsers(dest="ros2", required=True, parser_class=_Parser)
    ro = kinds.add_parser("robot", help="one robot's on-board work: its map -> sparse frontier messages")
    ro.add_argument("--name", required=True, help="the robot's name (its topics: /NAME/map, /NAME/pose)")
    ro.add_argument("--index", type=_SEED, default=None, help="the robot's index in the team, from 0")
    ro.add_argument(
        "--offset",
        type=_floats(3, "X,Y,YAW (metres, radians)"),
        default=None,
        metavar="X,Y,YAW",
        help="where the robot's map frame lies in the team frame (default 0,0,0: one shared frame)",
    )
    ro.add_argument(
        "--pose-type", default=None, help="pose_with_covariance (AMCL, default), odometry, or tf (needs tf2_ros)"
    )
    _add_team_flags(ro, robots=False)
    ce = kinds.add_parser("centre", help="the computing centre: frontier messages -> layers 1-3 -> Nav2 goals")
    ce.add_argument(
        "--strategy",
        default=DEFAULT_STRATEGY,
        help=f"one of {', '.join(BUILTIN_STRATEGIES)} but oracle (default {DEFAULT_STRATEGY})",
    )
    ce.add_argument("--policy", default=None, help=POLICY_HELP)
    ce.add_argument("--predictor", default=None, help=PREDICTOR_HELP)
    ce.add_argument(
        "--no-local", action="store_true", help="turn the local routing layer off: robots go to cluster centres"
    )
    ce.add_argument("--seed", type=_SEED, default=0, help="seed of a planner that draws (default 0)")
    ce.add_argument("--lockstep", action="store_true", help="take rounds from 'mrexplore ros2 sim --lockstep'")
    ce.add_argument(
        "--direct-maps",
        action="store_true",
        help="read each robot's map and pose here, no robot node needed (no bandwidth saving)",
    )
    ce.add_argument("--record", default=None, metavar="FILE", help="write the centre's record (JSON) here at the end")
    _add_team_flags(ce)
    si = kinds.add_parser("sim", help="the simulator as ROS 2 robots (maps, poses, Nav2's goals and status)")
    _add_mission_flags(si)
    si.add_argument("--lockstep", action="store_true", help="advance only once the centre answered each decision")
    si.add_argument("--speed", type=_POSITIVE, default=10.0, help="simulation steps a second in real time (default 10)")
    si.add_argument("--json", action="store_true", help="print the run's record as JSON on stdout")
    si.add_argument(
        "--progress-file", default=None, metavar="FILE", help="keep the step and coverage here (JSON), for a launcher"
    )
    si.add_argument("--network", action="store_true", help="use the system's DDS settings (default: loopback)")
    _add_config_flags(si, "flags override it")
    rl = kinds.add_parser("relay", help="a lossy link between robots and centre, to try the protocol under loss")
    rl.add_argument("--loss", type=_LOSS, required=True, metavar="P", help="share of frontier messages dropped")
    rl.add_argument("--seed", type=_SEED, default=0, help="seed of the drops (default 0)")
    _add_team_flags(rl)
    la = kinds.add_parser(
        "launch", help="sim, robot nodes and centre as separate processes on this machine (a demo, or a check)"
    )
    _add_mission_flags(la)
    la.add_argument("--lockstep", action="store_true", help="the mission equals 'mrexplore explore' step for step")
    la.add_argument("--speed", type=_POSITIVE, default=10.0, help="simulation steps a second in real time (default 10)")
    la.add_argument("--direct-maps", action="store_true", help="no robot nodes: the centre reads the robots' maps")
    la.add_argument(
        "--json", action="store_true", help="print explore's record plus the bytes measured on the wire, as JSON"
    )
    la.add_argument("--network", action="store_true", help="use the system's DDS settings (default: loopback)")
    _add_config_flags(la, "flags override it")


def _deployment(args: argparse.Namespace, run: RunConfig) -> tuple[Any, Any]:
    """The deployment and the team grid's frame from ``--deployment`` or ``--robots`` and ``--team-grid``."""
    from mrexplore.ros2.deployment import Deployment, TeamGrid, read_deployment

    if args.deployment:
        dep = read_deployment(args.deployment)
    else:
        names = getattr(args, "robots", None) or getattr(args, "name", None)
        if not names:
            raise MrExploreError("name the robots: --robots robot1,robot2 or --deployment FILE")
        dep = Deployment.of_names([n.strip() for n in names.split(",")], TeamGrid())
    grid = dep.team_grid
    if args.team_grid is not None:
        x0, y0, width, height = args.team_grid
        grid = replace(grid, x0=x0, y0=y0, width=width, height=height)
    if args.resolution is not None:
        grid = replace(grid, resolution=args.resolution)
    elif args.team_grid is not None and not args.deployment:
        grid = replace(grid, resolution=MapConfig.resolution_m)
    return dep, grid.frame(run.map.max_cells)


def _ros2(args: argparse.Namespace, argv: list[str]) -> str:
    import importlib.util

    if importlib.util.find_spec("rclpy") is None:  # found, not imported: DDS settings must come first
        raise MrExploreError("ROS 2 commands need rclpy; install it with: pip install -e '.[ros2]'")
    if args.ros2 in ("sim", "launch"):
        return _ros2_sim(args, argv)
    run = read_config_file(args.config) if args.config else RunConfig()
    dep, team = _deployment(args, run)
    loopback = not args.network
    if args.ros2 == "relay":
        from mrexplore.ros2.relay import run_relay

        return run_relay(dep, args.loss, args.seed, loopback=loopback)
    if args.ros2 == "robot":
        from mrexplore.maps.occupancy_grid import FrameOffset
        from mrexplore.ros2.robot_node import RobotNodeSettings, run_robot_node

        entry = dep.robot(args.name) if args.deployment else None
        index = args.index if args.index is not None else (entry.index if entry else None)
        if index is None:
            raise MrExploreError("give the robot's place in the team: --index N, or a --deployment that names it")
        offset = FrameOffset(*args.offset) if args.offset else (entry.offset if entry else FrameOffset())
        pose_type = args.pose_type or (entry.pose_type if entry else "pose_with_covariance")
        robot = RobotNodeSettings(args.name, index, team, offset, pose_type, run.preprocess, entry=entry)
        run_robot_node(robot, loopback=loopback)
        return f"robot {args.name} stopped"
    from mrexplore.centre import NO_ORACLE
    from mrexplore.ros2.centre_node import CentreSettings, run_centre_node

    if args.strategy == "oracle":
        raise MrExploreError(NO_ORACLE)  # before the middleware starts
    strategy = _strategy(args, run)
    if args.record:
        _check_output(args.record, "--record")
    record = Path(args.record) if args.record else None
    settings = CentreSettings(dep, strategy, team, args.lockstep, record, args.seed, args.direct_maps, run.preprocess)
    why = run_centre_node(settings, loopback=loopback)
    return f"centre stopped: {why}"


def _ros2_sim(args: argparse.Namespace, argv: list[str]) -> str:
    """``ros2 sim`` and ``ros2 launch``: the mission's settings as explore reads them."""
    from mrexplore.mission import MissionSpec
    from mrexplore.ros2.deployment import Deployment, TeamGrid

    run, strategy, truth, starts = _mission_setup(args)
    spec = MissionSpec(truth, strategy, run.sim, run.mission, seed=args.seed, starts_rc=starts)
    frame = truth.frame
    grid = TeamGrid(
        frame.origin_xy[0],
        frame.origin_xy[1],
        frame.width * frame.resolution_m,
        frame.height * frame.resolution_m,
        frame.resolution_m,
    )
    names = [f"robot{i + 1}" for i in range(run.sim.robots)]
    dep = Deployment.of_names(names, grid)
    if args.ros2 == "sim":
        from mrexplore.ros2.sim_node import SimSettings, run_sim_node

        progress_file = Path(args.progress_file) if args.progress_file else None
        sim_settings = SimSettings(spec, dep, args.lockstep, args.speed, progress_file=progress_file)
        record = run_sim_node(sim_settings, loopback=not args.network)
        if args.json:
            print(json.dumps(strict_json(record), allow_nan=False))
        return f"simulation ended: {record['done_reason']} after {record['steps']} steps"
    from mrexplore.ros2.launch import launch_team

    record = launch_team(spec, run, dep, grid, argv, args)
    measures, starts_rc = record.pop("measures"), record.pop("starts_rc")
    full = {**_mission_record(run, strategy, truth, args, measures, starts_rc), **record}
    if args.json:
        print(json.dumps(strict_json(full), allow_nan=False))
    return "launch ended" if args.json else _launch_summary(full)


def _add_report(sub: Any) -> None:
    rp = sub.add_parser("report", help="compare benches or policies already run (paired, teams, table-time, policies)")
    kinds = rp.add_subparsers(dest="report", required=True, parser_class=_Parser)
    pa = kinds.add_parser("paired", help="one strategy across separate benches, paired episode by episode")
    pa.add_argument(
        "--runs",
        nargs="+",
        required=True,
        metavar="LABEL=DIR[@STRATEGY]",
        help="bench folders of the same episodes, the reference first; @STRATEGY: another strategy's rows",
    )
    pa.add_argument("--train", nargs="*", default=[], metavar="LABEL=DIR", help="the train folder of a label's policy")
    pa.add_argument("--strategy", default=DEFAULT_STRATEGY, help=f"whose rows to compare (default {DEFAULT_STRATEGY})")
    pa.add_argument("--common", action="store_true", help="keep only the episodes every run holds")
    pa.add_argument("--out", default=None, help="also write the markdown here")
    te = kinds.add_parser("teams", help="steps a larger team needs against a smaller one, paired by map and seed")
    te.add_argument("--runs", nargs="+", required=True, help="bench folders, oldest first (later rows win)")
    te.add_argument("--small", type=_COUNT, default=8, help="the smaller team (default 8)")
    te.add_argument("--large", type=_COUNT, default=16, help="the larger team (default 16)")
    te.add_argument("--strategy", default=DEFAULT_STRATEGY, help=f"default {DEFAULT_STRATEGY}")
    tt = kinds.add_parser("table-time", help="how long a whole table would take, from episodes already timed")
    tt.add_argument("--runs", nargs="+", required=True, help="bench folders, oldest first (later rows win)")
    tt.add_argument("--seeds", type=_COUNT, default=3, help="seeds of the table (default 3)")
    tt.add_argument("--workers", type=_COUNT, default=2, help="workers of the table (default 2)")
    tt.add_argument("--strategies", default=",".join(TABLE_I), help="comma-separated (default Table I's seven)")
    po = kinds.add_parser("policies", help="policy files against the heuristic on maps no dev set holds")
    po.add_argument("policies", nargs="+", help="policy files (.npz), the first is the yardstick")
    po.add_argument("--fresh", type=_SEED, default=0, help="N fresh varied: plans instead of the validation maps")
    po.add_argument("--robots", type=_COUNT, default=None, help="robots per episode (default: train.val_robots)")
    po.add_argument("--workers", type=_WORKERS, default=0, help="worker processes (default: one per core)")
    po.add_argument("--train-maps", default=None, help="folder of training maps (default: train/ of the example maps)")
    po.add_argument("--csv", default=None, help="write every map's results per policy here")


def _labelled(items: Sequence[str], flag: str) -> dict[str, str]:
    out: dict[str, str] = {}
    for item in items:
        label, sep, path = item.partition("=")
        if not sep or not label or not path:
            raise MrExploreError(f"{flag} {item!r} must be LABEL=DIR; name each folder")
        out[label] = path
    return out


def _folders(items: Sequence[str]) -> list[Path]:
    for item in items:
        if not Path(item).is_dir():
            raise MrExploreError(f"--runs folder {item} not found; give folders that 'mrexplore bench --out' wrote")
    return [Path(i) for i in items]


def _train_maps(given: str | None) -> Path | None:
    """The training maps' folder: the one given, else ``train/`` of the example maps; None where absent."""
    folder = Path(given) if given is not None else maps_dir() / "train"
    return folder if folder.is_dir() else None


def _report(args: argparse.Namespace, argv: Sequence[str]) -> str:
    if args.report == "paired":
        runs = _labelled(args.runs, "--runs")
        trains = {k: Path(v) for k, v in _labelled(args.train, "--train").items()}
        from mrexplore.bench.compare import compare_runs

        text = compare_runs(runs, args.strategy, trains, args.common, "mrexplore " + " ".join(argv))
        if args.out:
            Path(args.out).write_text(text)
        return text
    if args.report == "teams":
        from mrexplore.bench.compare import team_ratio

        return team_ratio(_folders(args.runs), args.small, args.large, args.strategy)
    if args.report == "table-time":
        from mrexplore.bench.compare import table_time

        return table_time(_folders(args.runs), args.seeds, args.workers, [s for s in args.strategies.split(",") if s])
    import csv

    _need_torch()
    from mrexplore.training.compare import compare_policies

    lines, per_map = compare_policies(
        [Path(p) for p in args.policies], _train_maps(args.train_maps), args.fresh, args.robots, args.workers
    )
    if args.csv is not None:
        with open(args.csv, "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=list(per_map[0]))
            w.writeheader()
            w.writerows(per_map)
    return "\n".join(lines)


def _ints(text: str, name: str) -> list[int]:
    try:
        values = [int(v) for v in text.split(",") if v]
    except ValueError:
        raise MrExploreError(f"{name} must be comma-separated integers, got {text!r}") from None
    if not values:
        raise MrExploreError(f"{name} must name at least one value, got {text!r}")
    return values


def _run_config(args: argparse.Namespace) -> RunConfig:
    """The settings of this run: the ``--config`` file (or the defaults), then every flag given."""
    run = read_config_file(args.config) if args.config else RunConfig()
    faults = run.mission.faults
    if args.robot_failure:
        faults = replace(faults, robot_failures=tuple(args.robot_failure))
    if args.message_loss is not None:
        faults = replace(faults, message_loss=args.message_loss)
    if args.centre_restart:
        faults = replace(faults, centre_restarts=tuple(args.centre_restart))
    if args.comm_range is not None:
        faults = replace(faults, comm_range_m=args.comm_range)
    mission = replace(run.mission, faults=faults)
    given = vars(args)
    flags = {"max_steps": "max_steps", "min_replan_steps": "min_replan_steps", "transmission": "transmission"}
    mission = replace(mission, **{f: given[a] for a, f in flags.items() if given.get(a) is not None})
    if given.get("no_baseline_bytes"):
        mission = replace(mission, baseline_bytes=False)
    map_cfg = run.map
    if given.get("resolution") is not None:
        map_cfg = replace(map_cfg, resolution_m=args.resolution)
    if given.get("pixel_size") is not None:
        map_cfg = replace(map_cfg, pixel_size_m=args.pixel_size)
    sim = run.sim
    if isinstance(given.get("robots"), int):
        sim = replace(sim, robots=args.robots)
    gp = run.global_planning
    if given.get("commitment") is not None:
        gp = replace(gp, commitment=args.commitment)
    return replace(run, map=map_cfg, sim=sim, mission=mission, global_planning=gp)


def _check_failures(run: RunConfig, n: int) -> None:
    """Refuse, before any work, a robot failure of a robot outside a team of ``n``."""
    for robot, _ in run.mission.faults.robot_failures:
        if robot >= n:
            raise MrExploreError(f"--robot-failure names robot {robot}, but a team of {n} has robots 0..{n - 1}")


def _check_output(path: str | None, flag: str, folder: bool = False) -> None:
    """Refuse, before any work, an output path that cannot be written."""
    if path is None:
        return
    p = Path(path)
    if folder:
        if p.exists() and not p.is_dir():
            raise MrExploreError(f"{flag} {p} is a file, not a folder; pass a folder")
        parent = p if p.exists() else next((q for q in p.parents if q.exists()), Path("."))
    else:
        if p.is_dir():
            raise MrExploreError(f"{flag} {p} is a folder; pass a file path")
        parent = p.parent
        if not parent.is_dir():
            raise MrExploreError(f"{flag} folder {parent} does not exist; create it first")
    if not os.access(parent, os.W_OK | os.X_OK):
        raise MrExploreError(f"{flag} {p} cannot be written ({parent} is not writable); choose a writable path")


def _bench(args: argparse.Namespace, argv: Sequence[str]) -> str:
    strategies = [s for s in args.strategies.split(",") if s]
    if not strategies:
        raise MrExploreError(f"--strategies must name at least one strategy, got {args.strategies!r}")
    for name in strategies:
        check_strategy_name(name)
    run = _run_config(args)
    robots = _ints(args.robots, "--robots") if args.robots is not None else [run.sim.robots]
    if len(set(robots)) != len(robots):
        raise MrExploreError(f"--robots names a team size twice ({args.robots}); give each size once")
    for n in robots:
        SimConfig(robots=n)
        _check_failures(run, n)
    _check_output(args.out, "--out", folder=True)
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
    ran = run_bench(specs, out / "results.csv", args.workers, args.progress, args.ray_address)
    command = "mrexplore " + " ".join(argv)
    write_report(out / "results.csv", out / "report.md", strategies, command)
    return f"{ran} episodes run, {len(specs) - ran} already done; wrote {out / 'results.csv'} and {out / 'report.md'}"


TORCH_MISSING = (
    "training needs torch, which is not installed: pip install 'mrexplore[train]' (on a machine without an "
    "NVIDIA GPU, first: pip install torch --index-url https://download.pytorch.org/whl/cpu)"
)


def _need_torch() -> None:
    """One line naming the fix where torch cannot be imported (the commands that train need it)."""
    try:
        import torch  # noqa: F401
    except ImportError:
        raise MrExploreError(TORCH_MISSING) from None


def _train(args: argparse.Namespace) -> str:
    run = _run_config(args)
    if args.minutes is not None and not (math.isfinite(args.minutes) and args.minutes > 0):
        raise MrExploreError(f"--minutes must be > 0, got {args.minutes}")
    if args.predictor == TRAIN_PREDICTOR:
        return _train_predictor(args, run)
    if args.predictor is not None and not (run.train.strategy == "hier" and run.train.learned.reads_prediction):
        raise MrExploreError(
            f"--predictor {args.predictor} is for a hier policy that reads a prediction; set "
            "train.learned.use_predicted_gain or use_predicted_path: true in --config, or give --predictor alone "
            "to train a predictor"
        )
    if args.strategy is not None:
        run = replace(run, train=replace(run.train, strategy=args.strategy))
    if args.episodes is not None and args.episodes < 1:
        raise MrExploreError(f"--episodes must be >= 1, got {args.episodes}")
    _check_output(args.out, "--out", folder=True)
    _need_torch()
    say_if_compiling()
    from mrexplore.training.trainer import train

    result = train(
        run.train,
        Path(args.out),
        _train_maps(args.train_maps),
        minutes=args.minutes,
        episodes=args.episodes,
        workers=args.workers,
        ray_address=args.ray_address,
        resume=args.resume,
        seed=args.seed,
        progress=args.progress,
        say=lambda s: print(s, file=sys.stderr),
        sim=run.sim,
        mission=run.mission,
        predictor=args.predictor,
    )
    best = next(r for r in result.stages if r["stage"] == result.best_stage)
    sampled = f", sampled {best['val_sampled_steps_mean']:.1f}" if best.get("val_sampled_steps_mean") else ""
    wrote = f"wrote {result.policy_path} and {result.policy_path.parent / 'stages.csv'}"
    if result.best_stage == "baseline":
        start = "hier-heuristic's cost" if run.train.strategy == "hier" else "an untrained network"
        return (
            f"kept the baseline, no trained stage beat it on validation ({best['val_steps_mean']:.1f} steps"
            f"{sampled}): the policy is the untrained start ({start}); train longer; {wrote}"
        )
    return f"kept stage {result.best_stage} (validation {best['val_steps_mean']:.1f} steps{sampled}); {wrote}"


def _train_predictor(args: argparse.Namespace, run: RunConfig) -> str:
    if args.strategy is not None or args.episodes is not None:
        flag = "--strategy" if args.strategy is not None else "--episodes"
        raise MrExploreError(f"{flag} does not apply to --predictor (it trains on collected beliefs); drop it")
    _check_output(args.out, "--out", folder=True)
    _need_torch()
    say_if_compiling()
    from mrexplore.training.predictor import train_predictor

    path, best = train_predictor(
        run.predictor,
        Path(args.out),
        _train_maps(args.train_maps),
        minutes=args.minutes,
        workers=args.workers,
        ray_address=args.ray_address,
        resume=args.resume,
        seed=args.seed,
        progress=args.progress,
        say=lambda s: print(s, file=sys.stderr),
        sim=run.sim,
    )
    log = path.parent / "log.csv"
    return f"kept epoch {best['epoch']} (validation loss {best['val_loss']:.4f}); wrote {path} and {log}"


def _strategy(args: argparse.Namespace, run: RunConfig) -> Any:
    """The strategy the flags name (``--strategy``, ``--no-local``, ``--policy``) with the run's settings."""
    from mrexplore.pipeline import make_strategy

    return make_strategy(
        args.strategy,
        run.global_planning,
        run.preprocess,
        run.local_planning,
        local=not args.no_local,
        policy=args.policy,
        coscan_cfg=run.coscan,
        predictor=getattr(args, "predictor", None),
    )


def _mission_setup(args: argparse.Namespace) -> tuple[RunConfig, Any, Any, NDArray[np.int32] | None]:
    """The run's settings, strategy, map and starts from explore's flags (shared by ``ros2 sim`` and
    ``ros2 launch``), each checked before any work."""
    check_strategy_name(args.strategy)
    run = _run_config(args)
    sim_cfg = run.sim
    say_if_compiling()
    import numpy as np

    from mrexplore.maps.loaders import load_map
    from mrexplore.sim.starts import draw_starts, starts_from_xy

    strategy = _strategy(args, run)
    _check_failures(run, sim_cfg.robots)
    truth = load_map(args.map, run.map)
    starts = None
    if args.start:
        if len(set(args.start)) != len(args.start):
            raise MrExploreError("--start gives the same point twice; give each robot its own start")
        given = starts_from_xy(truth, args.start)
        if len({tuple(rc) for rc in given.tolist()}) != len(given):
            raise MrExploreError("--start puts two robots in one cell; give starts at least one cell apart")
        if len(given) == sim_cfg.robots:
            starts = given
        elif len(given) == 1:
            rng = np.random.default_rng(args.seed)
            starts = draw_starts(truth, sim_cfg.robots, sim_cfg.start_spread_m, rng, tuple(given[0]))
        else:
            raise MrExploreError(f"--start must be given once or once per robot ({sim_cfg.robots}), got {len(given)}")
    return run, strategy, truth, starts


def _explore(args: argparse.Namespace) -> dict[str, Any]:
    _check_output(args.gif, "--gif")
    _check_output(args.png, "--png")
    _check_output(args.save_map, "--save-map")
    run, strategy, truth, starts = _mission_setup(args)
    from mrexplore.maps.map_saver import save_ros_map
    from mrexplore.mission import MissionSpec, run_mission
    from mrexplore.render import GifRecorder, save_png

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
    if recorder is not None and args.gif:
        recorder.save_gif(args.gif, progress=args.progress)
    if recorder is not None and args.png:
        save_png(recorder.final_frame(), args.png)
    if args.save_map:
        save_ros_map(result.final_state, truth.frame, args.save_map)
    return _mission_record(run, strategy, truth, args, result.measures.to_dict(), result.starts_rc)


def _mission_record(
    run: RunConfig, strategy: Any, truth: Any, args: argparse.Namespace, measures: dict[str, Any], starts_rc: Any
) -> dict[str, Any]:
    """explore's record of one mission: what ran, its measures, the starts and every setting."""
    record: dict[str, Any] = {
        "strategy": strategy.name,
        "map": truth.name,
        "robots": run.sim.robots,
        "seed": args.seed,
        **measures,
        "starts_xy": [list(truth.frame.rc_to_xy((int(r), int(c)))) for r, c in starts_rc],
        "policy": strategy.policy,
        "predictor": strategy.predictor,
        "config": {
            **config_to_dict(replace(run, train=TrainConfig())),
            "strategy": {
                "preprocess": config_to_dict(strategy.preprocess),
                "commitment": strategy.commitment,
                "local": config_to_dict(strategy.local.cfg) if strategy.local is not None else None,
            },
        },
    }
    del record["config"]["train"]
    return record


def strict_json(value: Any) -> Any:
    """``value`` with every NaN or infinite float as None and tuples as lists: strict JSON, which
    ``json.dumps(..., allow_nan=False)`` then always accepts."""
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, dict):
        return {str(k): strict_json(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [strict_json(v) for v in value]
    if hasattr(value, "item") and hasattr(value, "dtype") and getattr(value, "ndim", None) == 0:  # NumPy scalar
        return strict_json(value.item())
    return value


def _kb(n: int | None) -> str:
    return "not counted" if n is None else f"{n / 1e3:.1f} kB"


def _launch_summary(rec: dict[str, Any]) -> str:
    """What ``ros2 launch`` prints: explore's summary in lockstep, the real-time run's few measures otherwise,
    and what crossed the middleware."""
    wire = rec["wire"]
    head = (
        _summary(rec)
        if rec["lockstep"]
        else f"explored {rec['map']} with {rec['robots']} robots ({rec['strategy']}, seed {rec['seed']}) in real time\n"
        f"  coverage {100 * rec['coverage']:.2f}% in {rec['steps']} steps; ended: {rec['done_reason']}"
    )
    return (
        f"{head}\n  through ROS 2: {wire['messages']} frontier messages, {_kb(wire['payload_bytes'])} "
        f"({_kb(wire['serialized_bytes'])} serialized); {rec['centre']['decisions']} decisions, "
        f"{rec['decision_ms_median']:.1f} ms median from the last message in to every goal out; "
        f"{rec['centre']['aborts']} goals aborted; logs in {rec['logs']}"
    )


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
            f"wall {rec['wall_s']:.1f} s; peak memory {rec['peak_mb']:.0f} MB; ended: {rec['done_reason']}",
            f"  a robot's on-board work a round: {rec['onboard_ms_median']:.1f} ms median, "
            f"{rec['onboard_ms_p95']:.1f} ms p95",
            f"  sent over {rec['rounds']} rounds: sparse {_kb(rec['bytes_sparse'])}, delta "
            f"{_kb(rec['bytes_sparse_delta'])}; grid {_kb(rec['bytes_grid'])}, zlib {_kb(rec['bytes_grid_zlib'])}; "
            f"centre map IoU min {rec['reconstruction_iou_min']:.4f}",
            *(
                [
                    f"  faults: {rec['robots_failed']} robots failed, {rec['messages_lost']} of "
                    f"{rec['messages_sent']} messages lost, {rec['messages_resent']} whole maps resent, "
                    f"{rec['acks_lost']} acknowledgements lost, {rec['centre_restarts']} centre restarts"
                ]
                if any(rec[k] for k in ("robots_failed", "messages_lost", "messages_resent", "centre_restarts"))
                else []
            ),
        ]
    )


def _one_line_warning(message: Warning | str, *args: Any, **kwargs: Any) -> None:
    print(f"mrexplore: warning: {message}", file=sys.stderr)


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``mrexplore`` command; returns the exit code."""
    with warnings.catch_warnings():
        warnings.showwarning = _one_line_warning  # a map that may not be a plan: one line, as errors are
        return _main(argv)


def _main(argv: Sequence[str] | None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    try:
        args = build_parser().parse_args(argv)
    except SystemExit as exc:  # argparse's one-line error (exit 2) or --help (exit 0)
        return int(exc.code or 0)
    if args.maps_dir is not None:
        os.environ[MAPS_ENV] = args.maps_dir  # read by maps_dir() here and in spawned workers
    try:
        if args.command == "explore":
            rec = _explore(args)
            print(json.dumps(strict_json(rec), allow_nan=False) if args.json else _summary(rec))
        elif args.command == "bench":
            print(_bench(args, argv))
        elif args.command == "train":
            print(_train(args))
        elif args.command == "config":
            print(f"# {CONFIG_HEADER}\n" + config_yaml(RunConfig()), end="")
        elif args.command == "report":
            print(_report(args, argv))
        elif args.command == "ros2":
            print(_ros2(args, argv), file=sys.stderr)
    except MrExploreError as exc:
        print(f"mrexplore: error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:
        print("mrexplore: interrupted; finished results are kept, rerun the command to go on", file=sys.stderr)
        return EXIT_INTERRUPTED
    return 0


if __name__ == "__main__":
    sys.exit(main())
