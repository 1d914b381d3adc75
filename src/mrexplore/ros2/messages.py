"""ROS 2 messages to the package's plain data and back: a robot's map and pose, the sparse frontier map as
bytes, the team map. The only module that knows the message types' fields."""

from __future__ import annotations

import array
import math
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from mrexplore.maps.frame import GridFrame
from mrexplore.maps.occupancy_grid import OccupancyGridData, occupancy_values, yaw_of
from mrexplore.runtime.colours import ROBOT_COLOURS as PICTURE_COLOURS
from mrexplore.types import StateGrid

if TYPE_CHECKING:  # the message packages come with the ros2 extra; imported where a message is built
    from geometry_msgs.msg import Pose, PoseStamped, PoseWithCovarianceStamped
    from nav_msgs.msg import OccupancyGrid, Odometry
    from std_msgs.msg import UInt8MultiArray
    from visualization_msgs.msg import MarkerArray

__all__ = [
    "grid_data",
    "pose_xyyaw",
    "bytes_message",
    "message_bytes",
    "team_map_message",
    "grid_message",
    "odometry_message",
    "goal_message",
    "pose_message",
    "markers_message",
    "ROBOT_COLOURS",
]

ROBOT_COLOURS = tuple(tuple(v / 255 for v in c) for c in PICTURE_COLOURS)
"""One colour per robot, 0-1 RGB, the package's pictures' (:mod:`~mrexplore.runtime.colours`)."""


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


def grid_message(grid: OccupancyGridData, frame_id: str, stamp: Any) -> OccupancyGrid:
    """A nav_msgs/OccupancyGrid of ``grid`` in ``frame_id`` (the inverse of :func:`grid_data`)."""
    from nav_msgs.msg import OccupancyGrid

    msg = OccupancyGrid()
    msg.header.frame_id, msg.header.stamp = frame_id, stamp
    msg.info.width, msg.info.height, msg.info.resolution = int(grid.width), int(grid.height), float(grid.resolution_m)
    x, y, yaw = grid.origin_xyyaw
    msg.info.origin.position.x, msg.info.origin.position.y = float(x), float(y)
    msg.info.origin.orientation.z, msg.info.origin.orientation.w = _quaternion(yaw)
    msg.data = array.array("b", np.asarray(grid.data, dtype=np.int8).tobytes())
    return msg


def odometry_message(x: float, y: float, frame_id: str, stamp: Any) -> Odometry:
    """A nav_msgs/Odometry at ``(x, y)`` in ``frame_id`` (``odom``), as a robot's base driver publishes it."""
    from nav_msgs.msg import Odometry

    msg = Odometry()
    msg.header.frame_id, msg.header.stamp, msg.child_frame_id = frame_id, stamp, "base_link"
    msg.pose.pose.position.x, msg.pose.pose.position.y = x, y
    msg.pose.pose.orientation.w = 1.0
    return msg


def _quaternion(yaw: float) -> tuple[float, float]:
    return math.sin(yaw / 2), math.cos(yaw / 2)


def goal_message(x: float, y: float, yaw: float, frame_id: str, stamp: Any) -> PoseStamped:
    """A geometry_msgs/PoseStamped goal at ``(x, y)`` facing ``yaw`` in ``frame_id``."""
    from geometry_msgs.msg import PoseStamped

    msg = PoseStamped()
    msg.header.frame_id, msg.header.stamp = frame_id, stamp
    msg.pose.position.x, msg.pose.position.y = x, y
    msg.pose.orientation.z, msg.pose.orientation.w = _quaternion(yaw)
    return msg


def pose_message(x: float, y: float, yaw: float, frame_id: str, stamp: Any) -> PoseWithCovarianceStamped:
    """A geometry_msgs/PoseWithCovarianceStamped at ``(x, y)`` facing ``yaw``, as AMCL publishes it."""
    from geometry_msgs.msg import PoseWithCovarianceStamped

    msg = PoseWithCovarianceStamped()
    msg.header.frame_id, msg.header.stamp = frame_id, stamp
    msg.pose.pose.position.x, msg.pose.pose.position.y = x, y
    msg.pose.pose.orientation.z, msg.pose.pose.orientation.w = _quaternion(yaw)
    return msg


def markers_message(
    frontier_mask: NDArray[np.bool_],
    centres_rc: NDArray[np.integer],
    robots_rc: NDArray[np.integer],
    routes: Sequence[NDArray[np.integer] | None],
    frame: GridFrame,
    frame_id: str,
) -> MarkerArray:
    """RViz markers in the team frame: a DELETEALL, the frontier cells (namespace ``frontiers``), one sphere
    per cluster centre (``clusters``), each robot's goal (``goals``, one arrow from the robot to it) and its
    route (``routes``), in the robot's colour."""
    from geometry_msgs.msg import Point
    from std_msgs.msg import ColorRGBA
    from visualization_msgs.msg import Marker, MarkerArray

    res = float(frame.resolution_m)

    def point(rc: Any) -> Point:
        x, y = frame.rc_to_xy((int(rc[0]), int(rc[1])))
        return Point(x=float(x), y=float(y), z=0.05)

    def marker(ns: str, mid: int, kind: int, colour: tuple[float, ...], size: float) -> Marker:
        m = Marker()
        m.header.frame_id, m.ns, m.id, m.type, m.action = frame_id, ns, mid, kind, Marker.ADD
        m.pose.orientation.w = 1.0
        m.scale.x = m.scale.y = m.scale.z = size
        m.color = ColorRGBA(r=colour[0], g=colour[1], b=colour[2], a=1.0)
        return m

    clear = Marker()
    clear.action = Marker.DELETEALL
    out = [clear]
    cells = marker("frontiers", 0, Marker.POINTS, (0.9, 0.1, 0.6), res)
    cells.points = [point(rc) for rc in np.argwhere(frontier_mask)]
    out.append(cells)
    for k, rc in enumerate(np.asarray(centres_rc).reshape(-1, 2)):
        sphere = marker("clusters", k, Marker.SPHERE, (0.9, 0.1, 0.6), 4 * res)
        sphere.pose.position = point(rc)
        out.append(sphere)
    for i, route in enumerate(routes):
        if route is None or len(route) == 0:
            continue
        colour = ROBOT_COLOURS[i % len(ROBOT_COLOURS)]
        arrow = marker("goals", i, Marker.ARROW, colour, 2 * res)
        arrow.scale.y = arrow.scale.z = 3 * res
        arrow.points = [point(robots_rc[i]), point(route[0])]
        out.append(arrow)
        line = marker("routes", i, Marker.LINE_STRIP, colour, res)
        line.points = [point(robots_rc[i])] + [point(rc) for rc in route]
        out.append(line)
    msg = MarkerArray()
    msg.markers = out
    return msg
