"""What the ROS package's launch file needs from mrexplore, as plain data it can be tested on without
``launch`` (not on PyPI): the team's deployment from the ``robots`` argument that nav2_bringup's cloned
multi-robot launch reads."""

from __future__ import annotations

import re
from typing import Any

from mrexplore.config.schema import is_finite
from mrexplore.ros2.deployment import Deployment
from mrexplore.types import MrExploreError

__all__ = ["nav2_robots", "bringup_deployment"]

_JAZZY = re.compile(r"^\s*([A-Za-z][A-Za-z0-9_]*)\s*=\s*(\{.*\})\s*$", re.DOTALL)


def nav2_robots(text: str, shared_map: bool) -> list[dict[str, Any]]:
    """A deployment's robots from the ``robots`` argument of nav2_bringup's cloned multi-robot launch, robots
    separated by ``;``, each a YAML mapping of a ``name`` and a ``pose`` of ``x``, ``y``, ``yaw`` (the current
    launch) or ``NAME={x: X, y: Y, yaw: A}`` (Jazzy's ``ParseMultiRobotPose``): each
    robot's map frame is where it started (slam_toolbox starts its map at the robot's first pose), or the
    team frame where the robots localise on one shared map (AMCL); one line naming the problem otherwise.

    Examples
    --------
    >>> robots = "{name: 'robot1', pose: {x: 0.5, y: 0.5, yaw: 0}};{name: 'robot2', pose: {x: -0.5, y: 1, yaw: 1.5}}"
    >>> [(r["name"], r["offset"]) for r in nav2_robots(robots, shared_map=False)]
    [('robot1', [0.5, 0.5, 0.0]), ('robot2', [-0.5, 1.0, 1.5])]
    >>> nav2_robots(robots, shared_map=True)[1]["offset"]
    [0.0, 0.0, 0.0]
    >>> nav2_robots("robot1={x: 1.0, y: 2.0, yaw: 0.5}; robot2={x: -1.0}", shared_map=False)[1]
    {'name': 'robot2', 'offset': [-1.0, 0.0, 0.0]}
    """
    from mrexplore.config.safe_yaml import load_yaml_text

    robots = []
    for k, part in enumerate(p for p in text.split(";") if p.strip()):
        jazzy = _JAZZY.match(part)  # Jazzy's ParseMultiRobotPose: robot1={x: 1.0, y: 1.0, yaw: 0.0}
        if jazzy:
            entry = {"name": jazzy.group(1), "pose": load_yaml_text(jazzy.group(2), f"robots argument, robot {k + 1}")}
        else:
            entry = load_yaml_text(part, f"robots argument, robot {k + 1}")
        if not isinstance(entry, dict) or "name" not in entry:
            raise MrExploreError(
                f"robots argument, robot {k + 1}: give {{name: 'robotN', pose: {{x: X, y: Y, yaw: A}}}}"
            )
        pose = entry.get("pose") or {}
        if not isinstance(pose, dict) or not all(is_finite(pose.get(key, 0.0)) for key in ("x", "y", "yaw")):
            raise MrExploreError(f"robots argument, robot {entry['name']}: pose must hold numbers x, y and yaw")
        xyyaw = [float(pose.get(key, 0.0)) for key in ("x", "y", "yaw")]
        robots.append({"name": str(entry["name"]), "offset": [0.0, 0.0, 0.0] if shared_map else xyyaw})
    if not robots:
        raise MrExploreError("robots argument names no robot; give \"{name: 'robot1', pose: {x: 0, y: 0, yaw: 0}}\"")
    return robots


def bringup_deployment(robots: str, shared_map: bool, base: Deployment | None = None) -> Deployment:
    """The deployment of the robots a nav2_bringup ``robots`` argument names, with ``base``'s other settings
    (the team grid, the timing), each robot on its default topics (``/NAME/map``, ``/NAME/pose``,
    ``/NAME/goal_pose``, ``/NAME/tf``)."""
    data = base.to_dict() if base is not None else {}
    return Deployment.from_dict({**data, "robots": nav2_robots(robots, shared_map)}, "robots argument")
