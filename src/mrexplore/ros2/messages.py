"""ROS 2 messages to the package's plain data and back: a robot's map and pose, the sparse frontier map as
bytes, the team map. The only module that knows the message types' fields."""

from __future__ import annotations

import array
from typing import TYPE_CHECKING

import numpy as np

from mrexplore.maps.frame import GridFrame
from mrexplore.maps.occupancy_grid import OccupancyGridData, occupancy_values, yaw_of
from mrexplore.types import StateGrid

if TYPE_CHECKING:  # the message packages come with the ros2 extra; imported where a message is built
    from geometry_msgs.msg import Pose
    from nav_msgs.msg import OccupancyGrid
    from std_msgs.msg import UInt8MultiArray

__all__ = ["grid_data", "pose_xyyaw", "bytes_message", "message_bytes", "team_map_message"]


def grid_data(msg: OccupancyGrid) -> OccupancyGridData:
    """The fields of a nav_msgs/OccupancyGrid that place and fill it (checked later, where it is read)."""
    info, o = msg.info, msg.info.origin
    yaw = yaw_of(o.orientation.x, o.orientation.y, o.orientation.z, o.orientation.w)
    data = np.frombuffer(msg.data, dtype=np.int8) if len(msg.data) else np.zeros(0, np.int8)
    origin = (float(o.position.x), float(o.position.y), yaw)
    return OccupancyGridData(int(info.width), int(info.height), float(info.resolution), origin, data)


def pose_xyyaw(pose: Pose) -> tuple[float, float, float]:
    """A geometry_msgs/Pose as x, y (metres) and yaw (radians)."""
    q = pose.orientation
    return float(pose.position.x), float(pose.position.y), yaw_of(q.x, q.y, q.z, q.w)


def bytes_message(data: bytes) -> UInt8MultiArray:
    """A std_msgs/UInt8MultiArray carrying ``data``."""
    from std_msgs.msg import UInt8MultiArray

    msg = UInt8MultiArray()
    msg.data = data
    return msg


def message_bytes(msg: UInt8MultiArray) -> bytes:
    """The bytes a std_msgs/UInt8MultiArray carries."""
    return bytes(msg.data)


def team_map_message(state: StateGrid, frame: GridFrame, frame_id: str) -> OccupancyGrid:
    """The team's grid as a nav_msgs/OccupancyGrid in ``frame_id`` (the team frame)."""
    from nav_msgs.msg import OccupancyGrid

    msg = OccupancyGrid()
    msg.header.frame_id = frame_id
    msg.info.width, msg.info.height = int(frame.width), int(frame.height)
    msg.info.resolution = float(frame.resolution_m)
    msg.info.origin.position.x, msg.info.origin.position.y = float(frame.origin_xy[0]), float(frame.origin_xy[1])
    msg.info.origin.orientation.w = 1.0
    msg.data = array.array("b", occupancy_values(state).tobytes())
    return msg
