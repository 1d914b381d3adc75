"""``mrexplore ros2 sim``: the package's simulator as a team of ROS 2 robots, for trying the nodes without a
robot.

Each simulated robot publishes its belief as its map (``/NAME/map``, nav_msgs/OccupancyGrid, transient local)
and its pose (``/NAME/pose``, geometry_msgs/PoseWithCovarianceStamped), in the team frame.

- In real time (the default) it stands in for Nav2 too: it follows the goals on ``/NAME/goal_pose`` along
  the shortest path through the cells its own map or the team map (``/mrexplore/map``, as a Nav2 costmap's
  static layer may take it) holds free, else through unknown space too, advancing ``speed`` simulation steps a
  second, and publishes the action status Nav2 would on ``/NAME/navigate_to_pose/_action/status``
  (executing, then succeeded; aborted when no path is known or the way turns out blocked). It ends when the
  centre's status says the exploration finished, or at ``max_steps``.
- With ``lockstep`` it runs the package's own mission loop (:class:`~mrexplore.mission.Mission`, the same as
  ``mrexplore explore``) and takes every decision from the centre through the middleware: at each decision it
  publishes the robots' maps and poses, asks the centre (``/mrexplore/lockstep/request``) and waits for its
  answer (``/mrexplore/lockstep/decision``), taken on the maps the robot nodes sent it. The simulation
  advances only once the answer is in, so the mission equals ``mrexplore explore``'s step for step.
"""

from __future__ import annotations

import json
import os
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mrexplore.config import GridThresholds
from mrexplore.maps.occupancy_grid import FrameOffset, state_in_team_frame
from mrexplore.mission import Mission, MissionResult, MissionSpec
from mrexplore.paths.astar import astar_path
from mrexplore.pipeline import Decision, DecisionInput
from mrexplore.preprocessing.frontiers import detect_frontiers
from mrexplore.ros2.deployment import Deployment
from mrexplore.ros2.lockstep import DecisionReply, DecisionRequest, state_digest
from mrexplore.ros2.messages import grid_data, pose_message, team_map_message
from mrexplore.sim.belief import classify
from mrexplore.sim.world import ExplorationSim
from mrexplore.types import CellState, MrExploreError

__all__ = ["SimSettings", "SimNode", "run_sim_node"]

_REQUEST_AGAIN_S = 2.0
_LOG_EVERY_S = 5.0
_FIRST_GOALS_S = 300.0
"""Real time: the simulation starts once every robot has a goal; it gives up after this long (a first run on
a machine compiles the kernels in every process: a minute or more on two cores)."""
_STATUS = {"executing": 2, "succeeded": 4, "aborted": 6}


@dataclass(frozen=True)
class SimSettings:
    """What the simulated team needs: the mission (map, strategy, settings, seed), the robots' names, and how
    it runs."""

    spec: MissionSpec
    deployment: Deployment
    lockstep: bool = False
    speed: float = 10.0
    """Simulation steps a second in real time."""
    reply_timeout_s: float = 300.0
    """Lockstep: how long the simulator waits for the centre's answer before it gives up."""
    progress_file: Path | None = None
    """Where the simulation's step and coverage are kept up to date (JSON), for a launcher's faults."""


class SimNode:
    """The simulated team's node (module docstring)."""

    def __init__(self, node: Any, settings: SimSettings) -> None:
        from action_msgs.msg import GoalStatusArray
        from geometry_msgs.msg import PoseStamped, PoseWithCovarianceStamped
        from nav_msgs.msg import OccupancyGrid
        from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
        from std_msgs.msg import String

        self.node, self.settings = node, settings
        spec = settings.spec
        self.frame = spec.truth.frame
        self.robots = settings.deployment.robots
        if len(self.robots) != spec.sim_cfg.robots:
            raise MrExploreError(
                f"the deployment names {len(self.robots)} robots, the mission has {spec.sim_cfg.robots}; "
                "give one name per robot"
            )
        latched = QoSProfile(
            depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL, reliability=ReliabilityPolicy.RELIABLE
        )
        self._maps = [node.create_publisher(OccupancyGrid, r.map_topic, latched) for r in self.robots]
        self._poses = [node.create_publisher(PoseWithCovarianceStamped, r.pose_topic, 10) for r in self.robots]
        self._String, self._GoalStatusArray = String, GoalStatusArray
        self._stamp = 0
        self._progress_at = self._logged_at = 0.0
        self.map_mismatches = 0
        """Lockstep decisions whose map at the centre differed from the simulator's own copy of it."""
        self.centre_ms: list[float] = []
        self._reply: DecisionReply | None = None
        self.centre_status: dict[str, Any] | None = None
        if settings.lockstep:
            self._request_pub = node.create_publisher(String, "/mrexplore/lockstep/request", 10)
            node.create_subscription(String, "/mrexplore/lockstep/decision", self._on_reply, 10)
            self.mission = Mission(spec, lambda sim, *_: self.progress(sim), progress=False, centre=self._remote)
            return

        def on_status(msg: Any) -> None:
            self.centre_status = json.loads(msg.data)

        node.create_subscription(String, "/mrexplore/status", on_status, 10)
        self.mission = Mission(spec, progress=False)  # its simulator and starts; the loop is the robots' own
        n = len(self.robots)
        self._status_pubs = [node.create_publisher(GoalStatusArray, r.nav_status_topic, 10) for r in self.robots]
        for i, r in enumerate(self.robots):
            node.create_subscription(PoseStamped, r.goal_topic, lambda m, i=i: self._on_goal(i, m), 10)
        self._goal_ids: list[bytes | None] = [None] * n
        self._goal_stamps: list[Any] = [None] * n
        self._nav: list[str | None] = [None] * n
        self._goal_rc: list[tuple[int, int]] = [(-1, -1)] * n
        self._team_map: NDArray[np.uint8] | None = None
        node.create_subscription(OccupancyGrid, "/mrexplore/map", self._on_team_map, latched)
        self.curve = [self.mission.sim.coverage]

    def progress(self, sim: ExplorationSim | None = None, force: bool = False) -> None:
        """Keep the progress file and the log's progress line up to date (a few times a second at most)."""
        now = time.monotonic()
        if not force and now - self._progress_at < 0.05:
            return
        sim = sim or self.mission.sim
        path = self.settings.progress_file
        if path is not None:
            tmp = path.with_suffix(".tmp")
            tmp.write_text(json.dumps({"step": int(sim.steps), "coverage": float(sim.coverage)}))
            tmp.replace(path)
        if now - self._logged_at >= _LOG_EVERY_S:
            self._logged_at = now
            self.node.get_logger().info(f"step {sim.steps}, coverage {sim.coverage:.1%}")
        self._progress_at = now

    # -- the world as the robots publish it -------------------------------------------------------------
    def publish_world(self) -> tuple[int, int]:
        """Each live robot's map and pose, under a new stamp (returned as ``(sec, nanosec)``)."""
        self._stamp += 1
        stamp = self.node.get_clock().now().to_msg()
        stamp.sec, stamp.nanosec = self._stamp, 0
        sim, sensor = self.mission.sim, self.settings.spec.sim_cfg.sensor
        team_frame = self.settings.deployment.team_frame
        for i in map(int, np.flatnonzero(sim.alive)):
            belief = sim.beliefs[i]
            grid = team_map_message(classify(belief.log_odds, belief.observed, sensor), self.frame, team_frame)
            grid.header.stamp = stamp
            self._maps[i].publish(grid)
            x, y = self.frame.rc_to_xy((int(sim.positions_rc[i, 0]), int(sim.positions_rc[i, 1])))
            self._poses[i].publish(pose_message(x, y, 0.0, team_frame, stamp))
        return (self._stamp, 0)

    # -- lockstep ----------------------------------------------------------------------------------------
    def _on_reply(self, msg: Any) -> None:
        try:
            self._reply = DecisionReply.from_json(msg.data)
        except MrExploreError as exc:
            self.node.get_logger().warning(f"decision reply dropped: {exc}")

    def _remote(self, inp: DecisionInput) -> Decision:
        """One decision taken by the centre through the middleware (the mission's ``centre``)."""
        import rclpy

        mission = self.mission
        stamp = self.publish_world()
        blacklist = [] if inp.blacklist is None else np.flatnonzero(inp.blacklist).tolist()
        request = DecisionRequest(
            mission.link.totals.rounds - 1,
            stamp,
            mission.active.tolist(),
            np.flatnonzero(mission.sending()).tolist(),
            list(inp.current) if inp.current is not None else [np.zeros((0, 2), np.int32)] * len(mission.active),
            blacklist,
            dict(mission.rng.bit_generator.state),
        )
        text = request.to_json()
        self._reply = None
        t0 = asked = time.monotonic()
        self._request_pub.publish(self._String(data=text))
        while self._reply is None or self._reply.round != request.round:
            rclpy.spin_once(self.node, timeout_sec=0.05)
            now = time.monotonic()
            if now - t0 > self.settings.reply_timeout_s:
                raise MrExploreError(
                    f"the centre did not answer round {request.round} within {self.settings.reply_timeout_s:.0f} s; "
                    "start 'mrexplore ros2 centre --lockstep' and a robot node per robot"
                )
            if now - asked > _REQUEST_AGAIN_S:
                self.publish_world()  # re-sent under the same stamp's successor: the robots answer once they hold it
                self._request_pub.publish(self._String(data=text))
                asked = now
        reply = self._reply
        if reply.state_digest != state_digest(inp.state):
            self.map_mismatches += 1
            self.node.get_logger().warning(f"round {request.round}: the centre's map differs from the simulator's")
        mission.rng.bit_generator.state = reply.rng
        self.centre_ms.append(reply.centre_ms)
        frontiers = inp.frontiers if inp.frontiers is not None else detect_frontiers(inp.state)
        return reply.decision(inp.state, frontiers)

    # -- real time: Nav2's part ----------------------------------------------------------------------------
    def _on_goal(self, i: int, msg: Any) -> None:
        sim, robot = self.mission.sim, self.robots[i]
        if not sim.alive[i]:
            return
        x, y = robot.offset.to_team(float(msg.pose.position.x), float(msg.pose.position.y))
        goal = self.frame.xy_to_rc((float(x), float(y)))
        self._goal_ids[i] = os.urandom(16)
        self._goal_stamps[i] = self.node.get_clock().now().to_msg()
        self._goal_rc[i] = goal
        path = self._plan(i) if self.frame.contains(goal) else np.zeros((0, 2), np.int32)
        sim.set_path(i, path)
        self._nav[i] = "executing" if len(path) else "aborted"
        self._publish_nav(i)

    def _plan(self, i: int) -> NDArray[np.int32]:
        """Robot i's path to its goal as Nav2 would find it on the robot's own map: through the cells it
        holds free, else through unknown space too (``allow_unknown``); empty where neither leads there."""
        sim = self.mission.sim
        belief = sim.beliefs[i]
        own = classify(belief.log_odds, belief.observed, self.settings.spec.sim_cfg.sensor)
        here = (int(sim.positions_rc[i, 0]), int(sim.positions_rc[i, 1]))
        goal = self._goal_rc[i]
        free, occupied = own == CellState.FREE, own == CellState.OCCUPIED
        if self._team_map is not None:  # the team map, as a Nav2 costmap's static layer may take it
            free |= self._team_map == CellState.FREE
            occupied |= self._team_map == CellState.OCCUPIED
        for passable in (free, ~occupied):
            passable[here] = True
            path = astar_path(passable, here, goal)
            if len(path):
                return path
        return np.zeros((0, 2), np.int32)

    def _on_team_map(self, msg: Any) -> None:
        try:  # read as any robot's map is: checked, thresholded, placed in the simulator's grid
            self._team_map = state_in_team_frame(grid_data(msg), FrameOffset(), self.frame, GridThresholds())
        except MrExploreError as exc:
            self.node.get_logger().warning(f"team map dropped: {exc}")

    def every_robot_has_a_goal(self) -> bool:
        return all(nav is not None for nav in self._nav)

    def _publish_nav(self, i: int) -> None:
        from action_msgs.msg import GoalStatus

        goal_id, nav = self._goal_ids[i], self._nav[i]
        if goal_id is None or nav is None:
            return
        status = GoalStatus()
        status.goal_info.goal_id.uuid = list(goal_id)
        status.goal_info.stamp = self._goal_stamps[i]
        status.status = _STATUS[nav]
        msg = self._GoalStatusArray()
        msg.status_list = [status]
        self._status_pubs[i].publish(msg)

    def step(self) -> None:
        """One simulation step in real time: drive, scan, report to navigation's listeners."""
        sim = self.mission.sim
        for robot in self.mission.faults.failures_due(sim.steps):
            sim.fail(robot)  # stops for good and publishes nothing more
        result = sim.step()
        self.curve.append(sim.coverage)
        self.progress()
        for i in map(int, np.flatnonzero(sim.alive)):
            if self._nav[i] != "executing":
                continue
            if result.blocked[i] or sim.path_ahead_blocked(i):
                path = self._plan(i)  # Nav2 plans again around what it just saw; it gives up only without a way
                sim.set_path(i, path)
                if not len(path):
                    self._nav[i] = "aborted"
            elif sim.at_path_end(i):
                self._nav[i] = "succeeded"
            self._publish_nav(i)


def _finished(status: dict[str, Any] | None) -> str | None:
    return None if status is None else status.get("finished")


def run_sim_node(settings: SimSettings, loopback: bool = True, ros_args: Sequence[str] = ()) -> dict[str, Any]:
    """Run the simulated team until its mission ends (lockstep) or the centre says the exploration finished
    (real time); returns the run's record: the mission's measures and how the middleware did."""
    from mrexplore.ros2.robot_node import start_rclpy

    rclpy = start_rclpy(loopback, ros_args)
    node = rclpy.create_node("mrexplore_sim")
    try:
        sim_node = SimNode(node, settings)
        spec = settings.spec
        if settings.lockstep:
            result: MissionResult = sim_node.mission.run()
            sim_node.progress(force=True)
            return {
                **result.measures.to_dict(),
                "map_mismatches": sim_node.map_mismatches,
                "centre_ms_median": float(np.median(sim_node.centre_ms)) if sim_node.centre_ms else None,
                "starts_rc": result.starts_rc.tolist(),
            }
        sim = sim_node.mission.sim
        period = 1.0 / settings.speed
        sim_node.publish_world()
        t0 = published = time.monotonic()  # the clock starts once every robot has its first goal
        while not sim_node.every_robot_has_a_goal() and time.monotonic() - t0 < _FIRST_GOALS_S:
            rclpy.spin_once(node, timeout_sec=0.1)
            if time.monotonic() - published > 1.0:
                sim_node.publish_world()  # for robot nodes that started late
                published = time.monotonic()
        if not sim_node.every_robot_has_a_goal():
            raise MrExploreError(
                f"no goal from the centre for every robot within {_FIRST_GOALS_S:.0f} s; start "
                "'mrexplore ros2 centre' and a robot node per robot on the same ROS domain"
            )
        next_step = time.monotonic()
        while _finished(sim_node.centre_status) is None and sim.steps < spec.mission_cfg.max_steps:
            rclpy.spin_once(node, timeout_sec=max(0.0, next_step - time.monotonic()))
            if time.monotonic() >= next_step:
                next_step += period
                sim_node.step()
                sim_node.publish_world()
        return {
            "steps": int(sim.steps),
            "coverage": float(sim.coverage),
            "done_reason": _finished(sim_node.centre_status) or "max_steps",
            "robots_lost": int((~sim.alive).sum()),
            "starts_rc": sim_node.mission.starts_rc.tolist(),
        }
    except KeyboardInterrupt:
        raise MrExploreError("the simulation was interrupted") from None
    finally:
        node.destroy_node()
        rclpy.try_shutdown()
