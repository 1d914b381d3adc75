"""How the centre's goals reach a robot's Nav2 and how Nav2's word on them comes back: callbacks around
:class:`~mrexplore.team.nav_goals.GoalTracker`, which holds the rules.

- ``action`` (where ``nav2_msgs`` imports, as on every Nav2 install): a NavigateToPose action client on the
  robot's ``navigate_to_pose`` action; the goal handle's acceptance and result say active, reached or
  aborted; pause and stop cancel the goal. The result of a goal the centre replaced is not read (Nav2 aborts
  a preempted goal; that is no abort of the new one).
- ``topic``: a PoseStamped on the robot's ``goal_pose`` (bt_navigator forwards it to its own action server)
  and the action's status topic read by the tracker; pause and stop send the robot's own cell as its goal.
"""

from __future__ import annotations

import importlib.util
import math
from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mrexplore.maps.frame import GridFrame
from mrexplore.ros2.deployment import RobotEntry
from mrexplore.ros2.messages import goal_message
from mrexplore.team.nav_goals import GoalTracker

__all__ = ["TopicGoals", "ActionGoals", "goal_channel", "goal_pose", "nav2_actions_available", "RESEND_AFTER_S"]

RESEND_AFTER_S = 1.0
"""A goal on ``goal_pose`` that Nav2 lists under no new id this long after it was sent goes out again (a
message published before the robot's subscription matched is lost), seconds of the node's clock."""
SETTLE_S = 3.0
"""An abort counts this long after the last send even where an earlier copy never showed up."""

OnState = Callable[[str], None]
Warn = Callable[[str], None]


def goal_pose(
    robot: RobotEntry, team: GridFrame, here_rc: NDArray[np.integer], goal_rc: NDArray[np.integer]
) -> tuple[float, float, float]:
    """A goal cell of the team grid as a pose ``(x, y, yaw)`` of the robot's own map frame, heading away from
    the robot's cell ``here_rc``."""
    gx, gy = team.rc_to_xy((int(goal_rc[0]), int(goal_rc[1])))
    hx, hy = team.rc_to_xy((int(here_rc[0]), int(here_rc[1])))
    x, y = robot.offset.to_robot(gx, gy)
    return float(x), float(y), math.atan2(gy - hy, gx - hx) - robot.offset.yaw_rad


def watch_goal_topic(node: Any, robot: RobotEntry, ours: set[tuple[int, int]], warn: Warn) -> None:
    """One warning for each goal another node publishes on the robot's goal topic (its stamp is none of
    ``ours``): two nodes steering one robot undo each other's goals."""
    from geometry_msgs.msg import PoseStamped

    def on_goal(msg: Any) -> None:
        if (int(msg.header.stamp.sec), int(msg.header.stamp.nanosec)) not in ours:
            warn(
                f"goal on {robot.goal_topic} not sent by this centre (another node publishes there); "
                "the centre keeps its own goal"
            )

    node.create_subscription(PoseStamped, robot.goal_topic, on_goal, 10)


def nav2_actions_available() -> bool:
    """Whether nav2_msgs (NavigateToPose) can be imported here."""
    return importlib.util.find_spec("nav2_msgs") is not None


class TopicGoals:
    """Goals on ``goal_pose``, tracked through the action's status topic (module docstring)."""

    kind = "topic"

    def __init__(self, node: Any, robot: RobotEntry, now: Callable[[], float], on_state: OnState, warn: Warn) -> None:
        from action_msgs.msg import GoalStatusArray
        from geometry_msgs.msg import PoseStamped

        self.node, self.robot, self.now, self.on_state, self.warn = node, robot, now, on_state, warn
        self.tracker = GoalTracker(RESEND_AFTER_S, SETTLE_S)
        self._warned = 0
        self.resent = 0
        self._last: Any = None
        self._held = False
        self.stamps: set[tuple[int, int]] = set()
        """The stamps of every goal this centre published (a goal on the topic with another is not ours)."""
        self._pub = node.create_publisher(PoseStamped, robot.goal_topic, 10)
        node.create_subscription(GoalStatusArray, robot.nav_status_topic, self._on_status, 10)
        watch_goal_topic(node, robot, self.stamps, warn)

    def send(self, x: float, y: float, yaw: float) -> None:
        """A new goal, in the robot's map frame."""
        self.tracker.sent(self.now())
        self._publish(x, y, yaw)

    def _publish(self, x: float, y: float, yaw: float) -> None:
        self._last = (x, y, yaw)
        # The count includes the centre's own watcher of the topic (watch_goal_topic): one is nobody else.
        if self._pub.get_subscription_count() <= 1:
            self._held = True  # Nav2 does not listen yet (a centre just started): sent once it does
            return
        self._held = False
        stamp = self.node.get_clock().now().to_msg()
        self.stamps.add((int(stamp.sec), int(stamp.nanosec)))
        self._pub.publish(goal_message(x, y, yaw, self.robot.frame, stamp))

    def hold(self, x: float, y: float, yaw: float) -> None:
        """Stop where it stands: its own pose as its goal."""
        self.send(x, y, yaw)

    def tick(self, answering: bool = True) -> None:
        """Send the goal again where Nav2 has not listed it yet and the robot still ``answering`` the centre's
        rounds (a robot that does not answer would not take it either); read an abort held back until now."""
        now = self.now()
        if self._held and self._last is not None:
            self.tracker.last_send = now
            self._publish(*self._last)
        elif self._last is not None and answering and self.tracker.due_to_resend(now):
            self.tracker.resent(now)
            self.resent += 1
            self._publish(*self._last)
        state = self.tracker.poll(now)
        if state is not None:
            self.on_state(state)

    def _on_status(self, msg: Any) -> None:
        listed = [
            (
                bytes(s.goal_info.goal_id.uuid),
                int(s.goal_info.stamp.sec) + int(s.goal_info.stamp.nanosec) * 1e-9,
                int(s.status),
            )
            for s in msg.status_list
        ]
        state = self.tracker.status(listed, self.now())
        for gid in self.tracker.foreign[self._warned :]:
            self.warn(f"navigation status of {self.robot.name} for unknown goal {gid.hex()[:8]} dropped")
        self._warned = len(self.tracker.foreign)
        if state is not None:
            self.on_state(state)


class ActionGoals:
    """Goals through Nav2's NavigateToPose action (module docstring)."""

    kind = "action"

    def __init__(self, node: Any, robot: RobotEntry, now: Callable[[], float], on_state: OnState, warn: Warn) -> None:
        from nav2_msgs.action import NavigateToPose
        from rclpy.action import ActionClient

        self.node, self.robot, self.on_state = node, robot, on_state
        self._Goal = NavigateToPose.Goal
        name = robot.nav_status_topic.removesuffix("/_action/status")
        self._client = ActionClient(node, NavigateToPose, name)
        self._handle: Any = None
        self._generation = 0
        self.resent = 0
        self.stamps: set[tuple[int, int]] = set()
        watch_goal_topic(node, robot, self.stamps, warn)

    def send(self, x: float, y: float, yaw: float) -> None:
        """A new goal, in the robot's map frame; the one it replaces is no longer read."""
        stamp = self.node.get_clock().now().to_msg()
        self.stamps.add((int(stamp.sec), int(stamp.nanosec)))
        goal = self._Goal()
        goal.pose = goal_message(x, y, yaw, self.robot.frame, stamp)
        self._generation += 1
        generation = self._generation
        future = self._client.send_goal_async(goal)
        future.add_done_callback(lambda f: self._on_response(generation, f))

    def _on_response(self, generation: int, future: Any) -> None:
        if generation != self._generation:
            return  # a goal already replaced
        handle = future.result()
        if not handle.accepted:
            self.node.get_logger().info(f"{self.robot.name}: Nav2 rejected the goal")
            self.on_state("aborted")
            return
        self._handle = handle
        self.on_state("active")
        handle.get_result_async().add_done_callback(lambda f: self._on_result(generation, f))

    def _on_result(self, generation: int, future: Any) -> None:
        from action_msgs.msg import GoalStatus

        if generation != self._generation:
            return  # Nav2 aborted a goal the centre replaced: no abort of the new one
        status = future.result().status
        if status != GoalStatus.STATUS_SUCCEEDED:
            self.node.get_logger().info(f"{self.robot.name}: Nav2 ended the goal with status {status}")
        self.on_state("reached" if status == GoalStatus.STATUS_SUCCEEDED else "aborted")

    def hold(self, x: float, y: float, yaw: float) -> None:
        """Stop: the running goal is cancelled."""
        self._generation += 1
        if self._handle is not None:
            self._handle.cancel_goal_async()
            self._handle = None

    def tick(self, answering: bool = True) -> None:
        """Nothing to send again: the action's goal request is acknowledged."""


def goal_channel(
    node: Any, robot: RobotEntry, now: Callable[[], float], on_state: OnState, warn: Warn
) -> TopicGoals | ActionGoals:
    """The robot's goal channel: its ``goal_via``, ``auto`` taking the action where nav2_msgs imports;
    ``on_state`` hears ``active``, ``reached`` or ``aborted`` of the current goal, ``warn`` what is dropped."""
    use_action = robot.goal_via == "action" or (robot.goal_via == "auto" and nav2_actions_available())
    return (ActionGoals if use_action else TopicGoals)(node, robot, now, on_state, warn)
