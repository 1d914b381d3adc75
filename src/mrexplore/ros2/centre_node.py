"""``mrexplore ros2 centre``: the team's computing centre as a ROS 2 node, a thin adapter around
:class:`~mrexplore.mission.centre.TeamPlanner`.

Topics (``NAME`` is each robot's name; every topic can be renamed in the deployment file):

- in: ``/mrexplore/NAME/frontiers`` (std_msgs/UInt8MultiArray: the robot's sparse frontier map);
  ``/NAME/navigate_to_pose/_action/status`` (action_msgs/GoalStatusArray, as Nav2's bt_navigator publishes it).
- out: ``/mrexplore/round`` (std_msgs/UInt32MultiArray ``[round, sec, nanosec]``: send your maps);
  ``/mrexplore/NAME/reply`` (``[round, kind]``: acknowledged, or send the whole map);
  ``/NAME/goal_pose`` (geometry_msgs/PoseStamped in the robot's own map frame, the topic bt_navigator follows);
  ``/mrexplore/map`` (nav_msgs/OccupancyGrid, transient local: the team map in the team frame);
  ``/mrexplore/markers`` (visualization_msgs/MarkerArray: frontier cells, one sphere per cluster centre, each
  robot's goal and route in its own colour); ``/mrexplore/status`` (std_msgs/String, JSON).
- services (std_srvs/Trigger): ``/mrexplore/pause``, ``/mrexplore/resume``, ``/mrexplore/stop``,
  ``/mrexplore/return_home``.

Nav2 takes a goal on ``goal_pose`` under an id of its own; the centre takes as its goal's the first new id
its robot's status lists after the goal was sent. A status of any other id, a frontier message that does not
decode and a goal on a robot's topic that this centre did not send are each one warning line and are
dropped; the node keeps what it had.
"""

from __future__ import annotations

import json
import math
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mrexplore.config import PreprocessConfig
from mrexplore.maps.frame import GridFrame
from mrexplore.mission.centre import NavState, TeamPlanner
from mrexplore.pipeline import ExplorationPipeline
from mrexplore.preprocessing.sparse_codec import peek
from mrexplore.preprocessing.sparse_map import SparseFrontierMap
from mrexplore.ros2.deployment import Deployment
from mrexplore.ros2.lockstep import DecisionReply, DecisionRequest
from mrexplore.ros2.messages import goal_message, markers_message, team_map_message
from mrexplore.ros2.robot_node import ACK, WHOLE_MAP, RobotNode, RobotNodeSettings
from mrexplore.types import CellState, MrExploreError

__all__ = ["CentreSettings", "CentreNode", "run_centre_node", "WireCounts"]

_NAV_STATES = {2: NavState.ACTIVE, 4: NavState.REACHED, 5: NavState.ABORTED, 6: NavState.ABORTED}
"""action_msgs/GoalStatus: executing, succeeded, canceled, aborted."""
_ASK_AGAIN_S = 0.5
_SEND_AGAIN_S = 1.0
"""A goal Nav2 has not taken (no new id in its status) is sent again this often: a message published before
the robot's subscription was matched is lost, and a robot without its goal would wait for ever."""
"""A robot that has not answered a round is asked again this often (it may still be starting)."""


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


@dataclass
class WireCounts:
    """The frontier messages as the centre received them, each robot's first answer of a round apart from
    the whole maps it asked for again."""

    messages: int = 0
    payload_bytes: int = 0
    """The sparse messages' own bytes (what the simulator counts)."""
    serialized_bytes: int = 0
    """The same messages as the middleware carried them (CDR: the payload plus a fixed header)."""
    resent_messages: int = 0
    resent_payload_bytes: int = 0
    resent_serialized_bytes: int = 0
    repeats: int = 0
    """Answers of a round already in (a robot asked again before its answer arrived)."""
    late: int = 0
    """Answers of a round already closed."""


@dataclass
class _Round:
    round: int
    stamp: tuple[int, int]
    expected: set[int]
    deadline: float
    request: DecisionRequest | None = None
    inbox: dict[int, SparseFrontierMap] = field(default_factory=dict)
    asked_whole: set[int] = field(default_factory=set)
    next_ask: float = 0.0
    last_in: float = 0.0


class CentreNode:
    """The centre's node (module docstring)."""

    def __init__(self, node: Any, settings: CentreSettings) -> None:
        from action_msgs.msg import GoalStatusArray
        from geometry_msgs.msg import PoseStamped
        from nav_msgs.msg import OccupancyGrid
        from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
        from std_msgs.msg import String, UInt8MultiArray, UInt32MultiArray
        from std_srvs.srv import Trigger
        from visualization_msgs.msg import MarkerArray

        self.node, self.settings = node, settings
        dep = settings.deployment
        self.robots = dep.robots
        n = len(self.robots)
        silence = max(1, math.ceil(dep.lost_after_s / dep.round_period_s))
        team = settings.team
        self.planner = TeamPlanner(
            n,
            (team.height, team.width),
            team.resolution_m,
            settings.strategy,
            silence_rounds=silence,
            blacklist_s=dep.blacklist_s,
            replan_s=dep.replan_s,
            min_replan_s=dep.min_replan_s,
            settle_s=dep.lost_after_s,
            seed=settings.seed,
        )
        self.wire = [WireCounts() for _ in range(n)]
        self.decision_ms: list[float] = []
        """Per decision: the last message of its round in (or the round's timeout) -> every goal out, ms."""
        self.warnings = 0
        self.finished: str | None = None
        self.paused = False
        # Rounds of a fresh centre start past any a robot may have answered before a restart.
        self.round = -1 if settings.lockstep else int(time.time() * 10) % 2**31
        self._round: _Round | None = None
        self._last_reply: str | None = None
        """The last lockstep decision's JSON, sent again where the simulator asks for that round again."""
        self._next_round = 0.0
        self._force = True
        self._goal_stamps: list[set[tuple[int, int]]] = [set() for _ in range(n)]
        self._goal_sent_ns = [0] * n
        self._goal_out: list[NDArray[np.int32] | None] = [None] * n
        """Each robot's goal as last sent (team grid)."""
        self._untaken_since: list[float | None] = [None] * n
        """When each robot's goal was last sent while Nav2 has not taken it (None: taken, or none)."""
        self.goals_resent = 0
        self._heard_at: list[float | None] = [None] * n  # each robot's last message taken (None: never)
        self.lost: set[int] = set()  # silent for lost_after_s: not waited for (:meth:`_mark_lost`)
        self._goal_id: list[bytes | None] = [None] * n
        self._known_ids: list[set[bytes]] = [set() for _ in range(n)]
        self._warned_ids: set[bytes] = set()
        self._UInt8MultiArray = UInt8MultiArray
        self._UInt32MultiArray = UInt32MultiArray
        self._String = String

        latched = QoSProfile(
            depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL, reliability=ReliabilityPolicy.RELIABLE
        )
        frontier_qos = QoSProfile(
            depth=10, reliability=ReliabilityPolicy.RELIABLE if dep.reliable else ReliabilityPolicy.BEST_EFFORT
        )
        self._replies, self._goals = [], []
        for i, robot in enumerate(self.robots):
            node.create_subscription(
                UInt8MultiArray,
                robot.frontiers_topic,
                lambda raw, i=i: self._on_frontiers(i, raw),
                frontier_qos,
                raw=True,
            )
            node.create_subscription(GoalStatusArray, robot.nav_status_topic, lambda m, i=i: self._on_nav(i, m), 10)
            node.create_subscription(PoseStamped, robot.goal_topic, lambda m, i=i: self._on_goal_topic(i, m), 10)
            self._replies.append(node.create_publisher(UInt32MultiArray, robot.reply_topic, 10))
            self._goals.append(node.create_publisher(PoseStamped, robot.goal_topic, 10))
        self._round_pub = node.create_publisher(UInt32MultiArray, "/mrexplore/round", 10)
        self._map_pub = node.create_publisher(OccupancyGrid, "/mrexplore/map", latched)
        self._markers_pub = node.create_publisher(MarkerArray, "/mrexplore/markers", latched)
        self._status_pub = node.create_publisher(String, "/mrexplore/status", 10)
        self._decision_pub = node.create_publisher(String, "/mrexplore/lockstep/decision", 10)
        if settings.lockstep:
            node.create_subscription(String, "/mrexplore/lockstep/request", self._on_request, 10)
        for name, action in (
            ("pause", self._pause),
            ("resume", self._resume),
            ("stop", self._stop),
            ("return_home", self._return_home),
        ):
            node.create_service(Trigger, f"/mrexplore/{name}", lambda req, res, a=action: self._service(a, res))
        node.create_timer(0.02, self._tick)
        self.direct = [
            RobotNode(
                node, RobotNodeSettings(r.name, r.index, team, r.offset, r.pose_type, settings.preprocess, entry=r)
            )
            for r in self.robots
            if settings.direct_maps
        ]
        """The robots' on-board work, done here where the robots run no node of ours (``direct_maps``)."""

    # -- log -------------------------------------------------------------------------------------------
    def _warn(self, text: str) -> None:
        self.warnings += 1
        self.node.get_logger().warning(text)

    # -- rounds ----------------------------------------------------------------------------------------
    def _open(self, round_: int, stamp: tuple[int, int], expected: set[int], request: DecisionRequest | None) -> None:
        now = time.monotonic()
        self.round = round_
        self._round = _Round(round_, stamp, expected, now + self.settings.deployment.round_timeout_s, request)
        self._ask()

    def _ask(self) -> None:
        r = self._round
        assert r is not None
        self._round_pub.publish(self._UInt32MultiArray(data=[r.round, r.stamp[0], r.stamp[1]]))
        r.next_ask = time.monotonic() + _ASK_AGAIN_S

    def _tick(self) -> None:
        if self.finished is not None:
            return
        now = time.monotonic()
        r = self._round
        if r is not None:
            complete = r.expected - self.lost <= set(r.inbox)
            if complete or (not self.settings.lockstep and now >= r.deadline):
                self._close()
            elif now >= r.next_ask:
                self._ask()
            return
        if self.settings.lockstep:
            return
        for i, since in enumerate(self._untaken_since):
            goal = self._goal_out[i]
            if since is not None and goal is not None and now - since >= _SEND_AGAIN_S:
                self.goals_resent += 1
                self._send_goal(i, goal, again=True)
        if now >= self._next_round:
            self._next_round = now + self.settings.deployment.round_period_s
            self._mark_lost(now)
            self._open(self.round + 1, (0, 0), set(range(len(self.robots))), None)

    def _mark_lost(self, now: float) -> None:
        """Robots silent for ``lost_after_s`` are lost: one warning each, and rounds no longer wait for them
        (they are still asked, and rejoin when they answer)."""
        after = self.settings.deployment.lost_after_s
        for i, at in enumerate(self._heard_at):
            if at is not None and i not in self.lost and now - at > after:
                self.lost.add(i)
                self._warn(
                    f"robot {self.robots[i].name} silent for {now - at:.1f} s: lost, no longer waited for "
                    "(it rejoins when it speaks again)"
                )

    def _on_request(self, msg: Any) -> None:
        try:
            request = DecisionRequest.from_json(msg.data)
        except MrExploreError as exc:
            self._warn(f"decision request dropped: {exc}")
            return
        if request.round <= self.round and self._round is None:
            if request.round == self.round and self._last_reply is not None:
                self._decision_pub.publish(self._String(data=self._last_reply))  # asked again: the same answer
            return
        if self._round is not None:
            return  # that round is being collected
        self._open(request.round, request.stamp, set(request.sending), request)

    def _on_frontiers(self, i: int, raw: bytes) -> None:
        from rclpy.serialization import deserialize_message

        name = self.robots[i].name
        try:
            data = bytes(deserialize_message(raw, self._UInt8MultiArray).data)
            message = peek(data)
        except MrExploreError as exc:
            self._warn(f"frontier message from {name} dropped: {exc}")
            return
        except Exception as exc:  # noqa: BLE001 - a message the middleware itself cannot read
            self._warn(f"frontier message from {name} dropped: it does not deserialize ({type(exc).__name__})")
            return
        if message.robot != i:
            self._warn(f"frontier message on {name}'s topic dropped: it names robot {message.robot}, not {i}")
            return
        r, wire = self._round, self.wire[i]
        if r is None or message.round != r.round or i not in r.expected:
            wire.late += 1  # a round already closed, or a robot not asked (failed, in the simulator's lockstep)
            return
        if i in r.inbox:
            wire.repeats += 1
            return
        if i in r.asked_whole and message.is_delta:
            wire.repeats += 1  # a repeat of the refused delta, sent before the request arrived
            return
        if i in r.asked_whole:
            wire.resent_messages += 1
            wire.resent_payload_bytes += len(data)
            wire.resent_serialized_bytes += len(raw)
        else:
            wire.messages += 1
            wire.payload_bytes += len(data)
            wire.serialized_bytes += len(raw)
        try:
            decoded = self.planner.read(data)
        except MrExploreError as exc:
            self._warn(f"frontier message from {name} dropped: {exc}")
            return
        if decoded is None:  # a delta on a base this centre lacks
            r.asked_whole.add(i)
            self._replies[i].publish(self._UInt32MultiArray(data=[r.round, WHOLE_MAP]))
            return
        r.inbox[i] = decoded
        r.last_in = time.monotonic()
        self._heard_at[i] = r.last_in
        if i in self.lost:
            self.lost.discard(i)
            self.node.get_logger().info(f"robot {name} speaks again: it rejoins the team")
        self._replies[i].publish(self._UInt32MultiArray(data=[r.round, ACK]))
        if r.expected - self.lost <= set(r.inbox):
            self._close()  # the round is complete: decide now, not at the next tick

    def _close(self) -> None:
        r = self._round
        assert r is not None
        self._round = None
        for i in sorted(r.inbox):  # in robot order, as the simulator's link delivers them
            self.planner.receive(r.inbox[i], r.round)
        t_in = r.last_in or time.monotonic()
        decisions = self.planner.decisions
        if r.request is not None:
            t_out = self._decide_lockstep(r.request)
        elif not self.paused:
            now = time.monotonic()
            for i, goal in self.planner.plan(r.round, now, force=self._force).items():
                self._send_goal(i, goal)
            t_out = time.monotonic()
            self._force = False
            if self.planner.done_reason is not None:
                self.finished = self.planner.done_reason
                self.node.get_logger().info(f"exploration finished: {_WHY[self.finished]} ({self._summary()})")
        else:
            t_out = time.monotonic()
        if self.planner.decisions > decisions:  # rounds that only moved robots along their routes apart
            self.decision_ms.append((t_out - t_in) * 1e3)  # the last message in -> every goal out
        self._publish_views()

    def _decide_lockstep(self, request: DecisionRequest) -> float:
        """Decide on the simulator's request; returns when every goal was out (``time.monotonic()``); the
        decision's record for the simulator follows."""
        t0 = time.perf_counter()
        planner = self.planner
        active = np.asarray(request.active, dtype=np.int64)
        mine = planner.assignable(request.round)
        if not np.array_equal(mine, active):
            self._warn(
                f"round {request.round}: the simulator assigns {request.active}, the centre heard {mine.tolist()}"
            )
        blacklist = np.zeros(planner.team.map.shape, dtype=bool)
        blacklist.flat[request.blacklist] = True
        rng = np.random.default_rng()
        rng.bit_generator.state = request.rng
        decision = planner.strategy.decide(
            planner.decision_input(request.round, blacklist, request.current, rng, active)
        )
        planner.decision = decision
        planner.decisions += 1
        for j, i in enumerate(map(int, active)):
            goal = decision.goals_rc[j]
            planner.goals[i], planner.routes[i] = goal, decision.routes[j][1:]
            if goal[0] >= 0:
                self._send_goal(i, goal)
        t_out = time.monotonic()
        reply = DecisionReply.of(
            request.round, request.active, decision, rng.bit_generator.state, (time.perf_counter() - t0) * 1e3
        )
        self._last_reply = reply.to_json()
        self._decision_pub.publish(self._String(data=self._last_reply))
        if decision.done_reason is not None:
            planner.done_reason = decision.done_reason
            self.node.get_logger().info(f"exploration finished: {_WHY[decision.done_reason]}")
        return t_out

    def _summary(self) -> str:
        """The team map in a few numbers, for the line that says why the exploration ended."""
        state = self.planner.team.state()
        un = self.planner.team.frontiers().un_mask & ~self.planner.blacklist()
        heard = int((self.planner.team.last_heard >= 0).sum())
        free, unknown = int((state == CellState.FREE).sum()), int((state == CellState.UNKNOWN).sum())
        return (
            f"team map: {free:,} free cells, {unknown:,} unknown, {int(un.sum()):,} frontier cells; "
            f"{heard} of {len(self.robots)} robots heard, {len(self.lost)} lost"
        )

    # -- goals and navigation --------------------------------------------------------------------------
    def _send_goal(self, i: int, goal_rc: NDArray[np.integer], again: bool = False) -> None:
        """Publish robot i's goal; ``again``: the same goal once more, as Nav2 has not taken it yet (a message
        published before the subscriber was matched is lost)."""
        robot, team = self.robots[i], self.settings.team
        here = self.planner.team.positions_rc[i]
        gx, gy = team.rc_to_xy((int(goal_rc[0]), int(goal_rc[1])))
        hx, hy = team.rc_to_xy((int(here[0]), int(here[1])))
        x, y = robot.offset.to_robot(gx, gy)
        yaw = math.atan2(gy - hy, gx - hx) - robot.offset.yaw_rad
        stamp = self.node.get_clock().now().to_msg()
        self._goal_stamps[i].add((int(stamp.sec), int(stamp.nanosec)))
        if not again:
            self._goal_sent_ns[i] = int(stamp.sec) * 10**9 + int(stamp.nanosec)
            self._goal_id[i] = None
            self._goal_out[i] = np.asarray(goal_rc, dtype=np.int32).copy()
        self._untaken_since[i] = time.monotonic()
        self._goals[i].publish(goal_message(float(x), float(y), yaw, robot.frame, stamp))

    def _on_goal_topic(self, i: int, msg: Any) -> None:
        stamp = (int(msg.header.stamp.sec), int(msg.header.stamp.nanosec))
        if stamp not in self._goal_stamps[i]:
            self._warn(
                f"goal on {self.robots[i].goal_topic} not sent by this centre (another node publishes there); "
                "the centre keeps its own goal"
            )

    def _on_nav(self, i: int, msg: Any) -> None:
        for status in msg.status_list:
            gid = bytes(status.goal_info.goal_id.uuid)
            stamp_ns = int(status.goal_info.stamp.sec) * 10**9 + int(status.goal_info.stamp.nanosec)
            if self._goal_id[i] is None and gid not in self._known_ids[i] and stamp_ns >= self._goal_sent_ns[i] > 0:
                self._goal_id[i] = gid  # the first new goal Nav2 took after ours was sent
                self._untaken_since[i] = None
                self._known_ids[i].add(gid)
            if gid == self._goal_id[i]:
                state = _NAV_STATES.get(int(status.status))
                if state is not None:
                    self.planner.navigation(i, state, time.monotonic())
                    if state != NavState.ACTIVE:
                        self._next_round = 0.0  # a robot is free: a round now, not at the next tick of the period
            elif gid not in self._known_ids[i] and gid not in self._warned_ids:
                self._warned_ids.add(gid)
                self._warn(f"navigation status of {self.robots[i].name} for unknown goal {gid.hex()[:8]} dropped")

    # -- services --------------------------------------------------------------------------------------
    def _service(self, action: Any, response: Any) -> Any:
        response.success, response.message = action()
        return response

    def _pause(self) -> tuple[bool, str]:
        self.paused = True
        for i, here in enumerate(self.planner.team.positions_rc):
            if here[0] >= 0:
                self._send_goal(i, here)  # hold where it stands
        return True, "paused: robots hold their positions; maps keep arriving"

    def _resume(self) -> tuple[bool, str]:
        self.paused, self._force = False, True
        return True, "resumed"

    def _stop(self) -> tuple[bool, str]:
        self._pause()
        self.finished = "stopped"
        self._publish_views()  # the status says so at once: a simulator or launcher waiting on it ends
        return True, "stopped: robots hold their positions"

    def _return_home(self) -> tuple[bool, str]:
        self.paused = True
        for i, start in enumerate(self.planner.starts):
            if start[0] >= 0:
                self._send_goal(i, start)
        return True, "returning: each robot drives to where its first message came from"

    # -- views -----------------------------------------------------------------------------------------
    def _publish_views(self) -> None:
        planner, team = self.planner, self.settings.team
        frame = self.settings.deployment.team_frame
        state = planner.team.state()
        self._map_pub.publish(team_map_message(state, team, frame))
        decision = planner.decision
        centres = decision.clusters.centers_rc if decision is not None else np.zeros((0, 2), np.int32)
        routes = [
            np.vstack([planner.goals[i : i + 1], planner.routes[i]]) if planner.goals[i, 0] >= 0 else None
            for i in range(len(self.robots))
        ]
        self._markers_pub.publish(
            markers_message(planner.team.frontiers().un_mask, centres, planner.team.positions_rc, routes, team, frame)
        )
        status = planner.team.status(self.round)
        self._status_pub.publish(self._String(data=json.dumps(self.status(status.heard, status.assignable))))

    def status(
        self, heard: NDArray[np.bool_] | None = None, assignable: NDArray[np.bool_] | None = None
    ) -> dict[str, Any]:
        """What the status topic says: the round, whom the centre hears, the goals, why it ended."""
        planner = self.planner
        return {
            "round": self.round,
            "robots": [r.name for r in self.robots],
            "heard": [] if heard is None else [bool(h) for h in heard],
            "assignable": [] if assignable is None else [bool(a) for a in assignable],
            "goals_rc": planner.goals.tolist(),
            "clusters": 0 if planner.decision is None else len(planner.decision.clusters),
            "decisions": planner.decisions,
            "aborts": planner.aborts,
            "goals_resent": self.goals_resent,
            "paused": self.paused,
            "lost": [self.robots[i].name for i in sorted(self.lost)],
            "finished": self.finished or planner.done_reason,
        }

    def record(self) -> dict[str, Any]:
        """The node's record: its status, each robot's wire counts, the decisions' latency."""
        return {
            **self.status(),
            "warnings": self.warnings,
            "wire": {r.name: w.__dict__ for r, w in zip(self.robots, self.wire, strict=True)},
            "decision_ms": self.decision_ms,
        }


_WHY = {
    "no_frontiers": "no frontier cluster of the minimum size is left",
    "no_reachable_frontiers": "no robot can reach any frontier cluster",
    "stopped": "stopped by /mrexplore/stop",
}


def run_centre_node(settings: CentreSettings, loopback: bool = True, ros_args: Sequence[str] = ()) -> str:
    """Start the centre's node and serve until the exploration ends or a signal (SIGINT, SIGTERM) stops it;
    returns why it ended. ``loopback``: keep DDS on this machine."""
    from mrexplore.ros2.robot_node import start_rclpy

    rclpy = start_rclpy(loopback, ros_args)
    node = rclpy.create_node("mrexplore_centre")
    why = "interrupted"
    centre: CentreNode | None = None
    try:
        centre = CentreNode(node, settings)
        node.get_logger().info(f"centre ready: {len(settings.deployment.robots)} robots, {settings.strategy.name}")
        while centre.finished is None:
            rclpy.spin_once(node, timeout_sec=0.2)
        why = centre.finished
        t0 = time.monotonic()
        while time.monotonic() - t0 < 1.0:  # the last goals and views go out
            rclpy.spin_once(node, timeout_sec=0.1)
    except KeyboardInterrupt:
        pass
    finally:
        if centre is not None and settings.record is not None:
            settings.record.write_text(json.dumps(centre.record()))
        node.destroy_node()
        rclpy.try_shutdown()
    return _WHY.get(why, why)
