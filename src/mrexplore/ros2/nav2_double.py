"""The simulator standing in for each robot's Nav2 and SLAM as they behave, not as the centre assumes
(docs/ros2.md cites the upstream files):

- goals arrive on ``/NAME/goal_pose``; each is accepted under a new id and stamped with the double's own
  clock (rcl_action re-stamps an accepted goal with the server's clock), sim time where ``--clock-rate`` runs
  one;
- a new goal preempts the running one, which is aborted (nav2_util's ``SimpleActionServer``);
- the status array lists every goal the server still holds, terminal ones until ``result_timeout_s`` (10 s,
  rcl_action's default) after they ended, and is published on every transition, not periodically;
- the path is planned on the robot's own map and the team map, through unknown space where nothing better is
  known (``allow_unknown``); planned again when the way turns out blocked; aborted only without a way;
- each robot's SLAM map is published in the robot's own map frame (placed at ``offsets[i]`` in the team frame)
  at ``slam_resolution_m``, transient local, as slam_toolbox publishes ``map``; its pose in that frame on
  ``pose`` (slam_toolbox's PoseWithCovarianceStamped), and an odometry in ``odom`` that drifts from it.
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mrexplore.config import GridThresholds
from mrexplore.maps.frame import GridFrame
from mrexplore.maps.occupancy_grid import FrameOffset, grid_in_robot_frame, state_in_team_frame
from mrexplore.mission import Mission
from mrexplore.paths.astar import astar_path
from mrexplore.ros2.deployment import RobotEntry
from mrexplore.ros2.goals import nav2_actions_available
from mrexplore.ros2.messages import grid_data, grid_message, odometry_message, pose_message
from mrexplore.sim.belief import classify
from mrexplore.team.nav_goals import ABORTED, EXECUTING, SUCCEEDED
from mrexplore.types import CellState, MrExploreError

__all__ = ["DoubleSettings", "Nav2Double", "SimClock", "CROSSED_S"]

CROSSED_S = 0.5
"""A goal that arrives this soon after the robot's last goal was aborted (seconds of the double's clock) was
sent before the centre could have read the abort: the abort is of a goal the centre already replaced."""


@dataclass(frozen=True)
class DoubleSettings:
    """How far the double departs from the simulator's own frame and grid."""

    slam_resolution_m: float | None = None
    """Cell size of each robot's SLAM map (None: the simulator's grid)."""
    offsets: tuple[FrameOffset, ...] = ()
    """Each robot's map frame in the team frame (empty: all the team frame)."""
    drift_m_per_s: float = 0.0
    """How fast each robot's odometry drifts from its map pose, metres per second of the double's clock."""
    result_timeout_s: float = 10.0
    """A terminal goal leaves the status array this long after it ended (rcl_action's default)."""
    inscribed_radius_m: float = 0.0
    """A goal this close to an obstacle of the robot's own map is refused by the planner, and the goal aborted
    (Nav2's planners fail on a goal in lethal or inscribed cost; 0: only a goal on an obstacle)."""
    map_period_s: float = 0.0
    """Each robot's map is published this often (slam_toolbox's ``map_update_interval``; 0: every step)."""


@dataclass
class _Goal:
    uuid: bytes
    stamp: Any
    """builtin_interfaces/Time on the double's clock."""
    seconds: float
    status: int
    ended_s: float | None = None


class Nav2Double:
    """Each simulated robot's Nav2 and SLAM (module docstring). ``now`` gives the double's clock as a
    builtin_interfaces/Time."""

    def __init__(
        self,
        node: Any,
        mission: Mission,
        robots: tuple[RobotEntry, ...],
        settings: DoubleSettings,
        now: Callable[[], Any],
    ) -> None:
        from action_msgs.msg import GoalStatusArray
        from geometry_msgs.msg import PoseStamped, PoseWithCovarianceStamped
        from nav_msgs.msg import OccupancyGrid, Odometry
        from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy

        self.node, self.mission, self.robots, self.settings, self.now = node, mission, robots, settings, now
        self.frame: GridFrame = mission.truth.frame
        n = len(robots)
        self.offsets = settings.offsets or tuple(FrameOffset() for _ in range(n))
        latched = QoSProfile(
            depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL, reliability=ReliabilityPolicy.RELIABLE
        )
        self._maps = [node.create_publisher(OccupancyGrid, r.map_topic, latched) for r in robots]
        self._poses = [node.create_publisher(PoseWithCovarianceStamped, r.pose_topic, 10) for r in robots]
        self._odom = [node.create_publisher(Odometry, f"/{r.name}/odom", 10) for r in robots]
        self._GoalStatusArray = GoalStatusArray
        self.actions: Any = None
        """Where nav2_msgs imports: NavigateToPose action servers, which take the goal_pose goals too."""
        if nav2_actions_available():
            from mrexplore.ros2.nav2_action_double import ActionDouble

            self.actions = ActionDouble(node, self)
        else:
            self._status = [node.create_publisher(GoalStatusArray, r.nav_status_topic, 10) for r in robots]
        for i, r in enumerate(robots):
            node.create_subscription(PoseStamped, r.goal_topic, lambda m, i=i: self.on_goal(i, m), 10)
        node.create_subscription(OccupancyGrid, "/mrexplore/map", self._on_team_map, latched)
        self.goals: list[list[_Goal]] = [[] for _ in range(n)]
        self._target: list[tuple[int, int]] = [(-1, -1)] * n
        self._team_map: NDArray[np.uint8] | None = None
        self.aborts_caused = 0
        """Goals aborted because no way to them was known (what the centre should read as aborts)."""
        self.preempted = 0
        """Goals aborted because a newer one replaced them."""
        self.crossed = 0  # aborts a new goal crossed: it came within CROSSED_S, sent before the abort was read
        self._aborted_at: list[float | None] = [None] * n
        self.expired = 0  # terminal goals dropped from the status array after result_timeout_s

    @staticmethod
    def _seconds(stamp: Any) -> float:
        return int(stamp.sec) + int(stamp.nanosec) * 1e-9

    # -- goals ----------------------------------------------------------------------------------------
    def on_goal(self, i: int, msg: Any) -> None:
        """A goal on ``goal_pose``: accepted under a new id on the double's clock, preempting the running one."""
        sim = self.mission.sim
        if not sim.alive[i]:
            return  # a failed robot's Nav2 answers nothing
        if self.actions is not None:
            self.actions.forward(i, msg)  # bt_navigator sends it to its own action server
            return
        stamp = self.now()
        now_s = self._seconds(stamp)
        aborted = self._aborted_at[i]
        if aborted is not None and now_s - aborted < CROSSED_S:
            self.crossed += 1
        self._aborted_at[i] = None
        for goal in self.goals[i]:
            if goal.status == EXECUTING:
                goal.status, goal.ended_s = ABORTED, now_s  # preempted (SimpleActionServer::accept_pending_goal)
                self.preempted += 1
        reachable = self.begin(i, msg.pose)
        goal = _Goal(os.urandom(16), stamp, now_s, EXECUTING if reachable else ABORTED)
        if not reachable:
            goal.ended_s = self._aborted_at[i] = now_s
            self.aborts_caused += 1
        self.goals[i].append(goal)
        self._publish_status(i)

    def begin(self, i: int, pose: Any) -> bool:
        """Robot i sets off for ``pose`` (its map frame); False where its planner refuses it or finds no way."""
        x, y = self.offsets[i].to_team(float(pose.position.x), float(pose.position.y))
        self._target[i] = self.frame.xy_to_rc((float(x), float(y)))
        reachable = self.frame.contains(self._target[i]) and not self._lethal(i)
        path = self._plan(i) if reachable else np.zeros((0, 2), np.int32)
        self.mission.sim.set_path(i, path)
        return bool(len(path))

    def progress(self, i: int, blocked: bool) -> int | None:
        """After a step, robot i on its way: plans again where the way turned out blocked; ABORTED without a
        way, SUCCEEDED at the end of its path, else None."""
        sim = self.mission.sim
        if blocked or sim.path_ahead_blocked(i):
            path = self._plan(i)
            sim.set_path(i, path)
            if not len(path):
                self.aborts_caused += 1
                return ABORTED
        elif sim.at_path_end(i):
            return SUCCEEDED
        return None

    def has_goal(self, i: int) -> bool:
        return bool(self.goals[i]) or (self.actions is not None and self.actions.has_goal(i))

    def _own_map(self, i: int) -> NDArray[np.uint8]:
        belief = self.mission.sim.beliefs[i]
        return classify(belief.log_odds, belief.observed, self.mission.sim_cfg.sensor)

    def _lethal(self, i: int) -> bool:
        """Whether robot i's goal lies within ``inscribed_radius_m`` of an obstacle of its own map."""
        k = round(self.settings.inscribed_radius_m / self.frame.resolution_m)
        r, c = self._target[i]
        near = self._own_map(i)[max(0, r - k) : r + k + 1, max(0, c - k) : c + k + 1]
        return bool((near == CellState.OCCUPIED).any())

    def _plan(self, i: int) -> NDArray[np.int32]:
        """Robot i's path to its goal as Nav2 would find it on the robot's own map: through the cells it
        holds free, else through unknown space too (``allow_unknown``); empty where neither leads there."""
        sim = self.mission.sim
        own = self._own_map(i)
        here = (int(sim.positions_rc[i, 0]), int(sim.positions_rc[i, 1]))
        free, occupied = own == CellState.FREE, own == CellState.OCCUPIED
        if self._team_map is not None:  # the team map, as a Nav2 costmap's static layer may take it
            free |= self._team_map == CellState.FREE
            occupied |= self._team_map == CellState.OCCUPIED
        for passable in (free, ~occupied):
            passable[here] = True
            path = astar_path(passable, here, self._target[i])
            if len(path):
                return path
        return np.zeros((0, 2), np.int32)

    def _on_team_map(self, msg: Any) -> None:
        try:  # read as any robot's map is: checked, thresholded, placed in the simulator's grid
            self._team_map = state_in_team_frame(grid_data(msg), FrameOffset(), self.frame, GridThresholds())
        except MrExploreError as exc:
            self.node.get_logger().warning(f"team map dropped: {exc}")

    def after_step(self, blocked: NDArray[np.bool_]) -> None:
        """After a simulation step: plan again around what was just seen, abort without a way, succeed at the
        end of the path; the status goes out on each change and as terminal goals expire."""
        if self.actions is not None:
            self.actions.after_step(blocked)
            return
        sim, now_s = self.mission.sim, self._seconds(self.now())
        for i in map(int, np.flatnonzero(sim.alive)):
            goal = self.goals[i][-1] if self.goals[i] else None
            changed = False
            if goal is not None and goal.status == EXECUTING:
                outcome = self.progress(i, bool(blocked[i]))
                if outcome is not None:
                    goal.status, goal.ended_s, changed = outcome, now_s, True
                    if outcome == ABORTED:
                        self._aborted_at[i] = now_s
            timeout = self.settings.result_timeout_s
            kept = [g for g in self.goals[i] if g.ended_s is None or now_s - g.ended_s < timeout]
            if changed or len(kept) < len(self.goals[i]):
                self.expired += len(self.goals[i]) - len(kept)
                self.goals[i] = kept
                self._publish_status(i)

    def _publish_status(self, i: int) -> None:
        from action_msgs.msg import GoalStatus

        listed = []
        for goal in self.goals[i]:
            status = GoalStatus()
            status.goal_info.goal_id.uuid = list(goal.uuid)
            status.goal_info.stamp = goal.stamp
            status.status = goal.status
            listed.append(status)
        self._status[i].publish(self._GoalStatusArray(status_list=listed))

    # -- SLAM -----------------------------------------------------------------------------------------
    def publish_world(self, stamp: Any, maps: bool = True) -> None:
        """Each live robot's pose and odometry, and its map where ``maps``, stamped ``stamp``."""
        sim, sensor = self.mission.sim, self.mission.sim_cfg.sensor
        resolution = self.settings.slam_resolution_m or self.frame.resolution_m
        drift = self.settings.drift_m_per_s * self._seconds(stamp)
        for i in map(int, np.flatnonzero(sim.alive)):
            robot, offset = self.robots[i], self.offsets[i]
            if maps:
                belief = sim.beliefs[i]
                grid = grid_in_robot_frame(
                    classify(belief.log_odds, belief.observed, sensor), self.frame, offset, resolution
                )
                self._maps[i].publish(grid_message(grid, robot.frame, stamp))
            x, y = offset.to_robot(*self.frame.rc_to_xy((int(sim.positions_rc[i, 0]), int(sim.positions_rc[i, 1]))))
            self._poses[i].publish(pose_message(float(x), float(y), 0.0, robot.frame, stamp))
            self._odom[i].publish(odometry_message(float(x) + drift, float(y) - drift, "odom", stamp))


class SimClock:
    """The simulation's clock: the node's own (wall) clock, or sim time published on ``/clock`` running
    ``rate`` times the wall clock from 1 s, as a simulator publishes it for nodes on ``use_sim_time``."""

    def __init__(self, node: Any, rate: float | None) -> None:
        self.node, self.rate, self._t0 = node, rate, time.monotonic()
        if rate is not None:
            from rosgraph_msgs.msg import Clock

            self._Clock = Clock
            self._pub = node.create_publisher(Clock, "/clock", 10)

    def seconds(self) -> float:
        if self.rate is None:
            return float(self.node.get_clock().now().nanoseconds) * 1e-9
        return 1.0 + (time.monotonic() - self._t0) * self.rate

    def now_msg(self) -> Any:
        """The clock now as a builtin_interfaces/Time."""
        if self.rate is None:
            return self.node.get_clock().now().to_msg()
        from builtin_interfaces.msg import Time

        t = self.seconds()
        return Time(sec=int(t), nanosec=int((t - int(t)) * 1e9))

    def publish(self) -> None:
        """Publish sim time (nothing on the wall clock)."""
        if self.rate is not None:
            self._pub.publish(self._Clock(clock=self.now_msg()))
