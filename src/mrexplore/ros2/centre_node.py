"""``mrexplore ros2 centre``: the team's computing centre as a ROS 2 node, callbacks around the objects that
hold the rules: :class:`~mrexplore.mission.centre.TeamPlanner` (the team map, decisions, goal book),
:class:`~mrexplore.team.rounds.RoundCollector` (rounds) and each robot's goal channel
(:mod:`~mrexplore.ros2.goals`). Every time it keeps is the node's clock: sim time where ``use_sim_time`` is set.

In: each robot's ``/mrexplore/NAME/frontiers`` and Nav2's word on its goals. Out: ``/mrexplore/round``,
``/mrexplore/NAME/reply``, each robot's goals, ``/mrexplore/map``, ``/mrexplore/markers``,
``/mrexplore/status``; services ``/mrexplore/pause``, ``resume``, ``stop``, ``return_home`` (docs/ros2.md
lists every topic with its type).

A message that does not decode and a goal on a robot's topic that this centre did not send are each one
warning line and dropped; the node keeps what it had.
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mrexplore.config import PreprocessConfig
from mrexplore.maps.frame import GridFrame
from mrexplore.mission.centre import NavState, TeamPlanner
from mrexplore.pipeline import ExplorationPipeline
from mrexplore.preprocessing.sparse_codec import peek
from mrexplore.ros2.centre_lockstep import LockstepAnswers
from mrexplore.ros2.centre_services import add_services
from mrexplore.ros2.centre_views import WHY, Views, WireCounts, centre_record, centre_status, save_record, team_summary
from mrexplore.ros2.deployment import Deployment
from mrexplore.ros2.goals import goal_channel, goal_pose
from mrexplore.ros2.lockstep import DecisionRequest
from mrexplore.ros2.parameters import apply_parameters
from mrexplore.ros2.robot_node import ACK, WHOLE_MAP, RobotNode, RobotNodeSettings
from mrexplore.team.rounds import Admit, Reply, RoundCollector
from mrexplore.types import MrExploreError

__all__ = ["CentreSettings", "CentreNode", "run_centre_node", "WireCounts"]

Request = DecisionRequest | None
_ASK_AGAIN_S = 0.5
"""A robot that has not answered a round is asked again this often (it may still be starting)."""
_SAVE_EVERY_S = 2.0  # the record is written this often while the centre runs, and at its end
_NAV = {"active": NavState.ACTIVE, "reached": NavState.REACHED, "aborted": NavState.ABORTED}


@dataclass(frozen=True)
class CentreSettings:
    """What the centre node needs: the deployment, the strategy, the team grid, and how it runs."""

    deployment: Deployment
    strategy: ExplorationPipeline
    team: GridFrame
    lockstep: bool = False
    """Rounds come from ``mrexplore ros2 sim --lockstep`` (its decision requests), not from a timer."""
    record: Path | None = None
    """Where the node writes its record (wire bytes, decisions) when it ends."""
    seed: int = 0
    direct_maps: bool = False
    """Read each robot's map and pose here (a robot node per robot inside this process): for teams that cannot
    run code on their robots; their whole maps cross the network, so nothing is saved."""
    preprocess: PreprocessConfig = PreprocessConfig()
    """The robots' layer 1 where the centre runs it for them (``direct_maps``)."""


class CentreNode:
    """The centre's node (module docstring)."""

    def __init__(self, node: Any, settings: CentreSettings) -> None:
        from rclpy.qos import QoSProfile, ReliabilityPolicy
        from std_msgs.msg import String, UInt8MultiArray, UInt32MultiArray

        self.node, self.settings = node, settings
        dep = settings.deployment
        self.robots = dep.robots
        n = len(self.robots)
        team = settings.team
        self.planner = TeamPlanner(
            n,
            (team.height, team.width),
            team.resolution_m,
            settings.strategy,
            silence_rounds=max(1, math.ceil(dep.lost_after_s / dep.round_period_s)),
            blacklist_s=dep.blacklist_s,
            replan_s=dep.replan_s,
            min_replan_s=dep.min_replan_s,
            settle_s=dep.lost_after_s,
            seed=settings.seed,
        )
        self.rounds = RoundCollector(n, dep.round_timeout_s, _ASK_AGAIN_S, dep.lost_after_s)
        self.wire = [WireCounts() for _ in range(n)]
        self.decision_ms: list[float] = []
        """Per decision: the last message of its round in (or the round's timeout) -> every goal out, ms
        (wall clock: the centre's work, whatever the node's clock)."""
        self.warnings = self.goals_sent = 0
        self.finished: str | None = None
        self.paused = False
        # Rounds of a fresh centre start past any a robot may have answered before a restart.
        self.round = -1 if settings.lockstep else int(time.time() * 10) % 2**31
        self._stamp: tuple[int, int] = (0, 0)
        self._request: DecisionRequest | None = None
        self._next_round = 0.0
        self.force = True
        self._last_in = 0.0
        self._Bytes, self._Pair, self._String = UInt8MultiArray, UInt32MultiArray, String

        frontier_qos = QoSProfile(
            depth=10, reliability=ReliabilityPolicy.RELIABLE if dep.reliable else ReliabilityPolicy.BEST_EFFORT
        )
        self._replies, self.goals = [], []
        for i, robot in enumerate(self.robots):
            on_frontiers = lambda raw, i=i: self._on_frontiers(i, raw)  # noqa: E731
            node.create_subscription(UInt8MultiArray, robot.frontiers_topic, on_frontiers, frontier_qos, raw=True)
            self._replies.append(node.create_publisher(UInt32MultiArray, robot.reply_topic, 10))
            on_state = lambda state, i=i: self._on_nav(i, state)  # noqa: E731
            self.goals.append(goal_channel(node, robot, self.now, on_state, self.warn))
        self._round_pub = node.create_publisher(UInt32MultiArray, "/mrexplore/round", 10)
        self.views = Views(node, self.planner, team, dep.team_frame)
        self.lockstep = LockstepAnswers(node, self) if settings.lockstep else None
        add_services(node, self)
        node.create_timer(0.02, self._tick)
        self.direct = [
            RobotNode(
                node, RobotNodeSettings(r.name, r.index, team, r.offset, r.pose_type, settings.preprocess, entry=r)
            )
            for r in self.robots
            if settings.direct_maps
        ]
        """The robots' on-board work, done here where the robots run no node of ours (``direct_maps``)."""

    def now(self) -> float:
        """The node's clock, seconds (sim time where ``use_sim_time`` is set)."""
        return float(self.node.get_clock().now().nanoseconds) * 1e-9

    def warn(self, text: str) -> None:
        self.warnings += 1
        self.node.get_logger().warning(text)

    # -- rounds ----------------------------------------------------------------------------------------
    def open_round(self, round_: int, stamp: tuple[int, int], expected: set[int], request: Request) -> None:
        """Ask the ``expected`` robots for their maps of ``round_`` (no earlier than ``stamp``)."""
        self.round, self._stamp, self._request = round_, stamp, request
        self.rounds.open(round_, expected, self.now())
        self._last_in = 0.0
        self._ask()

    def _ask(self) -> None:
        self._round_pub.publish(self._Pair(data=[self.round, self._stamp[0], self._stamp[1]]))

    def _tick(self) -> None:
        if self.finished is not None:
            return
        now, lockstep = self.now(), self.settings.lockstep
        if self.rounds.current is not None:
            if self.rounds.complete(now, wait=lockstep):
                self._close()
            elif self.rounds.due_to_ask(now):
                self._ask()
            return
        if lockstep:
            return
        period = self.settings.deployment.round_period_s
        for i, (channel, heard) in enumerate(zip(self.goals, self.rounds.heard_at, strict=True)):
            if i not in self.rounds.lost:  # a lost robot's Nav2 answers nothing: its goal is not sent again
                channel.tick(answering=heard is not None and now - heard <= 2 * period)
        if now >= self._next_round:
            self._next_round = now + self.settings.deployment.round_period_s
            for i, silent in self.rounds.mark_lost(now):
                self.warn(
                    f"robot {self.robots[i].name} silent for {silent:.1f} s: lost, no longer waited for "
                    "(it rejoins when it speaks again)"
                )
            self.open_round(self.round + 1, (0, 0), set(range(len(self.robots))), None)

    def _on_frontiers(self, i: int, raw: bytes) -> None:
        from rclpy.serialization import deserialize_message

        name = self.robots[i].name
        try:
            data = bytes(deserialize_message(raw, self._Bytes).data)
            message = peek(data)
        except MrExploreError as exc:
            self.warn(f"frontier message from {name} dropped: {exc}")
            return
        except Exception as exc:  # noqa: BLE001 - a message the middleware itself cannot read
            self.warn(f"frontier message from {name} dropped: it does not deserialize ({type(exc).__name__})")
            return
        if message.robot != i:
            self.warn(f"frontier message on {name}'s topic dropped: it names robot {message.robot}, not {i}")
            return
        verdict, wire = self.rounds.admit(i, message.round, message.is_delta), self.wire[i]
        if verdict in (Admit.LATE, Admit.REPEAT):
            # A round already closed, a robot not asked (failed, in the simulator's lockstep), or an answer in.
            wire.late += verdict is Admit.LATE
            wire.repeats += verdict is Admit.REPEAT
            return
        wire.count(verdict is Admit.RESENT, len(data), len(raw))
        try:
            decoded = self.planner.read(data)
        except MrExploreError as exc:
            self.warn(f"frontier message from {name} dropped: {exc}")
            return
        rejoins = i in self.rounds.lost
        if self.rounds.take(i, decoded, self.now()) is Reply.WHOLE_MAP:  # a delta on a base this centre lacks
            self._replies[i].publish(self._Pair(data=[message.round, WHOLE_MAP]))
            return
        self._last_in = time.monotonic()
        if rejoins:
            self.node.get_logger().info(f"robot {name} speaks again: it rejoins the team")
        self._replies[i].publish(self._Pair(data=[message.round, ACK]))
        if self.rounds.complete(self.now(), wait=True):
            self._close()  # every robot answered: decide now, not at the next tick

    def _close(self) -> None:
        round_ = self.round
        for message in self.rounds.close().values():  # in robot order, as the simulator's link delivers them
            self.planner.receive(message, round_)
        t_in = self._last_in or time.monotonic()
        decisions = self.planner.decisions
        if self._request is not None and self.lockstep is not None:
            self.lockstep.decide(self._request)
        elif not self.paused:
            for i, goal in self.planner.plan(round_, self.now(), force=self.force).items():
                self.send_goal(i, goal)
            self.force = False
            if self.planner.done_reason is not None:
                self.finished = self.planner.done_reason
                summary = team_summary(self.planner, len(self.robots), len(self.rounds.lost))
                self.node.get_logger().info(f"exploration finished: {WHY[self.finished]} ({summary})")
        if self.planner.decisions > decisions:  # rounds that only moved robots along their routes apart
            self.decision_ms.append((time.monotonic() - t_in) * 1e3)  # the last message in -> every goal out
        self.publish_views()

    # -- goals and navigation --------------------------------------------------------------------------
    def goal_pose(self, i: int, goal_rc: NDArray[np.integer]) -> tuple[float, float, float]:
        """Robot i's goal cell as a pose of its own map frame (:func:`~mrexplore.ros2.goals.goal_pose`)."""
        return goal_pose(self.robots[i], self.settings.team, self.planner.team.positions_rc[i], goal_rc)

    def send_goal(self, i: int, goal_rc: NDArray[np.integer]) -> None:
        self.goals_sent += 1
        self.goals[i].send(*self.goal_pose(i, goal_rc))

    def _on_nav(self, i: int, state: str) -> None:
        nav = _NAV[state]
        self.planner.navigation(i, nav, self.now())
        if nav != NavState.ACTIVE:
            self._next_round = 0.0  # a robot is free: a round now, not at the next tick of the period

    # -- views ---------------------------------------------------------------------------------------
    def publish_views(self) -> None:
        self.views.publish(self.round, self.status)

    def status(self, heard: Any = None, assignable: Any = None) -> dict[str, Any]:
        """What the status topic says (:func:`~mrexplore.ros2.centre_views.centre_status`)."""
        return centre_status(self, heard, assignable)

    def record(self) -> dict[str, Any]:
        """The node's record (:func:`~mrexplore.ros2.centre_views.centre_record`)."""
        return centre_record(self)


def run_centre_node(settings: CentreSettings, loopback: bool = True, ros_args: Sequence[str] = ()) -> str:
    """Start the centre's node and serve until the exploration ends or a signal (SIGINT, SIGTERM) stops it;
    returns why it ended. ``loopback``: keep DDS on this machine."""
    from mrexplore.mission.centre import warm_up
    from mrexplore.ros2.robot_node import start_rclpy

    warm_up(settings.strategy)  # kernels compiled before the team sees the centre
    rclpy = start_rclpy(loopback, ros_args)
    node = rclpy.create_node("mrexplore_centre")
    why = "interrupted"
    centre: CentreNode | None = None
    try:
        dep, team = apply_parameters(node, settings.deployment, settings.team)  # -p, --params-file
        settings = replace(settings, deployment=dep, team=team)
        centre = CentreNode(node, settings)
        node.get_logger().info(f"centre ready: {len(settings.deployment.robots)} robots, {settings.strategy.name}")
        saved = time.monotonic()
        while centre.finished is None:
            rclpy.spin_once(node, timeout_sec=0.2)
            if settings.record is not None and time.monotonic() - saved > _SAVE_EVERY_S:
                save_record(settings.record, centre)  # a centre killed (a crash, a power cut) leaves its counts
                saved = time.monotonic()
        why = centre.finished
        t0 = time.monotonic()
        while time.monotonic() - t0 < 1.0:  # the last goals and views go out
            rclpy.spin_once(node, timeout_sec=0.1)
    except KeyboardInterrupt:
        pass
    finally:
        if centre is not None and settings.record is not None:
            save_record(settings.record, centre)
        node.destroy_node()
        rclpy.try_shutdown()
    return WHY.get(why, why)
