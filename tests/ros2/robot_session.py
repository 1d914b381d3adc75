"""Run by tests/ros2/test_robot_node.py in a fresh interpreter: ``mrexplore ros2 robot`` in a process of its
own, this script playing the centre (a TeamCentre) through the middleware on loopback. Prints one JSON line."""

from __future__ import annotations

import json
import signal
import subprocess
import sys
import time

import numpy as np


def main() -> None:
    """The whole session (the loopback settings first, then rclpy)."""
    from mrexplore.ros2.loopback import keep_on_loopback

    keep_on_loopback()

    import rclpy
    from geometry_msgs.msg import PoseWithCovarianceStamped
    from nav_msgs.msg import OccupancyGrid
    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
    from std_msgs.msg import UInt8MultiArray, UInt32MultiArray

    from mrexplore.config import PreprocessConfig, SensorConfig
    from mrexplore.maps.frame import GridFrame
    from mrexplore.preprocessing.agents import RobotAgent, TeamCentre
    from mrexplore.preprocessing.sparse_codec import decode, peek
    from mrexplore.ros2.messages import team_map_message
    from mrexplore.ros2.robot_node import ACK, WHOLE_MAP
    from mrexplore.types import CellState

    TEAM = GridFrame(height=8, width=10, resolution_m=0.1)  # the robot's --team-grid 0,0,1.0,0.8

    def room(c1: int) -> np.ndarray:
        state = np.full((8, 10), CellState.UNKNOWN, np.uint8)
        state[2:6, 1:c1] = CellState.FREE
        return state

    robot = subprocess.Popen(
        [sys.executable, "-m", "mrexplore", "ros2", "robot", "--name", "robot1", "--index", "0"]
        + ["--team-grid", "0,0,1.0,0.8", "--team-resolution", "0.1"],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
    )
    result: dict[str, object] = {}
    try:
        rclpy.init()
        node = rclpy.create_node("test_centre")
        latched = QoSProfile(
            depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL, reliability=ReliabilityPolicy.RELIABLE
        )
        map_pub = node.create_publisher(OccupancyGrid, "/robot1/map", latched)
        pose_pub = node.create_publisher(PoseWithCovarianceStamped, "/robot1/pose", 10)
        round_pub = node.create_publisher(UInt32MultiArray, "/mrexplore/round", 10)
        reply_pub = node.create_publisher(UInt32MultiArray, "/mrexplore/robot1/reply", 10)
        inbox: list[bytes] = []
        node.create_subscription(
            UInt8MultiArray, "/mrexplore/robot1/frontiers", lambda m: inbox.append(bytes(m.data)), 10
        )
        centre = TeamCentre(1, (8, 10), PreprocessConfig().closing_size_cells, silence_rounds=3)

        def spin(seconds: float) -> None:
            t0 = time.monotonic()
            while time.monotonic() - t0 < seconds:
                rclpy.spin_once(node, timeout_sec=0.02)

        def publish_world(state: np.ndarray) -> None:
            map_pub.publish(team_map_message(state, TEAM, "map"))
            pose = PoseWithCovarianceStamped()
            pose.header.frame_id = "map"
            pose.pose.pose.position.x, pose.pose.pose.position.y = 0.25, 0.45  # cell (3, 2)
            pose.pose.pose.orientation.w = 1.0
            pose_pub.publish(pose)

        def ask(round_: int, state: np.ndarray) -> bytes:
            """Publish the world and the round until the robot answers (it may still be starting)."""
            inbox.clear()
            t0 = time.monotonic()
            while not inbox and time.monotonic() - t0 < 30:
                publish_world(state)
                spin(0.1)
                round_pub.publish(UInt32MultiArray(data=[round_, 0, 0]))
                spin(0.2)
            return inbox.pop(0)

        def reply(round_: int, kind: int) -> None:
            t0 = time.monotonic()
            while reply_pub.get_subscription_count() == 0 and time.monotonic() - t0 < 10:
                spin(0.05)  # the robot's reply subscription matched
            reply_pub.publish(UInt32MultiArray(data=[round_, kind]))
            spin(0.3)

        kinds = []
        first = centre.read(ask(0, room(4)))
        kinds.append(("whole", first is not None and not first.is_delta and centre.accepts(first)))
        centre.receive(first, 0)
        reply(0, ACK)
        second = centre.read(ask(1, room(5)))  # one column more: the delta is shorter than the whole map
        kinds.append(("delta", second is not None and second.is_delta and centre.accepts(second)))
        centre.receive(second, 1)
        reply(1, ACK)
        centre.restart(2)  # the centre forgets: the next delta has no base
        third = ask(2, room(6))
        kinds.append(("refused", peek(third).is_delta and centre.read(third) is None))
        inbox.clear()
        reply(2, WHOLE_MAP)
        spin(1.0)
        whole = centre.read(inbox.pop(0))
        kinds.append(("resent", whole is not None and not whole.is_delta and centre.accepts(whole)))
        centre.receive(whole, 2)
        reply(2, ACK)
        bad = team_map_message(room(8), TEAM, "map")
        bad.data = bad.data[:-3]  # data length not width x height
        map_pub.publish(bad)
        spin(0.3)
        for resolution in (float("nan"), float("inf"), 0.0):
            bad = team_map_message(room(8), TEAM, "map")
            bad.info.resolution = resolution
            map_pub.publish(bad)
            spin(0.3)
        huge = team_map_message(room(8), TEAM, "map")
        huge.info.width = huge.info.height = 100_000
        map_pub.publish(huge)
        spin(0.3)
        bad = team_map_message(room(8), TEAM, "map")
        bad.info.origin.position.x = float("nan")
        map_pub.publish(bad)
        spin(0.3)
        lost = PoseWithCovarianceStamped()
        lost.header.frame_id = "map"
        lost.pose.pose.position.x = float("nan")
        lost.pose.pose.orientation.w = 1.0
        pose_pub.publish(lost)
        spin(0.3)
        drifting = PoseWithCovarianceStamped()  # odometry's frame: it drifts from the map's
        drifting.header.frame_id = "odom"
        drifting.pose.pose.position.x, drifting.pose.pose.orientation.w = 0.65, 1.0
        for _ in range(3):  # many times a second, one warning
            pose_pub.publish(drifting)
            spin(0.1)
        spin(0.3)
        fourth = centre.read(ask(3, room(6)))  # the bad map and pose dropped: the robot still holds room(6)
        kinds.append(("after_bad_map", fourth is not None and fourth.is_delta and centre.accepts(fourth)))
        centre.receive(fourth, 3)
        result["steps"] = kinds
        # what the same robot and centre objects give in one process from room(6)
        agent = RobotAgent(0, (8, 10), PreprocessConfig(), SensorConfig())
        agent.sense_state(room(6))
        reference = TeamCentre(1, (8, 10), PreprocessConfig().closing_size_cells, silence_rounds=3)
        reference.receive(decode(agent.compose(0, (3, 2), agent.window()).full_bytes()), 0)  # a whole map
        result["centre_equals_in_process"] = bool(np.array_equal(centre.state(), reference.state()))
        node.destroy_node()
        rclpy.shutdown()
    finally:
        robot.send_signal(signal.SIGTERM)  # as a launcher stops it (Ctrl-C takes the same way out)
        t_stop = time.monotonic()
        try:
            _, err = robot.communicate(timeout=30)
        except subprocess.TimeoutExpired:
            robot.kill()
            _, err = robot.communicate()
        # The robot node's own warnings (ROS may add its own, e.g. where ROS_LOCALHOST_ONLY is set)
        result["warnings"] = [line for line in err.splitlines() if "WARN" in line and "[mrexplore_" in line]
        result["robot_exit"] = robot.returncode
        result["stop_s"] = round(time.monotonic() - t_stop, 2)
    print(json.dumps(result))


if __name__ == "__main__":
    main()
