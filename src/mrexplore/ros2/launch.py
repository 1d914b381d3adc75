"""``mrexplore ros2 launch``: the simulator, a robot node per robot and the centre as separate processes on
one machine, talking through ROS 2 (kept on loopback unless ``--network``), ended together.

It imports no rclpy itself: it sets the environment (:func:`~mrexplore.ros2.loopback.keep_on_loopback`) that
its children inherit, starts them, waits for the simulation to end, stops the others (SIGTERM, then SIGKILL
after a grace period), and merges their records.
"""

from __future__ import annotations

import argparse
import json
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
from mrexplore.types import MrExploreError

__all__ = ["launch_team", "stop_all"]

_LAUNCH_ONLY = {"--json": 0, "--direct-maps": 0}
"""launch's own flags (and how many values each takes), not passed on to the simulator."""
_GRACE_S = 10.0


def stop_all(processes: list[subprocess.Popen[Any]]) -> None:
    """End every process still running: SIGTERM, then SIGKILL after a grace period."""
    for p in processes:
        if p.poll() is None:
            p.send_signal(signal.SIGTERM)
    t0 = time.monotonic()
    for p in processes:
        try:
            p.wait(timeout=max(0.1, _GRACE_S - (time.monotonic() - t0)))
        except subprocess.TimeoutExpired:
            p.kill()
            p.wait()


def _sim_argv(argv: list[str]) -> list[str]:
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
    return [*out, "--json"]


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
    if not args.network:
        from mrexplore.ros2.loopback import keep_on_loopback

        keep_on_loopback()
    work = Path(tempfile.mkdtemp(prefix="mrexplore_launch_"))
    config = work / "config.yaml"
    config.write_text(config_yaml(run))
    # The centre's clock follows the simulation's: a round every two steps, a full decision as often as the
    # simulator's own replanning.
    period = max(0.05, 2.0 / args.speed)
    deployment = replace(
        deployment,
        team_grid=grid,
        round_period_s=period,
        round_timeout_s=period,
        replan_s=spec.mission_cfg.replan_every_steps / args.speed,
    )
    team_file = work / "deployment.yaml"
    team_file.write_text(yaml.safe_dump(deployment.to_dict(), sort_keys=False))
    me = [sys.executable, "-m", "mrexplore"]
    team = ["--deployment", str(team_file), "--config", str(config)]
    if args.network:
        team.append("--network")
    centre_cmd = [*me, "ros2", "centre", "--strategy", args.strategy, "--seed", str(args.seed)]
    centre_cmd += ["--record", str(work / "centre.json"), *team]
    if args.policy:
        centre_cmd += ["--policy", args.policy]
    if args.no_local:
        centre_cmd.append("--no-local")
    if args.lockstep:
        centre_cmd.append("--lockstep")
    if args.direct_maps:
        centre_cmd.append("--direct-maps")
    logs: list[Any] = []
    processes: list[subprocess.Popen[Any]] = []

    def start(cmd: list[str], name: str, stdout: Any = subprocess.DEVNULL) -> subprocess.Popen[Any]:
        log = open(work / f"{name}.log", "w")  # noqa: SIM115 - closed with the others at the end
        logs.append(log)
        p = subprocess.Popen(cmd, stdout=stdout, stderr=log, text=True)
        processes.append(p)
        return p

    try:
        start(centre_cmd, "centre")
        if not args.direct_maps:
            for r in deployment.robots:
                start([*me, "ros2", "robot", "--name", r.name, *team], r.name)
        sim = start([*me, *_sim_argv(argv)], "sim", stdout=subprocess.PIPE)
        print(
            f"launched: sim, {'no robot nodes' if args.direct_maps else f'{len(deployment.robots)} robot nodes'}, "
            f"centre ({'lockstep' if args.lockstep else 'real time'}); logs in {work}",
            file=sys.stderr,
        )
        out, _ = sim.communicate()
        if sim.returncode != 0:
            tail = (work / "sim.log").read_text()[-600:].strip().splitlines()
            raise MrExploreError(f"the simulation failed ({tail[-1] if tail else 'no output'}); logs in {work}")
        sim_record = json.loads(out.strip().splitlines()[-1])
    finally:
        stop_all(processes)
        for log in logs:
            log.close()
    centre_file = work / "centre.json"
    if not centre_file.is_file():
        raise MrExploreError(f"the centre wrote no record; its log is {work / 'centre.log'}")
    centre = json.loads(centre_file.read_text())
    return {
        "measures": {k: v for k, v in sim_record.items() if k not in ("starts_rc", "map_mismatches")},
        "starts_rc": sim_record.get("starts_rc", []),
        "transport": "ros2",
        "lockstep": bool(args.lockstep),
        "map_mismatches": sim_record.get("map_mismatches"),
        "wire": wire_summary(centre["wire"]),
        "centre": {k: centre[k] for k in ("decisions", "aborts", "warnings", "finished")},
        "decision_ms_median": _median(centre.get("decision_ms", [])),
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
