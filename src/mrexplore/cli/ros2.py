"""``mrexplore ros2``: the layers on ROS 2 robots (robot, centre, relay), and the simulator standing in for
them (sim, launch)."""

from __future__ import annotations

import argparse
import json
from dataclasses import replace
from pathlib import Path
from typing import Any

from mrexplore.cli.common import (
    DEFAULT_STRATEGY,
    LOSS,
    NON_NEGATIVE,
    POLICY_HELP,
    POSITIVE,
    PREDICTOR_HELP,
    SEED,
    Parser,
    check_output,
    floats,
)
from mrexplore.cli.explore import add_mission_flags, make_run_strategy, mission_setup
from mrexplore.cli.settings_flags import add_settings_flags, run_config
from mrexplore.config import MapConfig, RunConfig
from mrexplore.mission.record import launch_summary, mission_record, strict_json
from mrexplore.pipeline.registry import strategy_names
from mrexplore.types import MrExploreError

__all__ = ["add_ros2", "run_ros2"]

_ROS2_HELP = """Run the three layers on ROS 2 robots (docs/ros2.md). On each robot: 'mrexplore ros2 robot'; on the
computing centre: 'mrexplore ros2 centre'; to try them without robots: 'mrexplore ros2 launch', which starts
'mrexplore ros2 sim' (the simulator as ROS 2 robots), a robot node per robot and the centre, on this machine.

A deployment file (--deployment, YAML) holds a real team: the team grid, each robot's name, frame offset, frame
and topics, the centre's timing. Without one, --names names the robots (one shared frame, default topics)
and --team-grid sets the grid. Traffic stays on this machine's loopback unless --network is given."""


def _add_team_flags(p: argparse.ArgumentParser, robots: bool = True) -> None:
    p.add_argument("--deployment", default=None, metavar="FILE", help="YAML deployment file (docs/ros2.md)")
    if robots:
        p.add_argument(
            "--names", default=None, metavar="NAMES", help="comma-separated robot names, without a deployment"
        )
    p.add_argument(
        "--team-grid",
        type=floats(4, "X0,Y0,WIDTH,HEIGHT in metres"),
        default=None,
        metavar="X0,Y0,WIDTH,HEIGHT",
        help="the team's grid in the team frame: lower-left corner and size, metres (default: the deployment's)",
    )
    p.add_argument(
        "--team-resolution", type=POSITIVE, default=None, metavar="M", help="cell size of the team grid, metres"
    )
    p.add_argument(
        "--network",
        action="store_true",
        help="use the system's DDS settings (default: traffic kept on this machine's loopback)",
    )
    add_settings_flags(p)


def _add_nav2_flags(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--nav2",
        action="store_true",
        help="stand in for Nav2 and SLAM as they behave: a map frame per robot, SLAM maps at --slam-resolution, "
        "sim time on /clock (docs/ros2.md)",
    )
    p.add_argument(
        "--slam-resolution", type=POSITIVE, default=0.05, metavar="M", help="with --nav2: SLAM map cells, metres"
    )
    p.add_argument(
        "--inscribed-radius",
        type=NON_NEGATIVE,
        default=0.1,
        metavar="M",
        help="with --nav2: goals this close to an obstacle are aborted, as Nav2's planners refuse them (default 0.1)",
    )
    p.add_argument(
        "--clock-rate",
        type=POSITIVE,
        default=1.0,
        metavar="R",
        help="with --nav2: sim time runs R times the wall clock (default 1)",
    )


def add_ros2(sub: Any) -> None:
    rp = sub.add_parser(
        "ros2",
        help="run the layers on ROS 2 robots (docs/ros2.md)",
        description=_ROS2_HELP,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    kinds = rp.add_subparsers(dest="ros2", required=True, parser_class=Parser)
    ro = kinds.add_parser("robot", help="one robot's on-board work: its map -> sparse frontier messages")
    ro.add_argument("--name", required=True, help="the robot's name (its topics: /NAME/map, /NAME/pose)")
    ro.add_argument("--index", type=SEED, default=None, help="the robot's index in the team, from 0")
    ro.add_argument(
        "--offset",
        type=floats(3, "X,Y,YAW (metres, radians)"),
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
        help=f"one of {', '.join(strategy_names())} but oracle (default {DEFAULT_STRATEGY})",
    )
    ce.add_argument("--policy", default=None, help=POLICY_HELP)
    ce.add_argument("--predictor", default=None, help=PREDICTOR_HELP)
    ce.add_argument(
        "--no-local", action="store_true", help="turn the local routing layer off: robots go to cluster centres"
    )
    ce.add_argument("--seed", type=SEED, default=0, help="seed of a planner that draws (default 0)")
    ce.add_argument("--lockstep", action="store_true", help="take rounds from 'mrexplore ros2 sim --lockstep'")
    ce.add_argument(
        "--direct-maps",
        action="store_true",
        help="read each robot's map and pose here, no robot node needed (no bandwidth saving)",
    )
    ce.add_argument("--record", default=None, metavar="FILE", help="write the centre's record (JSON) here at the end")
    _add_team_flags(ce)
    si = kinds.add_parser("sim", help="the simulator as ROS 2 robots (maps, poses, Nav2's goals and status)")
    add_mission_flags(si)
    si.add_argument("--lockstep", action="store_true", help="advance only once the centre answered each decision")
    si.add_argument("--speed", type=POSITIVE, default=10.0, help="simulation steps a second in real time (default 10)")
    si.add_argument("--json", action="store_true", help="print the run's record as JSON on stdout")
    si.add_argument(
        "--progress-file", default=None, metavar="FILE", help="keep the step and coverage here (JSON), for a launcher"
    )
    si.add_argument("--network", action="store_true", help="use the system's DDS settings (default: loopback)")
    _add_nav2_flags(si)
    rl = kinds.add_parser("relay", help="a lossy link between robots and centre, to try the protocol under loss")
    rl.add_argument("--loss", type=LOSS, required=True, metavar="P", help="share of frontier messages dropped")
    rl.add_argument("--seed", type=SEED, default=0, help="seed of the drops (default 0)")
    _add_team_flags(rl)
    pa = kinds.add_parser("params", help="print the deployment's settings as a ROS 2 params file (for --params-file)")
    pa.add_argument("--out", default=None, metavar="FILE", help="write it here instead of printing it")
    _add_team_flags(pa)
    la = kinds.add_parser(
        "launch", help="sim, robot nodes and centre as separate processes on this machine (a demo, or a check)"
    )
    add_mission_flags(la)
    la.add_argument("--lockstep", action="store_true", help="the mission equals 'mrexplore explore' step for step")
    la.add_argument("--speed", type=POSITIVE, default=10.0, help="simulation steps a second in real time (default 10)")
    la.add_argument("--direct-maps", action="store_true", help="no robot nodes: the centre reads the robots' maps")
    la.add_argument(
        "--keep-logs", action="store_true", help="keep the processes' logs and records (a failed run always keeps them)"
    )
    la.add_argument(
        "--json", action="store_true", help="print explore's record plus the bytes measured on the wire, as JSON"
    )
    la.add_argument("--network", action="store_true", help="use the system's DDS settings (default: loopback)")
    _add_nav2_flags(la)


def _deployment(args: argparse.Namespace, run: RunConfig) -> tuple[Any, Any]:
    """The deployment and the team grid's frame from ``--deployment`` or ``--names`` and ``--team-grid``."""
    from mrexplore.ros2.deployment import Deployment, TeamGrid, read_deployment

    if args.deployment:
        dep = read_deployment(args.deployment)
    else:
        names = getattr(args, "names", None) or getattr(args, "name", None)
        if not names:
            raise MrExploreError("name the robots: --names robot1,robot2 or --deployment FILE")
        dep = Deployment.of_names([n.strip() for n in names.split(",")], TeamGrid())
    grid = dep.team_grid
    if args.team_grid is not None:
        x0, y0, width, height = args.team_grid
        grid = replace(grid, x0=x0, y0=y0, width=width, height=height)
    if args.team_resolution is not None:
        grid = replace(grid, resolution=args.team_resolution)
    elif args.team_grid is not None and not args.deployment:
        grid = replace(grid, resolution=MapConfig.resolution_m)
    return dep, grid.frame(run.map.max_cells)


def run_ros2(args: argparse.Namespace, argv: list[str]) -> str:

    if args.ros2 == "params":  # plain data: no ROS needed
        from mrexplore.ros2.parameters import params_yaml

        run = run_config(args)
        dep, team = _deployment(args, run)
        text = params_yaml(replace(dep, team_grid=_team_grid_of(team)))
        if args.out is None:
            print(text, end="")
            return ""
        check_output(args.out, "--out")
        Path(args.out).write_text(text)
        return f"ROS 2 parameters written to {args.out}"
    from mrexplore.ros2.loopback import rclpy_problem

    problem = rclpy_problem()  # checked in a child process: DDS settings must come before rclpy's import
    if problem is not None:
        raise MrExploreError(problem)
    if args.ros2 in ("sim", "launch"):
        return _ros2_sim(args, argv)
    run = run_config(args)
    dep, team = _deployment(args, run)
    loopback = not args.network
    if args.ros2 == "relay":
        from mrexplore.ros2.relay import run_relay

        return run_relay(dep, args.loss, args.seed, loopback=loopback, ros_args=args.ros_args)
    if args.ros2 == "robot":
        from mrexplore.maps.occupancy_grid import FrameOffset
        from mrexplore.ros2.robot_node import RobotNodeSettings, run_robot_node

        entry = dep.robot(args.name) if args.deployment else None
        index = args.index if args.index is not None else (entry.index if entry else None)
        if index is None:
            raise MrExploreError("give the robot's place in the team: --index N, or a --deployment that names it")
        offset = FrameOffset(*args.offset) if args.offset else (entry.offset if entry else FrameOffset())
        pose_type = args.pose_type or (entry.pose_type if entry else "pose_with_covariance")
        robot = RobotNodeSettings(
            args.name, index, team, offset, pose_type, run.preprocess, entry=entry, deployment=dep
        )
        run_robot_node(robot, loopback=loopback, ros_args=args.ros_args)
        return f"robot {args.name} stopped"
    from mrexplore.mission.centre import NO_ORACLE
    from mrexplore.ros2.centre_node import CentreSettings, run_centre_node

    if args.strategy == "oracle":
        raise MrExploreError(NO_ORACLE)  # before the middleware starts
    strategy = make_run_strategy(args, run)
    if args.record:
        check_output(args.record, "--record")
    record = Path(args.record) if args.record else None
    settings = CentreSettings(dep, strategy, team, args.lockstep, record, args.seed, args.direct_maps, run.preprocess)
    why = run_centre_node(settings, loopback=loopback, ros_args=args.ros_args)
    return f"centre stopped: {why}"


def _ros2_sim(args: argparse.Namespace, argv: list[str]) -> str:
    """``ros2 sim`` and ``ros2 launch``: the mission's settings as explore reads them."""
    from mrexplore.mission import MissionSpec
    from mrexplore.ros2.deployment import Deployment, TeamGrid

    run, strategy, truth, starts = mission_setup(args)
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
    if args.nav2:
        dep = _nav2_deployment(spec, dep)
    if args.ros2 == "sim":
        from mrexplore.ros2.nav2_double import DoubleSettings
        from mrexplore.ros2.sim_node import SimSettings, run_sim_node

        progress_file = Path(args.progress_file) if args.progress_file else None
        double, rate = DoubleSettings(), None
        if args.nav2:
            offsets = tuple(r.offset for r in dep.robots)
            double = DoubleSettings(
                args.slam_resolution,
                offsets,
                _DRIFT_M_PER_S,
                inscribed_radius_m=args.inscribed_radius,
                map_period_s=_SLAM_MAP_PERIOD_S,
            )
            rate = args.clock_rate
        sim_settings = SimSettings(
            spec, dep, args.lockstep, args.speed, progress_file=progress_file, double=double, clock_rate=rate
        )
        record = run_sim_node(sim_settings, loopback=not args.network, ros_args=args.ros_args)
        if args.json:
            print(json.dumps(strict_json(record), allow_nan=False))
        return f"simulation ended: {record['done_reason']} after {record['steps']} steps"
    from mrexplore.ros2.launch import launch_team

    record = launch_team(spec, run, dep, grid, argv, args)
    measures, starts_rc = record.pop("measures"), record.pop("starts_rc")
    full = {**mission_record(run, strategy, truth, args.seed, measures, starts_rc), **record}
    if args.json:
        print(json.dumps(strict_json(full), allow_nan=False))
    return "launch ended" if args.json else launch_summary(full)


_DRIFT_M_PER_S = 0.01
"""How fast the double's odometry drifts from its map pose under ``--nav2``."""
_SLAM_MAP_PERIOD_S = 1.0
"""The double's SLAM publishes each map this often under ``--nav2`` (slam_toolbox's ``map_update_interval``
as docs/ros2.md's recipe sets it; its default is 5 s)."""


def _nav2_deployment(spec: Any, dep: Any) -> Any:
    """The team as Nav2 robots bring it: each robot's map frame where it started (slam_toolbox starts its map
    at the robot's first pose), turned a quarter turn more than the last robot's."""
    import math

    from mrexplore.mission import Mission
    from mrexplore.ros2.deployment import Deployment

    starts = Mission(spec, progress=False).starts_rc  # the mission's own draw, as the simulator makes it
    robots = []
    for i, r in enumerate(dep.robots):
        x, y = spec.truth.frame.rc_to_xy((int(starts[i, 0]), int(starts[i, 1])))
        robots.append({"name": r.name, "offset": [float(x), float(y), (i % 4) * math.pi / 2]})
    return Deployment.from_dict({**dep.to_dict(), "robots": robots})


def _team_grid_of(team: Any) -> Any:
    """The :class:`~mrexplore.ros2.deployment.TeamGrid` of a team grid's frame."""
    from mrexplore.ros2.deployment import TeamGrid

    h, w = team.height * team.resolution_m, team.width * team.resolution_m
    return TeamGrid(team.origin_xy[0], team.origin_xy[1], round(w, 9), round(h, 9), team.resolution_m)
