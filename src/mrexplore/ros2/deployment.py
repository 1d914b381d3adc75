"""A team's deployment as one YAML file, read by every ``mrexplore ros2`` node: the team's grid, each robot's
name, frame offset, frame id and topics, and the centre's timing. Plain data, no ROS.

Example file (every field but ``robots`` has a default; a robot given as a bare name takes the defaults)::

    team_frame: map                # the frame of the team map and the markers
    team_grid: {x0: -20.0, y0: -20.0, width: 40.0, height: 40.0, resolution: 0.1}
    round_period_s: 1.0            # the centre asks for the robots' maps this often (real time)
    round_timeout_s: 0.5           # and decides on what arrived within this
    lost_after_s: 5.0              # a robot silent this long is lost: no goal, not waited for
    blacklist_s: 30.0              # an aborted goal's clusters are kept from that robot this long
    replan_s: 10.0                 # a full decision at least this often
    min_replan_s: 1.0              # a goal already seen is driven on to until this passed since a decision
    reliable: true                 # QoS of the frontier messages (false: best effort)
    robots:
      - name: robot1
        offset: [0.0, 0.0, 0.0]    # x, y (m), yaw (rad) of its map frame in the team frame
        frame: map                 # the frame of its goals (default: map)
        pose_type: pose_with_covariance   # or odometry, or tf (a tf2 lookup of base_frame in frame)
        map_topic: /robot1/map     # defaults: /NAME/map, /NAME/pose, /NAME/goal_pose,
        pose_topic: /robot1/pose   #           /NAME/navigate_to_pose/_action/status
      - robot2

Examples
--------
>>> d = Deployment.from_dict({"robots": ["robot1", {"name": "robot2", "offset": [1.0, 0.0, 0.0]}]})
>>> [r.name for r in d.robots], d.robots[1].offset.x_m, d.robots[0].goal_topic
(['robot1', 'robot2'], 1.0, '/robot1/goal_pose')
>>> Deployment.from_dict(d.to_dict()) == d
True
>>> TeamGrid(0.0, 0.0, 10.9, 8.5, 0.1).frame(10**6).height  # not ceil(85.00000000000001)
85
>>> try:
...     Deployment.from_dict({"robots": ["robot1", "robot1"]})
... except MrExploreError as exc:
...     print(exc)
deployment names robot 'robot1' twice; give each robot its own name
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Any

from mrexplore.config.schema import Checked, OneOf, at_least, config_from_dict, is_finite, positive, require
from mrexplore.maps.frame import GridFrame
from mrexplore.maps.occupancy_grid import FrameOffset
from mrexplore.types import MrExploreError

__all__ = ["Deployment", "RobotEntry", "TeamGrid", "read_deployment", "POSE_TYPES", "GOAL_VIA"]

POSE_TYPES = ("pose_with_covariance", "odometry", "tf")
GOAL_VIA = ("auto", "action", "topic")
"""How goals reach a robot's Nav2: its NavigateToPose action, its ``goal_pose`` topic, or ``auto`` (the action
where nav2_msgs imports)."""
"""How a robot's pose is read: PoseWithCovarianceStamped (AMCL, slam_toolbox), nav_msgs/Odometry, or a tf2 lookup
of ``base_frame`` in ``frame`` (needs tf2_ros from a sourced ROS 2 installation; untested here)."""
_NAME = re.compile(r"^[A-Za-z][A-Za-z0-9_]*$")


@dataclass(frozen=True)
class TeamGrid(Checked):
    """The team's grid in the team frame: its lower-left corner, size (metres) and cell size."""

    x0: float = -25.0
    """Left edge of the team grid in the team frame, metres."""
    y0: float = -25.0
    """Bottom edge of the team grid in the team frame, metres."""
    width: float = 50.0
    """Extent along x, metres."""
    height: float = 50.0
    """Extent along y, metres."""
    resolution: float = 0.1
    """Cell size of the team grid, metres."""

    _constraints = {"width": positive("metres"), "height": positive("metres"), "resolution": positive("metres")}

    def frame(self, max_cells: int) -> GridFrame:
        """The grid's :class:`GridFrame`; one line naming the problem where it has too many cells."""
        # Rounded first: 8.5 m at 0.1 m is 85 cells, not the 86 of ceil(85.00000000000001).
        h, w = (math.ceil(round(extent / self.resolution, 6)) for extent in (self.height, self.width))
        if h * w > max_cells:
            raise MrExploreError(
                f"team grid holds {h * w:,} cells at {self.resolution} m, more than {max_cells:,} (map.max_cells); "
                "use coarser cells or a smaller grid"
            )
        return GridFrame(h, w, self.resolution, (self.x0, self.y0))


@dataclass(frozen=True)
class RobotEntry(Checked):
    """One robot of the deployment: its name, index (its place in the list), frame and topics."""

    name: str
    """The robot's name: letters, digits and _, from a letter (a ROS name); its topics' namespace."""
    index: int
    """Its place in the team, from 0 (the order of the deployment's list)."""
    offset: FrameOffset = FrameOffset()
    """Where its map frame lies in the team frame: x, y (metres), yaw (radians)."""
    frame: str = "map"
    """The frame of its map, pose and goals."""
    base_frame: str = "base_link"
    """The robot's body frame, for ``pose_type: tf``."""
    pose_type: str = "pose_with_covariance"
    """How its pose is read: ``pose_with_covariance`` (AMCL, slam_toolbox), ``odometry`` or ``tf``."""
    map_topic: str = ""
    """Its occupancy grid (default ``/NAME/map``)."""
    pose_topic: str = ""
    """Its pose (default ``/NAME/pose``)."""
    goal_topic: str = ""
    """Where its goals are sent (default ``/NAME/goal_pose``)."""
    nav_status_topic: str = ""
    """Nav2's goal status (default ``/NAME/navigate_to_pose/_action/status``)."""
    frontiers_topic: str = ""
    """Where the robot's sparse frontier messages are read (default ``/mrexplore/NAME/frontiers``, where its
    node publishes them; a relay in between republishes them elsewhere)."""
    goal_via: str = "auto"
    """How goals reach its Nav2: ``action`` (NavigateToPose, on the action named by ``nav_status_topic`` less
    ``/_action/status``), ``topic`` (``goal_topic``), ``auto`` (the action where nav2_msgs imports)."""
    tf_topic: str = ""
    """Where ``pose_type: tf`` reads transforms (default ``/NAME/tf``, as nav2_bringup remaps each robot's)."""
    tf_static_topic: str = ""
    """Where ``pose_type: tf`` reads static transforms (default ``/NAME/tf_static``)."""

    _constraints = {"index": at_least(0), "pose_type": OneOf(POSE_TYPES), "goal_via": OneOf(GOAL_VIA)}

    def _validate(self) -> None:
        require(
            bool(_NAME.match(self.name)), "robot name", "letters, digits and _ (a ROS name), from a letter", self.name
        )
        defaults = {
            "frontiers_topic": f"/mrexplore/{self.name}/frontiers",
            "map_topic": f"/{self.name}/map",
            "pose_topic": f"/{self.name}/pose",
            "goal_topic": f"/{self.name}/goal_pose",
            "nav_status_topic": f"/{self.name}/navigate_to_pose/_action/status",
            "tf_topic": f"/{self.name}/tf",
            "tf_static_topic": f"/{self.name}/tf_static",
        }
        for key, value in defaults.items():
            if not getattr(self, key):
                object.__setattr__(self, key, value)

    @property
    def reply_topic(self) -> str:
        return f"/mrexplore/{self.name}/reply"


@dataclass(frozen=True)
class Deployment(Checked):
    """What the nodes of one team share (module docstring)."""

    robots: tuple[RobotEntry, ...]
    """The team, in order: each a name, or a mapping of a :class:`RobotEntry`'s fields."""
    team_frame: str = "map"
    """The frame of the team map and the markers."""
    team_grid: TeamGrid = field(default_factory=TeamGrid)
    """The team's grid in the team frame."""
    round_period_s: float = 1.0
    """The centre asks for the robots' maps this often, seconds."""
    round_timeout_s: float = 0.5
    """And decides on what arrived within this, seconds."""
    lost_after_s: float = 5.0
    """A robot silent this long is lost: no goal, rounds no longer wait for it (its map stays), seconds."""
    blacklist_s: float = 30.0
    """An aborted goal's clusters are kept from that robot this long, seconds."""
    replan_s: float = 10.0
    """A full decision at least this often, seconds."""
    min_replan_s: float = 1.0
    """A goal already seen is driven on to until this passed since a decision, seconds."""
    reliable: bool = True
    """QoS of the frontier messages (false: best effort)."""

    _constraints = {
        key: positive("seconds")
        for key in ("round_period_s", "round_timeout_s", "lost_after_s", "blacklist_s", "replan_s", "min_replan_s")
    }

    def robot(self, name: str) -> RobotEntry:
        """The entry of robot ``name``; one line naming the team's robots where it has none."""
        for r in self.robots:
            if r.name == name:
                return r
        raise MrExploreError(
            f"robot {name!r} is not in the deployment; its robots: {', '.join(r.name for r in self.robots)}"
        )

    @classmethod
    def from_dict(cls, data: Any, what: str = "deployment") -> Deployment:
        if not isinstance(data, dict):
            raise MrExploreError(f"{what} must be a YAML mapping of settings, got {type(data).__name__}")
        known = {f.name for f in fields(cls)}
        unknown = sorted(set(data) - known)
        if unknown:
            raise MrExploreError(f"{what} has unknown setting {unknown[0]!r}; known: {', '.join(sorted(known))}")
        raw_robots = data.get("robots")
        if not isinstance(raw_robots, list) or not raw_robots:
            raise MrExploreError(f"{what} must list its robots: robots: [robot1, robot2]")
        robots = tuple(_robot(entry, i, what) for i, entry in enumerate(raw_robots))
        names = [r.name for r in robots]
        for name in names:
            if names.count(name) > 1:
                raise MrExploreError(f"{what} names robot {name!r} twice; give each robot its own name")
        settings = {k: v for k, v in data.items() if k not in ("robots", "team_grid")}
        try:
            team_grid = config_from_dict(TeamGrid, data.get("team_grid", {}), "team_grid.")
            return cls(robots, team_grid=team_grid, **settings)
        except MrExploreError as exc:
            raise MrExploreError(f"{what}: {exc}") from None

    def to_dict(self) -> dict[str, Any]:
        """The deployment as :meth:`from_dict` reads it (a deployment file's contents)."""
        robots = [
            {
                "name": r.name,
                "offset": [r.offset.x_m, r.offset.y_m, r.offset.yaw_rad],
                **{k: getattr(r, k) for k in ("frame", "base_frame", "pose_type", "map_topic", "pose_topic")},
                "goal_topic": r.goal_topic,
                "nav_status_topic": r.nav_status_topic,
                "frontiers_topic": r.frontiers_topic,
                **{k: getattr(r, k) for k in ("goal_via", "tf_topic", "tf_static_topic")},
            }
            for r in self.robots
        ]
        timing: tuple[str, ...] = ("round_period_s", "round_timeout_s", "lost_after_s", "blacklist_s", "replan_s")
        timing += ("min_replan_s",)
        timing += ("reliable",)
        return {
            "team_frame": self.team_frame,
            "team_grid": dict(self.team_grid.__dict__),
            **{k: getattr(self, k) for k in timing},
            "robots": robots,
        }

    @classmethod
    def of_names(cls, names: list[str], team_grid: TeamGrid, **kwargs: Any) -> Deployment:
        """A deployment of robots sharing one frame, with the default topics."""
        return cls.from_dict({"robots": names, "team_grid": team_grid.__dict__, **kwargs})


def _robot(entry: Any, index: int, what: str) -> RobotEntry:
    if isinstance(entry, str):
        entry = {"name": entry}
    if not isinstance(entry, dict) or "name" not in entry:
        raise MrExploreError(f"{what}: robot {index + 1} must be a name or a mapping with a name")
    name = str(entry["name"])
    allowed = {f.name for f in fields(RobotEntry)} - {"index"}
    unknown = sorted(set(entry) - allowed)
    if unknown:
        raise MrExploreError(
            f"{what}: robot {name} has unknown setting {unknown[0]!r}; known: {', '.join(sorted(allowed))}"
        )
    offset = entry.get("offset", [0.0, 0.0, 0.0])
    if not isinstance(offset, list) or len(offset) != 3 or not all(is_finite(v) for v in offset):
        raise MrExploreError(f"{what}: robot {name}'s offset must be [x, y, yaw] (metres, radians), got {offset!r}")
    kwargs = {k: v for k, v in entry.items() if k not in ("name", "offset")}
    try:
        return RobotEntry(name, index, FrameOffset(*(float(v) for v in offset)), **kwargs)
    except MrExploreError as exc:
        raise MrExploreError(
            f"{what}: robot {name}'s {exc}" if not str(exc).startswith("robot name") else f"{what}: {exc}"
        ) from None


def read_deployment(path: str | Path) -> Deployment:
    """The :class:`Deployment` of a YAML file; any problem is one line naming the file."""
    from mrexplore.config.safe_yaml import load_yaml_file

    p = Path(path)
    if not p.is_file():
        raise MrExploreError(f"deployment file {p} not found; docs/ros2.md shows one")
    return Deployment.from_dict(load_yaml_file(p, f"deployment file {p}"), f"deployment file {p}")
