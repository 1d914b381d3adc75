"""``mrexplore ros2 robot`` in a process of its own, driven through the middleware on loopback by a test
centre: whole map, delta, a refused delta after a centre restart and the whole map resent, and a malformed
map, a pose of NaN and a pose in the odometry frame dropped with one warning each while the node keeps what it had."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest
from conftest import requires_rclpy

pytestmark = [requires_rclpy, pytest.mark.slow]


def test_the_robot_node_speaks_the_protocol_and_survives_a_bad_map() -> None:
    script = Path(__file__).with_name("robot_session.py")
    out = subprocess.run([sys.executable, str(script)], capture_output=True, text=True, timeout=240)
    assert out.returncode == 0, out.stderr[-2000:]
    result = json.loads(out.stdout.strip().splitlines()[-1])
    assert result["steps"] == [
        ["whole", True],
        ["delta", True],
        ["refused", True],
        ["resent", True],
        ["after_bad_map", True],
    ]
    assert result["centre_equals_in_process"]  # the same map the objects give in one process
    warnings = result["warnings"]
    expected = [
        "map dropped: occupancy grid data holds 77 values for 10 x 8 = 80 cells",
        "map dropped: occupancy grid resolution must be a finite number > 0 metres, got nan",
        "map dropped: occupancy grid resolution must be a finite number > 0 metres, got inf",
        "map dropped: occupancy grid resolution must be a finite number > 0 metres, got 0.0",
        "map dropped: occupancy grid of 100000 x 100000 cells is empty or larger than 60,000,000 cells; "
        "publish a map of the area explored",
        "map dropped: occupancy grid origin must be finite x, y and yaw, got (nan, 0.0, 0.0)",
        "pose dropped: position (nan, 0.0) and heading 0.0 must be finite",
        "pose dropped: /robot1/pose is in frame 'odom', the map in 'map'; give a pose in the map frame "
        "(AMCL's amcl_pose, slam_toolbox's pose) or pose_type tf",
    ]
    assert len(warnings) == len(expected)  # one line each, dropped; the node kept what it had (steps above)
    for line, text in zip(warnings, expected, strict=True):
        assert line.endswith(text)
    assert result["robot_exit"] == 0 and result["stop_s"] < 10  # ended by the test's SIGTERM, cleanly
