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


@pytest.mark.parametrize("strategy", ["utility", "hier", "hier-plan-nolocal"])
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


@pytest.mark.parametrize("fault", [[], ["--robot-failure", "1@60"]], ids=["none", "robot-node-killed"])
def test_a_nav2_team_on_sim_time_with_slam_maps_finer_than_the_team_grid(fault: list[str]) -> None:
    # The double behaves as Nav2 and slam_toolbox do: goals stamped on its sim clock (twice the wall clock),
    # a new goal aborting the last, a map frame per robot a quarter turn apart, 0.05 m maps under 0.2 m cells.
    nav2 = ["--nav2", "--slam-resolution", "0.05", "--clock-rate", "2"]
    run = mrexplore("ros2", "launch", *MAP, "--strategy", "utility", "--speed", "20", *nav2, *fault)
    assert run["coverage"] >= 0.99
    assert run["goals_resent"] * 20 <= max(run["goals_sent"], 20)  # at most one goal in 20 sent again
    double = run["nav2_double"]
    assert double["preempted"] > 0  # the centre replaced goals, and their aborts were not read as aborts
    assert run["aborts_read"] >= double["aborts_caused"] - double["aborts_crossed"]
    assert run["robots_lost"] == (1 if fault else 0)
    assert isinstance(run["ros_domain_id"], int)
