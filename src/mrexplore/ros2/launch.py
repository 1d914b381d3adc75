"""``mrexplore ros2 launch``: the simulator, a robot node per robot and the centre as separate processes on
one machine, talking through ROS 2 (kept on loopback unless ``--network``), ended together.

It imports no rclpy itself: it sets the environment (:func:`~mrexplore.ros2.loopback.keep_on_loopback`) that
its children inherit, starts them, waits for the simulation to end, stops the others (SIGTERM, then SIGKILL
after a grace period), and merges their records.

explore's faults happen to the processes: ``--robot-failure ID@STEP`` stops the simulated robot and kills its
robot node at that step; ``--centre-restart STEP`` kills the centre at that step and starts a new one;
``--message-loss P`` puts a relay (:mod:`~mrexplore.ros2.relay`) between the robots and the centre that drops
that share of their frontier messages.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path
from typing import Any

import yaml

from mrexplore.config import RunConfig, config_yaml
from mrexplore.mission import MissionSpec
from mrexplore.ros2.deployment import Deployment, TeamGrid
from mrexplore.ros2.processes import TeamProcesses
from mrexplore.ros2.relay import relayed_topic
from mrexplore.types import MrExploreError

__all__ = ["launch_team", "TeamProcesses", "wire_summary", "merged_records"]

_LAUNCH_ONLY = {"--json": 0, "--direct-maps": 0, "--keep-logs": 0}
"""launch's own flags (and how many values each takes), not passed on to the simulator."""
_CENTRE_KEYS = ("decisions", "aborts", "goals_resent", "warnings", "lost", "finished", "goal_via")
"""What launch's record shows of the centre's."""
_SAY_EVERY_S = 5.0
"""How often the launcher says how far the simulation got."""
_RESTART_AFTER_S = 1.0
"""A killed centre is started again this long after."""


def _sim_argv(argv: list[str], progress_file: Path) -> list[str]:
    """The user's command line with ``launch`` turned into ``sim`` and launch's own flags removed."""
    out, skip = [], 0
    for k, arg in enumerate(argv):
        if skip:
            skip -= 1
            continue
        if arg in _LAUNCH_ONLY:
            skip = _LAUNCH_ONLY[arg]
            continue
        out.append("sim" if arg == "launch" and k > 0 and argv[k - 1] == "ros2" else arg)
    return [*out, "--json", "--progress-file", str(progress_file)]


def _say_progress(progress_file: Path) -> None:
    try:
        progress = json.loads(progress_file.read_text())
    except (OSError, ValueError):
        print("starting: the nodes load (a first run compiles its kernels: a minute or more)", file=sys.stderr)
        return
    print(f"step {progress['step']}, coverage {progress['coverage']:.1%}", file=sys.stderr)


def _sim_step(progress_file: Path) -> int:
    try:
        return int(json.loads(progress_file.read_text())["step"])
    except (OSError, ValueError, KeyError):
        return -1


class _Faults:
    """The mission's scheduled faults, struck at the processes as the simulation reaches their steps (from
    the launcher's own thread: a process started from another thread would get the death signal when that
    thread ends)."""

    def __init__(self, team: TeamProcesses, spec: MissionSpec, names: list[str], progress_file: Path) -> None:
        faults = spec.mission_cfg.faults
        self.team, self.names, self.progress_file = team, names, progress_file
        self.due = sorted(
            [(step, "robot", robot) for robot, step in faults.robot_failures]
            + [(step, "centre", 0) for step in faults.centre_restarts]
        )
        self._restart_at: float | None = None
        self.centres = 1

    def poll(self) -> None:
        if self._restart_at is not None and time.monotonic() >= self._restart_at:
            self._restart_at = None
            self.centres += 1
            cmd = self.team.commands["centre"]
            record = cmd.index("--record") + 1  # each centre keeps its own record
            cmd = [*cmd[:record], str(self.team.work / f"centre-{self.centres}.json"), *cmd[record + 1 :]]
            self.team.start("centre", cmd)
        if not self.due or _sim_step(self.progress_file) < self.due[0][0]:
            return
        step, kind, robot = self.due.pop(0)
        if kind == "robot":
            print(f"step {step}: robot {self.names[robot]}'s node killed", file=sys.stderr)
            self.team.kill(self.names[robot])
        else:
            print(f"step {step}: centre killed; a new one starts in {_RESTART_AFTER_S:.0f} s", file=sys.stderr)
            self.team.kill("centre")
            self._restart_at = time.monotonic() + _RESTART_AFTER_S


def launch_team(
    spec: MissionSpec,
    run: RunConfig,
    deployment: Deployment,
    grid: TeamGrid,
    argv: list[str],
    args: argparse.Namespace,
) -> dict[str, Any]:
    """Run one mission (``spec``, with the settings ``run``) through separate processes; returns the
    simulator's measures (``measures``), the starts and what the centre measured on the wire."""
    domain = "the system's"
    if not args.network:
        from mrexplore.ros2.loopback import keep_on_loopback

        domain = keep_on_loopback()["ROS_DOMAIN_ID"]
    work = Path(tempfile.mkdtemp(prefix="mrexplore_launch_"))
    config = work / "config.yaml"
    config.write_text(config_yaml(run))
    deployment = _timed(deployment, grid, spec, args)
    loss = spec.mission_cfg.faults.message_loss
    robots_file, centre_file = work / "deployment.yaml", work / "centre_deployment.yaml"
    robots_file.write_text(yaml.safe_dump(deployment.to_dict(), sort_keys=False))
    centre_side = deployment
    if loss > 0:
        relayed = tuple(replace(r, frontiers_topic=relayed_topic(r.name)) for r in deployment.robots)
        centre_side = replace(deployment, robots=relayed)
    centre_file.write_text(yaml.safe_dump(centre_side.to_dict(), sort_keys=False))
    me = [sys.executable, "-m", "mrexplore"]
    net = ["--network"] if args.network else []
    centre_cmd = [*me, "ros2", "centre", "--strategy", args.strategy, "--seed", str(args.seed)]
    centre_cmd += ["--record", str(work / "centre.json"), "--deployment", str(centre_file), "--config", str(config)]
    centre_cmd += net
    if args.policy:
        centre_cmd += ["--policy", args.policy]
    for flag in ("no_local", "lockstep", "direct_maps"):
        if getattr(args, flag):
            centre_cmd.append("--" + flag.replace("_", "-"))
    # Under --nav2 every node of the team runs on the double's sim time, as on a simulated Nav2 team.
    ros_args = ["--ros-args", "-p", "use_sim_time:=true"] if getattr(args, "nav2", False) else []
    centre_cmd += ros_args
    team = TeamProcesses(work)

    def stop(signum: int, frame: object) -> None:
        raise KeyboardInterrupt  # SIGTERM ends the launch as Ctrl-C does: every process it started is ended

    signal.signal(signal.SIGTERM, stop)
    progress_file = work / "progress.json"
    names = [r.name for r in deployment.robots]
    try:
        team.start("centre", centre_cmd)
        if not args.direct_maps:
            for name in names:
                robot_cmd = [*me, "ros2", "robot", "--name", name, "--deployment", str(robots_file), *net]
                team.start(name, robot_cmd + ros_args)
        if loss > 0:
            relay = [*me, "ros2", "relay", "--deployment", str(robots_file), "--loss", str(loss)]
            team.start("relay", relay + ["--seed", str(args.seed), *net])
        sim = team.start("sim", [*me, *_sim_argv(argv, progress_file)], stdout=subprocess.PIPE)
        print(
            f"launched: sim, {'no robot nodes' if args.direct_maps else f'{len(names)} robot nodes'}, "
            f"{'a relay losing ' + format(loss, '.0%') + ', ' if loss > 0 else ''}"
            f"centre ({'lockstep' if args.lockstep else 'real time'}); ROS domain {domain}; logs in {work}"
            f"{'' if args.keep_logs else ' (removed at the end unless the run fails; --keep-logs keeps them)'}",
            file=sys.stderr,
        )
        faults = _Faults(team, spec, names, progress_file)
        said = time.monotonic()
        while sim.poll() is None:
            faults.poll()
            time.sleep(0.02)
            if time.monotonic() - said >= _SAY_EVERY_S:  # a line every few seconds: the run is alive
                said = time.monotonic()
                _say_progress(progress_file)
        assert sim.stdout is not None
        out = sim.stdout.read()
        if sim.returncode != 0:
            tail = (work / "sim.log").read_text()[-600:].strip().splitlines()
            raise MrExploreError(f"the simulation failed ({tail[-1] if tail else 'no output'}); logs in {work}")
        sim_record = json.loads(out.strip().splitlines()[-1])
    finally:
        team.stop_all()
    record = _launch_record(work, sim_record, args)
    if not args.keep_logs:  # a run that ended well leaves nothing behind; a failed one keeps its logs (above)
        shutil.rmtree(work, ignore_errors=True)
        record["logs"] = None
    return record


def _timed(deployment: Deployment, grid: TeamGrid, spec: MissionSpec, args: argparse.Namespace) -> Deployment:
    """The deployment on the launch's team grid, its centre's clock following the simulation's: a round every
    two steps, a full decision as often as the simulator's own replanning."""
    period = max(0.05, 2.0 / args.speed)
    rate = args.clock_rate if getattr(args, "nav2", False) else 1.0
    return replace(
        deployment,
        team_grid=grid,
        round_period_s=period,
        round_timeout_s=period,
        # Five seconds of the wall clock, whatever the sim clock's rate: every process shares two cores here.
        lost_after_s=deployment.lost_after_s * max(1.0, rate),
        replan_s=spec.mission_cfg.replan_every_steps / args.speed,
        min_replan_s=spec.mission_cfg.min_replan_steps / args.speed,
    )


def _launch_record(work: Path, sim_record: dict[str, Any], args: argparse.Namespace) -> dict[str, Any]:
    """The simulator's measures and what the centres (one, or one per restart) counted."""
    records = sorted(work.glob("centre*.json"), key=lambda p: (len(p.name), p.name))  # in the order they ran
    if not records:
        raise MrExploreError(f"the centre wrote no record; its log is {work / 'centre.log'}")
    centre = merged_records([json.loads(p.read_text()) for p in records])
    double = ("goals_received", "aborts_caused", "aborts_crossed", "preempted", "sim_seconds")
    return {
        "measures": {k: v for k, v in sim_record.items() if k not in ("starts_rc", "map_mismatches", *double)},
        "starts_rc": sim_record.get("starts_rc", []),
        "transport": "ros2",
        "lockstep": bool(args.lockstep),
        "map_mismatches": sim_record.get("map_mismatches"),
        "wire": wire_summary(centre["wire"]),
        "centre": {k: centre.get(k) for k in _CENTRE_KEYS},
        "centres": len(records),
        "goals_sent": centre.get("goals_sent"),
        "goals_resent": centre.get("goals_resent"),
        "aborts_read": centre.get("aborts"),
        "robots_lost": len(centre.get("lost") or []),
        "nav2_double": {k: sim_record.get(k) for k in double} if not args.lockstep else None,
        "decision_ms_median": _median(centre.get("decision_ms", [])),
        "ros_domain_id": int(os.environ["ROS_DOMAIN_ID"]) if os.environ.get("ROS_DOMAIN_ID", "").isdigit() else None,
        "logs": str(work),
    }


def _median(values: list[float]) -> float | None:
    return sorted(values)[len(values) // 2] if values else None


def wire_summary(per_robot: dict[str, dict[str, int]]) -> dict[str, Any]:
    """The frontier messages the centre received, summed over the robots: payload (what the simulator counts)
    and serialized (what the middleware carried), with the fixed per-message overhead between them."""
    keys: tuple[str, ...] = ("messages", "payload_bytes", "serialized_bytes", "resent_messages", "resent_payload_bytes")
    keys += ("resent_serialized_bytes", "repeats", "late")
    total: dict[str, Any] = {k: sum(r.get(k, 0) for r in per_robot.values()) for k in keys}
    n = total["messages"] + total["resent_messages"]
    overhead = total["serialized_bytes"] + total["resent_serialized_bytes"] - total["payload_bytes"]
    overhead -= total["resent_payload_bytes"]
    total["overhead_bytes_per_message"] = overhead / n if n else None
    total["per_robot"] = per_robot
    return total


def merged_records(records: list[dict[str, Any]]) -> dict[str, Any]:
    """The records of the centres that ran one after another (a restart starts a new one) as one: counts
    summed, each robot's wire counts summed, the decisions' latencies joined, the state the last one's.

    Examples
    --------
    >>> first = {"goals_sent": 9, "wire": {"r1": {"messages": 4}}, "decision_ms": [1.0], "finished": None}
    >>> last = {"goals_sent": 3, "wire": {"r1": {"messages": 2}}, "decision_ms": [2.0], "finished": "stopped"}
    >>> m = merged_records([first, last])
    >>> m["goals_sent"], m["wire"], m["decision_ms"], m["finished"]
    (12, {'r1': {'messages': 6}}, [1.0, 2.0], 'stopped')
    """
    merged = dict(records[-1])
    for key in ("goals_sent", "goals_resent", "aborts", "decisions", "warnings"):
        merged[key] = sum(r.get(key) or 0 for r in records)
    merged["decision_ms"] = [ms for r in records for ms in r.get("decision_ms", [])]
    wire: dict[str, dict[str, int]] = {}
    for r in records:
        for name, counts in r.get("wire", {}).items():
            mine = wire.setdefault(name, {})
            for k, v in counts.items():
                mine[k] = mine.get(k, 0) + v
    merged["wire"] = wire
    return merged
