"""The deployment's settings as ROS 2 parameters, derived from their one declaration
(:class:`~mrexplore.ros2.deployment.Deployment`'s fields, types, docs and rules): each node declares them
with the deployment file's values as defaults, so that ``-p round_period_s:=0.5`` or a ``--params-file``
overrides them as it would any ROS node's, checked as the file's values are. The params file of the ROS
package is written from the same declaration (:func:`params_yaml`).

Examples
--------
>>> from mrexplore.ros2.deployment import Deployment
>>> dep = Deployment.from_dict({"robots": ["robot1"]})
>>> [s.path for s in parameter_settings(dep)][:3]
['team_frame', 'team_grid.x0', 'team_grid.y0']
>>> with_parameters(dep, {"round_period_s": 2, "team_grid.resolution": 0.05}).round_period_s
2.0
>>> try:
...     with_parameters(dep, {"round_period_s": -1.0})
... except MrExploreError as exc:
...     print(exc)
ROS parameter round_period_s: must be > 0 seconds, got -1.0
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import yaml

from mrexplore.config.schema import Setting, settings_of
from mrexplore.maps.frame import GridFrame
from mrexplore.ros2.deployment import Deployment
from mrexplore.types import MrExploreError

__all__ = [
    "parameter_settings",
    "with_parameters",
    "declare_parameters",
    "apply_parameters",
    "params_yaml",
]


def parameter_settings(dep: Deployment) -> Iterator[Setting]:
    """Every deployment setting a ROS parameter carries: all but the robots' list (the file's, or ``--names``)."""
    return (s for s in settings_of(dep) if s.path != "robots")


def with_parameters(dep: Deployment, values: dict[str, Any]) -> Deployment:
    """``dep`` with the parameters ``values`` (dotted names) in place of its settings, each checked as the
    deployment file's; a bad one is one line naming the parameter."""
    data = dep.to_dict()
    for path, value in values.items():
        keys = path.split(".")
        node = data
        for key in keys[:-1]:
            node = node[key]
        node[keys[-1]] = value
        try:
            Deployment.from_dict(data, "ROS parameters")
        except MrExploreError as exc:
            reason = str(exc).split(f"{keys[-1]} ", 1)[-1] if f"{keys[-1]} must" in str(exc) else str(exc)
            raise MrExploreError(f"ROS parameter {path}: {reason}") from None
    return Deployment.from_dict(data, "ROS parameters")


def declare_parameters(node: Any, dep: Deployment) -> Deployment:
    """Declare the deployment's settings as ``node``'s parameters (defaults: ``dep``'s values, each with its
    documentation) and return the deployment as the parameters say (``-p``, ``--params-file``)."""
    from rcl_interfaces.msg import ParameterDescriptor

    values = {}
    for s in parameter_settings(dep):
        # Dynamic typing: ``-p round_period_s:=2`` (an integer) is as good as 2.0, as in the YAML file.
        descriptor = ParameterDescriptor(description=s.doc, dynamic_typing=True)
        value = node.declare_parameter(s.path, s.default, descriptor).value
        if value != s.default:
            values[s.path] = value
    return with_parameters(dep, values) if values else dep


def apply_parameters(node: Any, dep: Deployment, team: GridFrame) -> tuple[Deployment, GridFrame]:
    """The deployment and the team grid's frame as ``node``'s parameters say (:func:`declare_parameters`);
    the frame is rebuilt only where the parameters change the team grid."""
    from mrexplore.config import MapConfig

    mine = declare_parameters(node, dep)
    if mine.team_grid != dep.team_grid:
        team = mine.team_grid.frame(MapConfig().max_cells)
    return mine, team


def params_yaml(dep: Deployment) -> str:
    """A ROS 2 params file (``--params-file``) holding the deployment's settings as parameters of every
    mrexplore node (the ``/**`` wildcard: the centre and each robot's node read the same values), each
    setting's documentation as a comment above it."""
    lines = [
        "# mrexplore's ROS 2 parameters, written by 'mrexplore ros2 params' from the deployment's settings.",
        "/**:",
        "  ros__parameters:",
    ]
    section = ""
    for s in parameter_settings(dep):
        keys = s.path.split(".")
        indent = "    " + "  " * (len(keys) - 1)
        if len(keys) > 1 and keys[0] != section:
            section = keys[0]
            lines.append(f"    {section}:")
        lines.append(f"{indent}# {s.doc}" if s.doc else "")
        value = yaml.safe_dump(s.default, default_flow_style=True).strip().removesuffix("...").strip()
        lines.append(f"{indent}{keys[-1]}: {value}")
    return "\n".join(line for line in lines if line) + "\n"
