"""The ROS 2 adapters' messages through the real middleware, on loopback: the team map and a robot's sparse
frontier message published, received and read back unchanged."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import types
from pathlib import Path

import pytest
from conftest import requires_rclpy

from mrexplore.types import MrExploreError

pytestmark = requires_rclpy


def test_the_team_map_and_a_frontier_message_cross_the_middleware_unchanged() -> None:
    script = Path(__file__).with_name("roundtrip.py")
    out = subprocess.run([sys.executable, str(script)], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    result = json.loads(out.stdout.strip().splitlines()[-1])
    assert result["map_equal"] and result["bytes_equal"] and result["cells"] > 0
    env = result["env"]
    exported = os.environ.get("ROS_DOMAIN_ID")  # a ROS user's own is kept; else one is drawn in 1-101
    assert env["ROS_AUTOMATIC_DISCOVERY_RANGE"] == "LOCALHOST"
    assert env["ROS_DOMAIN_ID"] == exported if exported else 1 <= int(env["ROS_DOMAIN_ID"]) <= 101
    assert "127.0.0.1" in Path(env["FASTRTPS_DEFAULT_PROFILES_FILE"]).read_text()


@pytest.mark.parametrize(("exported", "want"), [("166", "166"), ("0", "0"), ("", None)])
def test_an_exported_domain_id_is_kept_and_one_is_drawn_only_where_none_is(monkeypatch, exported, want) -> None:
    from mrexplore.ros2 import loopback

    monkeypatch.setattr(loopback, "sys", types.SimpleNamespace(modules={}))  # as in a process before rclpy
    for var in ("ROS_AUTOMATIC_DISCOVERY_RANGE", "RMW_IMPLEMENTATION", "FASTRTPS_DEFAULT_PROFILES_FILE"):
        monkeypatch.setenv(var, "")  # restored after the test, as the variables it sets are
    monkeypatch.setenv("FASTDDS_DEFAULT_PROFILES_FILE", "")
    monkeypatch.setenv("ROS_DOMAIN_ID", exported)
    env = loopback.keep_on_loopback()
    assert env["ROS_DOMAIN_ID"] == want if want else 1 <= int(env["ROS_DOMAIN_ID"]) <= 101


@pytest.mark.parametrize("exported", ["233", "x", "-1"])
def test_an_exported_domain_id_out_of_range_is_one_line(monkeypatch, exported) -> None:
    from mrexplore.ros2 import loopback

    monkeypatch.setenv("ROS_DOMAIN_ID", exported)
    with pytest.raises(MrExploreError) as err:
        loopback.exported_domain_id()
    assert str(err.value) == (
        f"ROS_DOMAIN_ID must be an integer in [0, 232], got {exported!r}; export another, or unset it"
    )


def test_loopback_settings_refuse_to_come_after_rclpy() -> None:
    code = "import rclpy\nfrom mrexplore.ros2.loopback import keep_on_loopback\nkeep_on_loopback()\n"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert out.returncode != 0
    assert "keep_on_loopback() must run before rclpy is imported; call it first" in out.stderr


ROS_ARGS = """
from mrexplore.ros2.robot_node import start_rclpy
rclpy = start_rclpy(True, ["--ros-args", "-p", "use_sim_time:=true", "-r", "/robot1/map:=/robot1/slam_map"])
node = rclpy.create_node("mrexplore_robot1")
print(node.get_parameter("use_sim_time").value, node.resolve_topic_name("/robot1/map"))
node.destroy_node()
rclpy.shutdown()
"""


def test_a_node_takes_ros_own_arguments() -> None:
    """``--ros-args`` reaches rcl as for any ROS 2 node: a parameter (``use_sim_time``) and a remap."""
    out = subprocess.run([sys.executable, "-c", ROS_ARGS], capture_output=True, text=True, timeout=60)
    assert out.returncode == 0, out.stderr
    assert out.stdout.split() == ["True", "/robot1/slam_map"]


def test_ros_args_are_split_off_and_refused_where_no_node_starts(capsys) -> None:
    from mrexplore.cli import main
    from mrexplore.cli.main import split_ros_args

    argv = ["ros2", "centre", "--names", "a", "--ros-args", "-r", "__ns:=/team", "--", "--seed", "3"]
    assert split_ros_args(argv) == (
        ["ros2", "centre", "--names", "a", "--seed", "3"],
        ["--ros-args", "-r", "__ns:=/team"],
    )
    assert main(["explore", "--ros-args", "-p", "use_sim_time:=true"]) == 2
    assert capsys.readouterr().err == (
        "mrexplore: error: --ros-args is for the ros2 commands that start a node (robot, centre, relay, sim); drop it\n"
    )
