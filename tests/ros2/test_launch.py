"""``mrexplore ros2 launch``: the simulator, three robot nodes and the centre as separate processes on
loopback. In lockstep the mission equals ``mrexplore explore``'s, and the bytes the centre received on the wire
equal those the simulator counts; in real time the team finishes the map, also when a robot node is killed,
when the centre is killed and started again, and when a relay drops 30% of the frontier messages."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest
from conftest import requires_rclpy

pytestmark = [requires_rclpy, pytest.mark.slow]

MAP = ["--map", "generated:0", "--resolution", "0.2"]
SAME = ("steps", "coverage", "steps_to_99", "decisions", "path_len_sum_m", "done_reason", "bytes_sparse_delta")


def mrexplore(*args: str) -> dict:
    out = subprocess.run(
        [sys.executable, "-m", "mrexplore", *args, "--json"], capture_output=True, text=True, timeout=600
    )
    assert out.returncode == 0, out.stderr[-2000:]
    return json.loads(out.stdout.strip().splitlines()[-1])


@pytest.mark.parametrize("strategy", ["utility", "hier"])
def test_lockstep_through_ros2_equals_explore(strategy: str) -> None:
    alone = mrexplore("explore", *MAP, "--strategy", strategy)
    launched = mrexplore("ros2", "launch", *MAP, "--strategy", strategy, "--lockstep")
    assert {k: launched[k] for k in SAME} == {k: alone[k] for k in SAME}
    assert launched["map_mismatches"] == 0  # the centre decided on the very grid the simulator rebuilt
    wire = launched["wire"]
    assert wire["payload_bytes"] == alone["bytes_sparse_delta"]  # every message's bytes, as counted
    assert wire["messages"] == alone["messages_sent"]  # (a robot asked again while busy answers again: apart)
    assert 12 <= wire["overhead_bytes_per_message"] <= 24  # CDR's header and padding, per message


@pytest.mark.parametrize(
    "fault",
    [[], ["--robot-failure", "1@80"], ["--centre-restart", "120"], ["--message-loss", "0.3"]],
    ids=["none", "robot-node-killed", "centre-restarted", "relay-drops-30pc"],
)
def test_real_time_team_finishes_the_map(fault: list[str]) -> None:
    run = mrexplore("ros2", "launch", *MAP, "--strategy", "utility", "--speed", "20", *fault)
    assert run["coverage"] >= 0.99
    assert run["done_reason"] in ("no_frontiers", "no_reachable_frontiers")
    if fault and fault[0] == "--robot-failure":
        assert run["robots_lost"] == 1
        assert run["centre"]["lost"] == ["robot2"]  # the centre no longer waits for the killed node
    if fault and fault[0] == "--message-loss":
        assert run["wire"]["messages"] > 0


def test_direct_maps_need_no_robot_node() -> None:
    alone = mrexplore("explore", *MAP, "--strategy", "utility")
    launched = mrexplore("ros2", "launch", *MAP, "--strategy", "utility", "--lockstep", "--direct-maps")
    assert {k: launched[k] for k in SAME} == {k: alone[k] for k in SAME}
    assert launched["wire"]["payload_bytes"] == alone["bytes_sparse_delta"] and launched["map_mismatches"] == 0
