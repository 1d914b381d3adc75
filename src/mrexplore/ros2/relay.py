"""``mrexplore ros2 relay``: a lossy link between the robots and the centre, to try the protocol under loss
through the middleware. It forwards each robot's frontier messages from ``/mrexplore/NAME/frontiers`` to
``/mrexplore/relay/NAME/frontiers`` as the bytes arrived (no decoding), dropping each with probability
``loss``; the centre reads the relayed topics (``frontiers_topic`` in its deployment).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from mrexplore.ros2.deployment import Deployment

__all__ = ["LossyRelay", "run_relay", "relayed_topic"]


def relayed_topic(name: str) -> str:
    """Where the relay republishes robot ``name``'s frontier messages."""
    return f"/mrexplore/relay/{name}/frontiers"


class LossyRelay:
    """Forwards every robot's frontier messages, each lost with probability ``loss`` (drawn from ``seed``)."""

    def __init__(self, node: Any, deployment: Deployment, loss: float, seed: int = 0) -> None:
        from std_msgs.msg import UInt8MultiArray

        self.loss, self.rng = loss, np.random.default_rng(seed)
        self.forwarded = self.dropped = 0
        for robot in deployment.robots:
            out = node.create_publisher(UInt8MultiArray, relayed_topic(robot.name), 10)
            node.create_subscription(
                UInt8MultiArray,
                f"/mrexplore/{robot.name}/frontiers",
                lambda raw, out=out: self._forward(raw, out),
                10,
                raw=True,
            )

    def _forward(self, raw: bytes, out: Any) -> None:
        if self.rng.random() < self.loss:
            self.dropped += 1
            return
        self.forwarded += 1
        out.publish(raw)  # the serialized message as it came


def run_relay(
    deployment: Deployment, loss: float, seed: int, loopback: bool = True, ros_args: Sequence[str] = ()
) -> str:
    """Serve until a signal ends the relay; returns what it forwarded and dropped."""
    from mrexplore.ros2.robot_node import serve, start_rclpy

    rclpy = start_rclpy(loopback, ros_args)
    node = rclpy.create_node("mrexplore_relay")
    relay = serve(rclpy, node, lambda: LossyRelay(node, deployment, loss, seed), f"relay losing {loss:.0%} ready")
    return f"relay forwarded {relay.forwarded} and dropped {relay.dropped} frontier messages"
