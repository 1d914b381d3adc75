"""Run by tests/ros2/test_messages.py in a fresh interpreter (the loopback settings must come before rclpy):
a team map and a frontier message published on loopback, received and read back; prints one JSON line."""

from __future__ import annotations

import json
import time

import numpy as np


def main() -> None:
    """The whole session (the loopback settings first, then rclpy)."""
    from mrexplore.ros2.loopback import keep_on_loopback

    env = keep_on_loopback()

    import rclpy
    from nav_msgs.msg import OccupancyGrid
    from std_msgs.msg import UInt8MultiArray

    from mrexplore.config import GridThresholds, PreprocessConfig, SensorConfig
    from mrexplore.maps.frame import GridFrame
    from mrexplore.maps.occupancy_grid import FrameOffset, state_in_team_frame
    from mrexplore.preprocessing.agents import RobotAgent
    from mrexplore.preprocessing.sparse_codec import decode
    from mrexplore.ros2.messages import bytes_message, grid_data, message_bytes, team_map_message
    from mrexplore.types import CellState

    state = np.full((6, 9), CellState.UNKNOWN, np.uint8)
    state[1:5, 1:7] = CellState.FREE
    state[2, 4] = CellState.OCCUPIED
    frame = GridFrame(height=6, width=9, resolution_m=0.1, origin_xy=(-0.3, 0.2))
    robot = RobotAgent(0, state.shape, PreprocessConfig(closing_size_cells=1), SensorConfig())
    robot.sense_state(state)
    sent = robot.compose(0, (3, 2), robot.window()).full_bytes()

    rclpy.init()
    node = rclpy.create_node("mrexplore_roundtrip")
    maps: list[OccupancyGrid] = []
    blobs: list[bytes] = []
    node.create_subscription(OccupancyGrid, "/mrexplore/map", maps.append, 10)
    node.create_subscription(
        UInt8MultiArray, "/mrexplore/robot1/frontiers", lambda m: blobs.append(message_bytes(m)), 10
    )
    map_pub = node.create_publisher(OccupancyGrid, "/mrexplore/map", 10)
    msg_pub = node.create_publisher(UInt8MultiArray, "/mrexplore/robot1/frontiers", 10)
    t0 = time.monotonic()
    while not (maps and blobs) and time.monotonic() - t0 < 20:
        map_pub.publish(team_map_message(state, frame, "map"))
        msg_pub.publish(bytes_message(sent))
        rclpy.spin_once(node, timeout_sec=0.05)
    node.destroy_node()
    rclpy.shutdown()
    back = state_in_team_frame(grid_data(maps[0]), FrameOffset(), frame, GridThresholds()) if maps else None
    received = decode(blobs[0]) if blobs else None
    print(
        json.dumps(
            {
                "env": env,
                "map_equal": back is not None and bool(np.array_equal(back, state)),
                "bytes_equal": bool(blobs) and blobs[0] == sent,
                "cells": None if received is None else len(received.cells),
            }
        )
    )


if __name__ == "__main__":
    main()
