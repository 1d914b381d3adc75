"""``mrexplore ros2 sim``: the package's simulator as a team of ROS 2 robots, for trying the nodes without a
robot.

Each simulated robot publishes its belief as its map (``/NAME/map``, nav_msgs/OccupancyGrid, transient local)
and its pose (``/NAME/pose``, geometry_msgs/PoseWithCovarianceStamped), in the team frame.

- In real time (the default) it stands in for each robot's Nav2 and SLAM as they behave
  (:mod:`~mrexplore.ros2.nav2_double`): goals on ``/NAME/goal_pose`` accepted under ids and stamps of its own
  clock, a new goal preempting the last, status arrays on each change. ``--nav2`` adds what a Nav2 team
  brings: each robot's map in a frame of its own at SLAM's resolution, and sim time on ``/clock`` at
  ``clock_rate`` times the wall clock. It ends when the centre's status says the exploration finished, or at
  ``max_steps``.
- With ``lockstep`` it runs the package's own mission loop (:class:`~mrexplore.mission.Mission`, the same as
  ``mrexplore explore``) and takes every decision from the centre through the middleware: at each decision it
  publishes the robots' maps and poses, asks the centre (``/mrexplore/lockstep/request``) and waits for its
  answer (``/mrexplore/lockstep/decision``), taken on the maps the robot nodes sent it. The simulation
  advances only once the answer is in, so the mission equals ``mrexplore explore``'s step for step.
"""

from __future__ import annotations

import json
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from mrexplore.mission import Mission, MissionResult, MissionSpec
from mrexplore.pipeline import Decision, DecisionInput
from mrexplore.preprocessing.frontiers import detect_frontiers
from mrexplore.ros2.deployment import Deployment
from mrexplore.ros2.lockstep import DecisionReply, DecisionRequest, state_digest
from mrexplore.ros2.messages import pose_message, team_map_message
from mrexplore.ros2.nav2_double import DoubleSettings, Nav2Double, SimClock
from mrexplore.sim.belief import classify
from mrexplore.sim.world import ExplorationSim
from mrexplore.types import MrExploreError

__all__ = ["SimSettings", "SimNode", "run_sim_node"]

_REQUEST_AGAIN_S = 2.0
_LOG_EVERY_S = 5.0
_FIRST_GOALS_S = 300.0
"""Real time: the simulation starts once every robot has a goal; it gives up after this long (a first run on
a machine compiles the kernels in every process: a minute or more on two cores)."""


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
    double: DoubleSettings = DoubleSettings()
    """Real time: how each robot's Nav2 and SLAM depart from the simulator's frame and grid."""
    clock_rate: float | None = None
    """Real time: publish sim time on ``/clock`` running this many times the wall clock (None: no sim time)."""


class SimNode:
    """The simulated team's node (module docstring)."""

    def __init__(self, node: Any, settings: SimSettings) -> None:
        from geometry_msgs.msg import PoseWithCovarianceStamped
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
        self._String = String
        self._stamp = 0
        self._progress_at = self._logged_at = 0.0
        self.map_mismatches = 0
        """Lockstep decisions whose map at the centre differed from the simulator's own copy of it."""
        self.centre_ms: list[float] = []
        self._reply: DecisionReply | None = None
        self.centre_status: dict[str, Any] | None = None
        if settings.lockstep:
            latched = QoSProfile(
                depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL, reliability=ReliabilityPolicy.RELIABLE
            )
            self._maps = [node.create_publisher(OccupancyGrid, r.map_topic, latched) for r in self.robots]
            self._poses = [node.create_publisher(PoseWithCovarianceStamped, r.pose_topic, 10) for r in self.robots]
            self._request_pub = node.create_publisher(String, "/mrexplore/lockstep/request", 10)
            node.create_subscription(String, "/mrexplore/lockstep/decision", self._on_reply, 10)
            self.mission = Mission(spec, lambda sim, *_: self.progress(sim), progress=False, centre=self._remote)
            return

        def on_status(msg: Any) -> None:
            self.centre_status = json.loads(msg.data)

        node.create_subscription(String, "/mrexplore/status", on_status, 10)
        self.mission = Mission(spec, progress=False)  # its simulator and starts; the loop is the robots' own
        self.clock = SimClock(node, settings.clock_rate)
        self.double = Nav2Double(node, self.mission, self.robots, settings.double, self.clock.now_msg)
        self._map_at = -float("inf")
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

    # -- real time -------------------------------------------------------------------------------------
    def every_robot_has_a_goal(self) -> bool:
        return all(self.double.has_goal(i) for i in range(len(self.robots)))

    def publish_now(self, force: bool = False) -> None:
        """The robots' SLAM output now: maps every ``map_period_s`` of the clock (or ``force``), poses always."""
        now = self.clock.seconds()
        maps = force or now - self._map_at >= self.settings.double.map_period_s
        if maps:
            self._map_at = now
        self.double.publish_world(self.clock.now_msg(), maps)

    def step(self) -> None:
        """One simulation step in real time: drive, scan, report to navigation's listeners."""
        sim = self.mission.sim
        for robot in self.mission.faults.failures_due(sim.steps):
            sim.fail(robot)  # stops for good and publishes nothing more
        result = sim.step()
        self.curve.append(sim.coverage)
        self.progress()
        self.double.after_step(result.blocked)


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
        if settings.lockstep:
            result: MissionResult = sim_node.mission.run()
            sim_node.progress(force=True)
            return {
                **result.measures.to_dict(),
                "map_mismatches": sim_node.map_mismatches,
                "centre_ms_median": float(np.median(sim_node.centre_ms)) if sim_node.centre_ms else None,
                "starts_rc": result.starts_rc.tolist(),
            }
        return _run_real_time(rclpy, node, sim_node)
    except KeyboardInterrupt:
        raise MrExploreError("the simulation was interrupted") from None
    finally:
        node.destroy_node()
        rclpy.try_shutdown()


def _run_real_time(rclpy: Any, node: Any, sim_node: SimNode) -> dict[str, Any]:
    """The simulation in real time (or sim time): it starts once every robot has its first goal, then steps
    ``speed`` times a second of its clock until the centre says the exploration finished."""
    settings, clock, double = sim_node.settings, sim_node.clock, sim_node.double
    sim = sim_node.mission.sim
    sim_node.publish_now(force=True)
    t0 = published = time.monotonic()
    while not sim_node.every_robot_has_a_goal() and time.monotonic() - t0 < _FIRST_GOALS_S:
        rclpy.spin_once(node, timeout_sec=0.02)
        clock.publish()  # sim time runs while the team starts, as a simulator's does
        if time.monotonic() - published > 1.0:
            sim_node.publish_now(force=True)  # for robot nodes that started late
            published = time.monotonic()
    if not sim_node.every_robot_has_a_goal():
        raise MrExploreError(
            f"no goal from the centre for every robot within {_FIRST_GOALS_S:.0f} s; start "
            "'mrexplore ros2 centre' and a robot node per robot on the same ROS domain"
        )
    period, next_step = 1.0 / settings.speed, clock.seconds()
    while _finished(sim_node.centre_status) is None and sim.steps < settings.spec.mission_cfg.max_steps:
        rclpy.spin_once(node, timeout_sec=0.005)
        clock.publish()
        if clock.seconds() >= next_step:
            next_step += period
            sim_node.step()
            sim_node.publish_now()
    return {
        "steps": int(sim.steps),
        "coverage": float(sim.coverage),
        "done_reason": _finished(sim_node.centre_status) or "max_steps",
        "robots_lost": int((~sim.alive).sum()),
        "starts_rc": sim_node.mission.starts_rc.tolist(),
        "goals_received": sum(len(g) for g in double.goals) + double.expired + _action_goals(double),
        "aborts_caused": double.aborts_caused,
        "aborts_crossed": double.crossed,
        "preempted": double.preempted,
        "sim_seconds": clock.seconds(),
    }


def _action_goals(double: Nav2Double) -> int:
    return 0 if double.actions is None else int(double.actions.received)
