"""Run by tests/ros2/test_centre_node.py in a fresh interpreter: ``mrexplore ros2 centre`` and ``mrexplore ros2
robot`` in processes of their own, this script playing the robot's SLAM (its map and pose) and Nav2 (the
action status) through the middleware on loopback. Prints one JSON line."""

from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOM_START = (5, 3)


def room() -> np.ndarray:
    """A 12 x 20 room open to unknown space on its east side and through a door in its north wall."""
    from mrexplore.types import CellState

    state = np.full((12, 20), CellState.UNKNOWN, np.uint8)
    state[2:10, 0:11] = CellState.OCCUPIED
    state[3:9, 1:11] = CellState.FREE
    state[2, 2:5] = CellState.UNKNOWN
    return state


def main() -> None:
    """The whole session (the loopback settings first, then rclpy)."""
    from mrexplore.ros2.loopback import keep_on_loopback

    keep_on_loopback()

    import rclpy
    from action_msgs.msg import GoalStatus, GoalStatusArray
    from geometry_msgs.msg import PoseStamped
    from nav_msgs.msg import OccupancyGrid
    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
    from std_msgs.msg import String, UInt8MultiArray
    from std_srvs.srv import Trigger
    from visualization_msgs.msg import MarkerArray

    from mrexplore.config import PreprocessConfig, SensorConfig
    from mrexplore.maps.frame import GridFrame
    from mrexplore.maps.occupancy_grid import occupancy_values
    from mrexplore.preprocessing.agents import RobotAgent, TeamCentre
    from mrexplore.preprocessing.sparse_codec import decode
    from mrexplore.ros2.messages import pose_message, team_map_message

    team = GridFrame(height=12, width=20, resolution_m=0.1)
    work = Path(tempfile.mkdtemp(prefix="centre_session_"))
    deployment = work / "team.yaml"
    deployment.write_text(
        "team_grid: {x0: 0.0, y0: 0.0, width: 2.0, height: 1.2, resolution: 0.1}\n"
        "round_period_s: 0.2\nround_timeout_s: 0.2\nreplan_s: 100.0\nblacklist_s: 60.0\nrobots: [robot1]\n"
    )
    me = [sys.executable, "-m", "mrexplore", "ros2"]
    centre = subprocess.Popen(
        [*me, "centre", "--deployment", str(deployment), "--strategy", "nearest", "--record", str(work / "c.json")],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
    )
    robot = subprocess.Popen(
        [*me, "robot", "--name", "robot1", "--deployment", str(deployment)],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    result: dict[str, object] = {}
    try:
        rclpy.init()
        node = rclpy.create_node("test_robot1_world")
        latched = QoSProfile(
            depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL, reliability=ReliabilityPolicy.RELIABLE
        )
        map_pub = node.create_publisher(OccupancyGrid, "/robot1/map", latched)
        pose_pub = node.create_publisher(type(pose_message(0, 0, 0, "map", None)), "/robot1/pose", 10)
        nav_pub = node.create_publisher(GoalStatusArray, "/robot1/navigate_to_pose/_action/status", 10)
        goal_pub = node.create_publisher(PoseStamped, "/robot1/goal_pose", 10)  # the stranger
        junk_pub = node.create_publisher(UInt8MultiArray, "/mrexplore/robot1/frontiers", 10)
        goals: list[tuple[float, float]] = []
        statuses: list[dict] = []
        views: dict[str, object] = {}
        node.create_subscription(
            PoseStamped, "/robot1/goal_pose", lambda m: goals.append((m.pose.position.x, m.pose.position.y)), 10
        )
        node.create_subscription(String, "/mrexplore/status", lambda m: statuses.append(json.loads(m.data)), 10)
        node.create_subscription(OccupancyGrid, "/mrexplore/map", lambda m: views.update(map=m), latched)
        node.create_subscription(MarkerArray, "/mrexplore/markers", lambda m: views.update(markers=m), latched)

        def spin(seconds: float) -> None:
            t0 = time.monotonic()
            while time.monotonic() - t0 < seconds:
                rclpy.spin_once(node, timeout_sec=0.02)

        def publish_world() -> None:
            stamp = node.get_clock().now().to_msg()
            grid = team_map_message(room(), team, "map")
            grid.header.stamp = stamp
            map_pub.publish(grid)
            x, y = team.rc_to_xy(ROOM_START)
            pose_pub.publish(pose_message(x, y, 0.0, "map", stamp))

        def wait_goal(count: int, limit_s: float) -> bool:
            t0 = time.monotonic()
            while len(goals) < count and time.monotonic() - t0 < limit_s:
                publish_world()
                spin(0.1)
            return len(goals) >= count

        result["first_goal"] = wait_goal(1, 300)  # a first run compiles the kernels: minutes
        spin(0.5)
        # The team map and markers, read back.
        agent = RobotAgent(0, (12, 20), PreprocessConfig(), SensorConfig())
        agent.sense_state(room())
        reference = TeamCentre(1, (12, 20), PreprocessConfig().closing_size_cells, silence_rounds=3)
        reference.receive(decode(agent.compose(0, ROOM_START, agent.window()).full_bytes()), 0)
        expected_map = occupancy_values(reference.state()).tobytes()
        team_map = views["map"]
        result["team_map_equal"] = bytes(np.asarray(team_map.data, np.int8).tobytes()) == expected_map
        markers = views["markers"].markers
        by_ns: dict[str, int] = {}
        for m in markers:
            by_ns[m.ns] = by_ns.get(m.ns, 0) + 1
        result["markers"] = by_ns
        result["clusters"] = statuses[-1]["clusters"]
        # Nav2 takes the goal under an id of its own, then aborts it.
        gid = os.urandom(16)

        def nav(status_code: int, goal_id: bytes, stamp: object) -> None:
            s = GoalStatus()
            s.goal_info.goal_id.uuid = list(goal_id)
            s.goal_info.stamp = stamp
            s.status = status_code
            nav_pub.publish(GoalStatusArray(status_list=[s]))

        accepted = node.get_clock().now().to_msg()
        nav(GoalStatus.STATUS_EXECUTING, gid, accepted)
        spin(0.5)
        n_goals = len(goals)
        nav(GoalStatus.STATUS_ABORTED, gid, accepted)
        got = wait_goal(n_goals + 1, 10)
        spin(0.3)
        after = [s["round"] for s in statuses if s["decisions"] >= 2]
        # from the first round that read the abort (a round open when it came may close first)
        read = [s["round"] for s in statuses if s["aborts"] >= 1]
        result["abort"] = {
            "new_goal": got and goals[-1] != goals[n_goals - 1],
            "rounds_after_abort": (after[0] - read[0]) if after and read else None,
            "aborts": statuses[-1]["aborts"],
        }
        # Bad messages: each one warning line, dropped; the centre keeps what it had and goes on.
        map_before, rounds_before = bytes(views["map"].data), statuses[-1]["round"]
        junk_pub.publish(UInt8MultiArray(data=b"\x07not a frontier message"))
        spin(0.5)
        nav(GoalStatus.STATUS_SUCCEEDED, os.urandom(16), accepted)  # a goal the centre never sent
        spin(0.5)
        stranger = PoseStamped()
        stranger.header.frame_id = "map"
        stranger.pose.position.x, stranger.pose.orientation.w = 0.35, 1.0
        goal_pub.publish(stranger)
        spin(0.8)
        result["kept_map"] = bytes(views["map"].data) == map_before
        result["kept_going"] = statuses[-1]["round"] > rounds_before
        # The services: every robot back to its start, then stop.
        home = node.create_client(Trigger, "/mrexplore/return_home")
        stop = node.create_client(Trigger, "/mrexplore/stop")
        for client in (home, stop):
            client.wait_for_service(timeout_sec=10)
        n_goals = len(goals)
        future = home.call_async(Trigger.Request())
        rclpy.spin_until_future_complete(node, future, timeout_sec=10)
        spin(0.5)
        result["home"] = future.result().success and len(goals) > n_goals and goals[-1] == team.rc_to_xy(ROOM_START)
        future = stop.call_async(Trigger.Request())
        rclpy.spin_until_future_complete(node, future, timeout_sec=10)
        result["stop"] = bool(future.result().success)
        spin(0.5)
        result["stop_status"] = statuses[-1]["finished"]  # the last status says why it ended
        node.destroy_node()
        rclpy.shutdown()
        try:
            _, err = centre.communicate(timeout=20)  # the stop service ends the centre
        except subprocess.TimeoutExpired:
            centre.kill()
            _, err = centre.communicate()
        result["centre_exit"] = centre.returncode
        result["centre_said"] = err.strip().splitlines()[-1] if err.strip() else ""
        # The centre node's own warnings (ROS may add its own, e.g. a deprecation warning where
        # ROS_LOCALHOST_ONLY is set in a ROS user's shell)
        ours = [line for line in err.splitlines() if "WARN" in line and "[mrexplore_centre]" in line]
        result["warnings"] = [line.split("]: ", 1)[-1] for line in ours]
        result["record"] = json.loads((work / "c.json").read_text())["finished"]
    finally:
        for p in (centre, robot):
            if p.poll() is None:
                p.send_signal(signal.SIGTERM)
        for p in (centre, robot):
            try:
                p.wait(timeout=20)
            except subprocess.TimeoutExpired:
                p.kill()
                p.wait()
        shutil.rmtree(work, ignore_errors=True)  # nothing left in the temporary folder
    print(json.dumps(result))


if __name__ == "__main__":
    main()
