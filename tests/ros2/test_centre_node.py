"""``mrexplore ros2 centre`` and a robot node in processes of their own, driven through the middleware on
loopback by a test world that plays the robot's SLAM and Nav2 (centre_session.py): a first goal; the team map
and the markers read back; an aborted goal replaced by another at once; a frontier message that does not
decode, a status for an unknown goal and a stranger's goal each one warning line, dropped, with nothing lost;
the return-home and stop services."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest
from conftest import requires_rclpy

pytestmark = [requires_rclpy, pytest.mark.slow]


def test_the_centre_node_plans_reads_nav2_and_survives_bad_messages() -> None:
    script = Path(__file__).with_name("centre_session.py")
    out = subprocess.run([sys.executable, str(script)], capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, out.stderr[-2000:]
    result = json.loads(out.stdout.strip().splitlines()[-1])
    assert result["first_goal"]
    # the team map equals the one the same objects build in one process; one sphere per cluster centre,
    # one goal and one route for the one robot (and the DELETEALL that clears the last views)
    assert result["team_map_equal"]
    assert result["markers"] == {"": 1, "frontiers": 1, "clusters": result["clusters"], "goals": 1, "routes": 1}
    assert result["clusters"] >= 2
    # Nav2 aborted the goal: another goal in the very round that reads the abort
    assert result["abort"] == {"new_goal": True, "rounds_after_abort": 0, "aborts": 1}
    assert result["warnings"] == [
        "frontier message from robot1 dropped: bad frontier message: magic 0x07 is not 0x4d; "
        "drop it and ask the robot for a full map",
        result["warnings"][1],
        "goal on /robot1/goal_pose not sent by this centre (another node publishes there); "
        "the centre keeps its own goal",
    ]
    assert result["warnings"][1].startswith("navigation status of robot1 for unknown goal ")
    assert result["warnings"][1].endswith(" dropped")
    assert result["kept_map"] and result["kept_going"]
    assert result["home"] and result["stop"] and result["stop_status"] == "stopped"
    assert result["centre_exit"] == 0
    assert result["centre_said"] == "centre stopped: stopped by /mrexplore/stop"
    assert result["record"] == "stopped"
