"""``mrexplore ros2 robot``: one robot's on-board work as a ROS 2 node, a thin adapter around
:class:`~mrexplore.preprocessing.agents.RobotAgent`.

Topics (``NAME`` is the robot's name):

- in: ``/NAME/map`` (nav_msgs/OccupancyGrid, transient local, as slam_toolbox and map_server publish it);
  ``/NAME/pose`` (geometry_msgs/PoseWithCovarianceStamped, as AMCL and slam_toolbox publish it, or
  nav_msgs/Odometry); ``/mrexplore/round``
  (``[round, sec, nanosec]``, as std_msgs/UInt32MultiArray: the centre asks for round r's maps, taken no
  earlier than that stamp; ``0, 0``: whatever the robot holds); ``/mrexplore/NAME/reply``
  (std_msgs/UInt32MultiArray ``[round, kind]``, kind :data:`ACK` or
  :data:`WHOLE_MAP`).
- out: ``/mrexplore/NAME/frontiers`` (std_msgs/UInt8MultiArray): the robot's sparse frontier map, a delta
  against what the centre acknowledged or the whole map, in the team's grid.

The protocol is the simulator's: the robot answers each round with its incremental message; the centre
acknowledges it (later deltas apply to it) or, lacking the delta's base, asks for the whole map, which the
robot sends at once. A malformed map or message is one warning line in the node's log and is dropped; the
node keeps what it had.
"""

from __future__ import annotations

import importlib.util
import math
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any

from mrexplore.config import GridThresholds, PreprocessConfig, SensorConfig
from mrexplore.maps.frame import GridFrame
from mrexplore.maps.occupancy_grid import FrameOffset, state_in_team_frame, yaw_of
from mrexplore.preprocessing.agents import RobotAgent
from mrexplore.preprocessing.sparse_map import SparseFrontierMap
from mrexplore.preprocessing.transmission import Outgoing
from mrexplore.ros2.deployment import POSE_TYPES, Deployment, RobotEntry
from mrexplore.ros2.messages import bytes_message, grid_data, pose_xyyaw
from mrexplore.types import MrExploreError

__all__ = ["RobotNodeSettings", "RobotNode", "run_robot_node", "start_rclpy", "serve", "ACK", "WHOLE_MAP"]

ACK = 0
"""Reply kind: the centre holds the robot's message of that round."""
WHOLE_MAP = 1
"""Reply kind: the centre lacks the delta's base; send the whole map."""


@dataclass(frozen=True)
class RobotNodeSettings:
    """What one robot node needs: its name and index in the team, the team's grid, its frame's offset."""

    name: str
    index: int
    """The robot's index in the team (its id in messages)."""
    team: GridFrame
    """The team's grid: cell size, size and origin in the team frame."""
    offset: FrameOffset = FrameOffset()
    pose_type: str = "pose_with_covariance"
    preprocess: PreprocessConfig = PreprocessConfig()
    thresholds: GridThresholds = GridThresholds()
    entry: RobotEntry | None = None
    """The robot's entry in a deployment file (its topics); None: the default topics of ``name``."""
    deployment: Deployment | None = None
    """The team's deployment, whose settings the node declares as ROS parameters (None: none declared)."""

    @property
    def topics(self) -> RobotEntry:
        return self.entry if self.entry is not None else RobotEntry(self.name, self.index)

    def __post_init__(self) -> None:
        if self.pose_type not in POSE_TYPES:
            raise MrExploreError(f"pose type must be one of {', '.join(POSE_TYPES)}, got {self.pose_type!r}")
        if self.pose_type == "tf" and importlib.util.find_spec("tf2_ros") is None:
            raise MrExploreError(
                "pose type tf needs tf2_ros, which comes with a sourced ROS 2 installation (not on PyPI); "
                "source it, or use pose_with_covariance or odometry"
            )


class RobotNode:
    """The robot's node: keeps its :class:`RobotAgent` fed with its map and pose, answers the centre's rounds."""

    def __init__(self, node: Any, settings: RobotNodeSettings) -> None:
        from geometry_msgs.msg import PoseWithCovarianceStamped
        from nav_msgs.msg import OccupancyGrid, Odometry
        from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
        from std_msgs.msg import UInt8MultiArray, UInt32MultiArray

        self.node, self.settings = node, settings
        team = settings.team
        self.agent = RobotAgent(settings.index, (team.height, team.width), settings.preprocess, SensorConfig())
        self.position_rc: tuple[int, int] | None = None
        self.has_map = False
        self._sent: tuple[int, Outgoing, SparseFrontierMap] | None = None
        """The round answered last, its messages and the one sent (what an acknowledgement confirms)."""
        self._sent_bytes = b""
        self._map_stamp = self._pose_stamp = (-1, -1)
        self._asked: tuple[int, tuple[int, int]] | None = None
        """The round asked for and not answered yet, and the stamp its map and pose must have."""
        topics = settings.topics
        latched = QoSProfile(
            depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL, reliability=ReliabilityPolicy.RELIABLE
        )
        node.create_subscription(OccupancyGrid, topics.map_topic, self._on_map, latched)
        self._tf: Any = None
        self._frames_warned: set[str] = set()
        if settings.pose_type == "tf":  # the robot's pose looked up when a round is answered
            self._tf = _tf_buffer(node, topics)
        else:
            pose_msg = PoseWithCovarianceStamped if settings.pose_type == "pose_with_covariance" else Odometry
            node.create_subscription(pose_msg, topics.pose_topic, self._on_pose, 10)
        node.create_subscription(UInt32MultiArray, "/mrexplore/round", self._on_round, 10)
        node.create_subscription(UInt32MultiArray, topics.reply_topic, self._on_reply, 10)
        self._out = node.create_publisher(UInt8MultiArray, f"/mrexplore/{topics.name}/frontiers", 10)

    def _warn(self, text: str) -> None:
        self.node.get_logger().warning(text)

    def _on_map(self, msg: Any) -> None:
        s = self.settings
        try:
            state = state_in_team_frame(grid_data(msg), s.offset, s.team, s.thresholds)
        except MrExploreError as exc:
            self._warn(f"map dropped: {exc}")
            return
        self.agent.sense_state(state)
        self.has_map = True
        self._map_stamp = (int(msg.header.stamp.sec), int(msg.header.stamp.nanosec))
        self._answer()

    def _on_pose(self, msg: Any) -> None:
        frame, expected = str(msg.header.frame_id), self.settings.topics.frame
        if frame.lstrip("/") != expected.lstrip("/"):
            if frame not in self._frames_warned:  # once per frame: poses come many times a second
                self._frames_warned.add(frame)
                self._warn(
                    f"pose dropped: {self.settings.topics.pose_topic} is in frame {frame!r}, the map in {expected!r}; "
                    "give a pose in the map frame (AMCL's amcl_pose, slam_toolbox's pose) or pose_type tf"
                )
            return
        x, y, yaw = pose_xyyaw(msg.pose.pose)
        if self._place(x, y, yaw):
            self._pose_stamp = (int(msg.header.stamp.sec), int(msg.header.stamp.nanosec))
            self._answer()

    def _look_up_pose(self) -> None:
        """The robot's pose from tf2: its base frame in its map frame, now."""
        import rclpy.time

        topics = self.settings.topics
        try:
            t = self._tf.lookup_transform(topics.frame, topics.base_frame, rclpy.time.Time())
        except Exception as exc:  # noqa: BLE001 - tf2's lookup errors share no base class importable here
            self._warn(f"pose not known: tf2 has no {topics.frame} -> {topics.base_frame} ({type(exc).__name__})")
            return
        q = t.transform.rotation
        if self._place(float(t.transform.translation.x), float(t.transform.translation.y), yaw_of(q.x, q.y, q.z, q.w)):
            self._pose_stamp = (int(t.header.stamp.sec), int(t.header.stamp.nanosec))

    def _place(self, x: float, y: float, yaw: float) -> bool:
        """Put the robot at a pose of its map frame in the team's grid; False (one warning) where it cannot be."""
        if not (math.isfinite(x) and math.isfinite(y) and math.isfinite(yaw)):
            self._warn(f"pose dropped: position ({x}, {y}) and heading {yaw} must be finite")
            return False
        xy = self.settings.offset.to_team(x, y)
        rc = self.settings.team.xy_to_rc(xy)
        if not self.settings.team.contains(rc):
            self._warn(f"pose dropped: ({xy[0]:.2f}, {xy[1]:.2f}) m lies outside the team's grid")
            return False
        self.position_rc = rc
        return True

    def _on_round(self, msg: Any) -> None:
        values = [int(v) for v in msg.data]
        if len(values) != 3:
            self._warn(f"round dropped: {values} is not [round, sec, nanosec]")
            return
        self._asked = (values[0], (values[1], values[2]))
        self._answer()

    def _answer(self) -> None:
        """Answer the round asked for once the robot holds a map and a pose of its stamp or later."""
        if self._tf is not None and self._asked is not None:
            self._look_up_pose()
        if self._asked is None or self.position_rc is None or not self.has_map:
            return  # nothing to send before the robot's first map and pose
        round_, stamp = self._asked
        if self._map_stamp < stamp or self._pose_stamp < stamp:
            return  # the world of that round is still on its way
        self._asked = None
        if self._sent is not None and self._sent[0] == round_:
            self._out.publish(bytes_message(self._sent_bytes))  # asked again: the same answer
            return
        out = self.agent.compose(round_, self.position_rc, self.agent.window())
        data = out.incremental()
        self._sent, self._sent_bytes = (round_, out, out.incremental_message()), data
        self._out.publish(bytes_message(data))

    def _on_reply(self, msg: Any) -> None:
        values = list(msg.data)
        if len(values) != 2 or self._sent is None or values[0] != self._sent[0]:
            self._warn(f"reply dropped: {values} answers no message this robot sent")
            return
        round_, out, message = self._sent
        if values[1] == ACK:
            self.agent.acknowledged(message)
        elif values[1] == WHOLE_MAP:
            data = out.full_bytes()
            self._sent, self._sent_bytes = (round_, out, out.full), data
            self._out.publish(bytes_message(data))
        else:
            self._warn(f"reply dropped: kind {values[1]} is neither {ACK} (ack) nor {WHOLE_MAP} (whole map)")


def _tf_buffer(node: Any, topics: RobotEntry) -> Any:
    """A tf2 buffer fed from the robot's own TF topics (nav2_bringup remaps each robot's ``/tf`` and
    ``/tf_static`` to ``/NAME/tf`` and ``/NAME/tf_static``): subscribed here, as tf2_ros's listener takes
    its topic names only in newer releases."""
    import tf2_ros
    from rclpy.qos import DurabilityPolicy, QoSProfile
    from tf2_msgs.msg import TFMessage

    buffer = tf2_ros.Buffer()
    static_qos = QoSProfile(depth=100, durability=DurabilityPolicy.TRANSIENT_LOCAL)

    def feed(msg: Any, static: bool) -> None:
        for t in msg.transforms:
            if static:
                buffer.set_transform_static(t, "mrexplore")
            else:
                buffer.set_transform(t, "mrexplore")

    node.create_subscription(TFMessage, topics.tf_topic, lambda m: feed(m, False), 100)
    node.create_subscription(TFMessage, topics.tf_static_topic, lambda m: feed(m, True), static_qos)
    return buffer


def start_rclpy(loopback: bool = True, ros_args: Sequence[str] = ()) -> Any:
    """rclpy, initialised for a node that takes SIGINT and SIGTERM itself (both raise KeyboardInterrupt in
    its bounded spins). ``loopback``: keep DDS on this machine first
    (:func:`~mrexplore.ros2.loopback.keep_on_loopback`, with the domain already set where it is).
    ``ros_args``: the command line's ``--ros-args ...`` (remaps, ``-p NAME:=VALUE`` such as
    ``use_sim_time:=true``, ``--params-file``, ``--log-level``), which rcl applies to the node as to any
    ROS 2 node."""
    import signal

    if loopback:
        from mrexplore.ros2.loopback import keep_on_loopback

        keep_on_loopback()  # the exported ROS_DOMAIN_ID where there is one (a launch exports its own)
    import rclpy
    from rclpy.signals import SignalHandlerOptions

    def stop(signum: int, frame: object) -> None:
        raise KeyboardInterrupt  # SIGTERM ends the node as Ctrl-C does

    # The node takes SIGINT and SIGTERM itself: under rclpy's own handlers a SIGTERM left the process
    # hanging in about half the runs of the middleware test under load.
    rclpy.init(args=["mrexplore", *ros_args], signal_handler_options=SignalHandlerOptions.NO)
    signal.signal(signal.SIGTERM, stop)
    signal.signal(signal.SIGINT, stop)
    return rclpy


def run_robot_node(settings: RobotNodeSettings, loopback: bool = True, ros_args: Sequence[str] = ()) -> None:
    """Start the robot's node and serve until interrupted (SIGINT or SIGTERM). ``loopback``: keep DDS on this
    machine; ``ros_args``: see :func:`start_rclpy`."""
    RobotAgent.warm_up(settings.preprocess)  # kernels compiled before the team sees the robot
    rclpy = start_rclpy(loopback, ros_args)
    node = rclpy.create_node(f"mrexplore_{settings.name}")

    def build() -> RobotNode:
        if settings.deployment is None:
            return RobotNode(node, settings)
        from mrexplore.ros2.parameters import apply_parameters

        dep, team = apply_parameters(node, settings.deployment, settings.team)  # -p, --params-file
        return RobotNode(node, replace(settings, team=team, deployment=dep))

    serve(rclpy, node, build, f"robot {settings.name} ready")


def serve(rclpy: Any, node: Any, build: Any, ready: str) -> Any:
    """Build a node's adapter with ``build()``, say ``ready`` and spin until a signal ends it (SIGINT or
    SIGTERM, raised within a bounded wait); the node and rclpy are shut down however it ends. Returns what
    ``build`` made (None where building failed)."""
    made = None
    try:
        made = build()
        node.get_logger().info(ready)
        while True:
            rclpy.spin_once(node, timeout_sec=0.2)
    except KeyboardInterrupt:
        pass
    finally:
        node.destroy_node()
        rclpy.try_shutdown()
    return made
