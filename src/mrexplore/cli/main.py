"""The ``mrexplore`` command: builds the parser from each command's module, runs the command, and turns bad
input into one line and exit code 2.

The modules that do the work (numba's kernels, the simulator, the bench) are imported only once the
arguments are valid, so that ``--help`` and every argument error answer at once.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import warnings
from collections.abc import Sequence
from typing import Any

from mrexplore.cli.bench import add_bench, run_bench_command
from mrexplore.cli.common import EXIT_BAD_INPUT, EXIT_INTERRUPTED, Parser
from mrexplore.cli.explore import add_explore, run_explore
from mrexplore.cli.maps import add_maps, run_maps
from mrexplore.cli.report import add_report, run_report
from mrexplore.cli.ros2 import add_ros2, run_ros2
from mrexplore.cli.train import add_train, run_train
from mrexplore.config import CONFIG_HEADER, RunConfig, config_yaml
from mrexplore.mission.record import strict_json, summary
from mrexplore.runtime.example_maps import MAPS_ENV
from mrexplore.types import MrExploreError

__all__ = ["main", "build_parser"]


def build_parser() -> argparse.ArgumentParser:
    """The whole command line: one sub-command per module of this package."""
    parser = Parser(prog="mrexplore", description="Multi-robot exploration with a hierarchical planner.")
    parser.add_argument(
        "--maps-dir",
        default=None,
        help=f"where the example maps are (training maps in train/); sets runtime.maps_dir (${MAPS_ENV}); "
        "default ../shared/maps",
    )
    sub = parser.add_subparsers(dest="command", required=True, parser_class=Parser)
    add_explore(sub)
    add_bench(sub)
    add_train(sub)
    sub.add_parser(
        "config", help="print every setting with its default as a YAML file for --config", description=CONFIG_HEADER
    )
    add_report(sub)
    add_ros2(sub)
    add_maps(sub)
    return parser


def _one_line_warning(message: Warning | str, *args: Any, **kwargs: Any) -> None:
    print(f"mrexplore: warning: {message}", file=sys.stderr)


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``mrexplore`` command; returns the exit code."""
    with warnings.catch_warnings():
        warnings.showwarning = _one_line_warning  # a map that may not be a plan: one line, as errors are
        return _main(argv)


def _run(args: argparse.Namespace, argv: list[str]) -> None:
    if args.command == "explore":
        rec = run_explore(args)
        print(json.dumps(strict_json(rec), allow_nan=False) if args.json else summary(rec))
    elif args.command == "bench":
        print(run_bench_command(args, argv))
    elif args.command == "train":
        print(run_train(args))
    elif args.command == "config":
        print(f"# {CONFIG_HEADER}\n" + config_yaml(RunConfig()), end="")
    elif args.command == "report":
        print(run_report(args, argv))
    elif args.command == "maps":
        print(run_maps(args))
    elif args.command == "ros2":
        said = run_ros2(args, argv)
        if said:
            print(said, file=sys.stderr)


ROS_ARGS = "--ros-args"
NODE_COMMANDS = ("robot", "centre", "relay", "sim")
"""The ros2 commands that start one ROS 2 node, and so take ``--ros-args ...`` (ROS's own arguments)."""


def split_ros_args(argv: list[str]) -> tuple[list[str], list[str]]:
    """The command line's own arguments, and ROS's: ``--ros-args`` and all that follows (up to a ``--``
    that ends them), as every ROS 2 node takes them.

    Examples
    --------
    >>> split_ros_args(["ros2", "robot", "--name", "r1", "--ros-args", "-p", "use_sim_time:=true"])
    (['ros2', 'robot', '--name', 'r1'], ['--ros-args', '-p', 'use_sim_time:=true'])
    """
    if ROS_ARGS not in argv:
        return argv, []
    start = argv.index(ROS_ARGS)
    end = argv.index("--", start) if "--" in argv[start:] else len(argv)
    return argv[:start] + argv[end + 1 :], argv[start:end]


def _main(argv: Sequence[str] | None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    own, ros_args = split_ros_args(argv)
    try:
        args = build_parser().parse_args(own)
    except SystemExit as exc:  # argparse's one-line error (exit 2) or --help (exit 0)
        return int(exc.code or 0)
    if ros_args and not (args.command == "ros2" and args.ros2 in NODE_COMMANDS):
        print(
            f"mrexplore: error: {ROS_ARGS} is for the ros2 commands that start a node "
            f"({', '.join(NODE_COMMANDS)}); drop it",
            file=sys.stderr,
        )
        return EXIT_BAD_INPUT
    args.ros_args = ros_args
    if args.maps_dir is not None:
        os.environ[MAPS_ENV] = args.maps_dir  # the runtime.maps_dir setting, here and in spawned workers
    try:
        _run(args, argv)
    except MrExploreError as exc:
        print(f"mrexplore: error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:
        print("mrexplore: interrupted; finished results are kept, rerun the command to go on", file=sys.stderr)
        return EXIT_INTERRUPTED
    return 0
