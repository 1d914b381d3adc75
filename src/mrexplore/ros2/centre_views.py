"""What the centre node shows: the team map, the markers and its status (JSON on ``/mrexplore/status``), its
wire counts, and the line that says why the exploration ended."""

from __future__ import annotations

import json
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mrexplore.maps.frame import GridFrame
from mrexplore.mission.centre import TeamPlanner
from mrexplore.ros2.messages import markers_message, team_map_message
from mrexplore.types import CellState

__all__ = ["WireCounts", "Views", "centre_status", "centre_record", "save_record", "team_summary", "WHY"]

WHY = {
    "no_frontiers": "no frontier cluster of the minimum size is left",
    "no_reachable_frontiers": "no robot can reach any frontier cluster",
    "stopped": "stopped by /mrexplore/stop",
}
"""Why the exploration ended, in words."""


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

    def count(self, resent: bool, payload: int, serialized: int) -> None:
        """One message taken: a first answer, or a whole map asked for again (``resent``)."""
        if resent:
            self.resent_messages += 1
            self.resent_payload_bytes += payload
            self.resent_serialized_bytes += serialized
        else:
            self.messages += 1
            self.payload_bytes += payload
            self.serialized_bytes += serialized


Flags = NDArray[Any] | None


def centre_status(centre: Any, heard: Flags = None, assignable: Flags = None) -> dict[str, Any]:
    """What a :class:`~mrexplore.ros2.centre_node.CentreNode`'s status topic says: the round, whom it hears,
    the goals, the goals sent and sent again, the robots lost, whether it is paused, why it ended."""
    planner: TeamPlanner = centre.planner
    return {
        "round": centre.round,
        "robots": [r.name for r in centre.robots],
        "heard": [] if heard is None else [bool(h) for h in heard],
        "assignable": [] if assignable is None else [bool(a) for a in assignable],
        "goals_rc": planner.goals.tolist(),
        "clusters": 0 if planner.decision is None else len(planner.decision.clusters),
        "decisions": planner.decisions,
        "aborts": planner.aborts,
        "goals_sent": centre.goals_sent,
        "goals_resent": sum(g.resent for g in centre.goals),
        "goal_via": sorted({g.kind for g in centre.goals}),
        "paused": centre.paused,
        "lost": [centre.robots[i].name for i in sorted(centre.rounds.lost)],
        "finished": centre.finished or planner.done_reason,
    }


def centre_record(centre: Any) -> dict[str, Any]:
    """A centre node's record: its status, each robot's wire counts, the decisions' latency."""
    return {
        **centre_status(centre),
        "warnings": centre.warnings,
        "wire": {r.name: w.__dict__ for r, w in zip(centre.robots, centre.wire, strict=True)},
        "decision_ms": centre.decision_ms,
    }


def save_record(path: Any, centre: Any) -> None:
    """Write the centre's record to ``path`` whole or not at all (a reader never sees half a file)."""
    tmp = path.with_suffix(".tmp")
    tmp.write_text(json.dumps(centre_record(centre)))
    tmp.replace(path)


def team_summary(planner: TeamPlanner, n_robots: int, lost: int) -> str:
    """The team map in a few numbers, for the line that says why the exploration ended."""
    state = planner.team.state()
    un = planner.team.frontiers().un_mask & ~planner.blacklist()
    heard = int((planner.team.last_heard >= 0).sum())
    free, unknown = int((state == CellState.FREE).sum()), int((state == CellState.UNKNOWN).sum())
    return (
        f"team map: {free:,} free cells, {unknown:,} unknown, {int(un.sum()):,} frontier cells; "
        f"{heard} of {n_robots} robots heard, {lost} lost"
    )


class Views:
    """The centre's publishers of what people and tools watch: ``/mrexplore/map`` and ``/mrexplore/markers``
    (transient local, in the team frame) and ``/mrexplore/status``."""

    def __init__(self, node: Any, planner: TeamPlanner, team: GridFrame, frame: str) -> None:
        from nav_msgs.msg import OccupancyGrid
        from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
        from std_msgs.msg import String
        from visualization_msgs.msg import MarkerArray

        self.planner, self.team, self.frame, self._String = planner, team, frame, String
        latched = QoSProfile(
            depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL, reliability=ReliabilityPolicy.RELIABLE
        )
        self._map = node.create_publisher(OccupancyGrid, "/mrexplore/map", latched)
        self._markers = node.create_publisher(MarkerArray, "/mrexplore/markers", latched)
        self._status = node.create_publisher(String, "/mrexplore/status", 10)

    def publish(self, round_: int, status: Callable[[Any, Any], dict[str, Any]]) -> None:
        """Publish the team map, the markers and ``status(heard, assignable)`` after ``round_``."""
        planner, team, frame = self.planner, self.team, self.frame
        self._map.publish(team_map_message(planner.team.state(), team, frame))
        decision = planner.decision
        centres = decision.clusters.centers_rc if decision is not None else np.zeros((0, 2), np.int32)
        routes = [planner.book.current(i) if planner.goals[i, 0] >= 0 else None for i in range(len(planner.goals))]
        self._markers.publish(
            markers_message(planner.team.frontiers().un_mask, centres, planner.team.positions_rc, routes, team, frame)
        )
        link = planner.team.status(round_)
        self._status.publish(self._String(data=json.dumps(status(link.heard, link.assignable))))
