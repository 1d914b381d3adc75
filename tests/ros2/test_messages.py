"""The ROS 2 adapters' messages through the real middleware, on loopback: the team map and a robot's sparse
frontier message published, received and read back unchanged."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

from conftest import requires_rclpy

pytestmark = requires_rclpy


def test_the_team_map_and_a_frontier_message_cross_the_middleware_unchanged() -> None:
    script = Path(__file__).with_name("roundtrip.py")
    out = subprocess.run([sys.executable, str(script)], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    result = json.loads(out.stdout.strip().splitlines()[-1])
    assert result["map_equal"] and result["bytes_equal"] and result["cells"] > 0
    env = result["env"]
    assert env["ROS_AUTOMATIC_DISCOVERY_RANGE"] == "LOCALHOST" and 1 <= int(env["ROS_DOMAIN_ID"]) <= 101
    assert "127.0.0.1" in Path(env["FASTRTPS_DEFAULT_PROFILES_FILE"]).read_text()


def test_loopback_settings_refuse_to_come_after_rclpy() -> None:
    code = "import rclpy\nfrom mrexplore.ros2.loopback import keep_on_loopback\nkeep_on_loopback()\n"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert out.returncode != 0
    assert "keep_on_loopback() must run before rclpy is imported; call it first" in out.stderr
