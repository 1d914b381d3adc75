"""The lockstep exchange between ``mrexplore ros2 sim --lockstep`` and the centre, as JSON text (plain data, no
ROS): the simulator asks for round r's decision and says what its robots report (their current routes, the
goals they gave up, whom the centre can hear), the centre answers with the decision it took on the maps it
received through the middleware.

The robots' reports stand for what Nav2 tells a real centre (a goal still being driven to, a goal aborted);
the generator's state travels both ways so that a planner that draws (NeuralCoMapping's seed) draws the
same numbers as in one process. Nothing here is needed outside lockstep: a real-time centre keeps its own
routes and blacklist.

Examples
--------
>>> import numpy as np
>>> route = np.array([[2, 3]], np.int32)
>>> req = DecisionRequest(4, (4, 0), [0, 1], [0, 1], [route, np.zeros((0, 2), np.int32)], [7], {})
>>> DecisionRequest.from_json(req.to_json()) == req
True
"""

from __future__ import annotations

import hashlib
import json
import time
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mrexplore.global_planning.protocol import Assignment
from mrexplore.mission.centre import TeamPlanner
from mrexplore.pipeline.decision import Decision
from mrexplore.preprocessing.clustering import Clusters
from mrexplore.preprocessing.frontiers import Frontiers
from mrexplore.types import MrExploreError, StateGrid

__all__ = ["DecisionRequest", "DecisionReply", "state_digest", "decide_lockstep"]


def _cells(rows: Any) -> NDArray[np.int32]:
    return np.asarray(rows, dtype=np.int32).reshape(-1, 2)


def _rows(cells: NDArray[np.integer]) -> list[list[int]]:
    return [[int(r), int(c)] for r, c in np.asarray(cells).reshape(-1, 2)]


def _parse(text: str, what: str) -> dict[str, Any]:
    try:
        data = json.loads(text)
    except json.JSONDecodeError as exc:
        raise MrExploreError(f"{what} is not JSON ({exc.msg} at character {exc.pos})") from None
    if not isinstance(data, dict):
        raise MrExploreError(f"{what} must be a JSON object, got {type(data).__name__}")
    return data


def state_digest(state: StateGrid) -> str:
    """A short digest of a grid, to check two processes decided on the same map."""
    return hashlib.sha256(np.ascontiguousarray(state).tobytes()).hexdigest()[:16]


@dataclass(frozen=True)
class DecisionRequest:
    """The simulator asks for the decision of one round."""

    round: int
    stamp: tuple[int, int]
    """``(sec, nanosec)`` of the maps and poses published for this round: a robot answers only once it holds them."""
    active: list[int]
    """The robots the decision covers, in robot order."""
    sending: list[int]
    """The robots that send their maps this round (the centre waits for each)."""
    current: list[NDArray[np.int32]]
    """Each active robot's route still being driven (its goal first; empty for none)."""
    blacklist: list[int]
    """Row-major indices of the cells that are no longer candidates."""
    rng: dict[str, Any]
    """The mission generator's state (``numpy.random.Generator.bit_generator.state``)."""

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, DecisionRequest):
            return NotImplemented
        return self.to_json() == other.to_json()

    def to_json(self) -> str:
        return json.dumps(
            {
                "round": self.round,
                "stamp": list(self.stamp),
                "active": self.active,
                "sending": self.sending,
                "current": [_rows(c) for c in self.current],
                "blacklist": self.blacklist,
                "rng": self.rng,
            },
            separators=(",", ":"),
        )

    @classmethod
    def from_json(cls, text: str) -> DecisionRequest:
        d = _parse(text, "decision request")
        try:
            return cls(
                int(d["round"]),
                (int(d["stamp"][0]), int(d["stamp"][1])),
                [int(i) for i in d["active"]],
                [int(i) for i in d["sending"]],
                [_cells(c) for c in d["current"]],
                [int(i) for i in d["blacklist"]],
                dict(d["rng"]),
            )
        except (KeyError, TypeError, ValueError, IndexError) as exc:
            raise MrExploreError(f"decision request lacks or mistypes a field ({exc})") from None


@dataclass(frozen=True)
class DecisionReply:
    """The centre's decision of one round, over the robots it could assign to."""

    round: int
    active: list[int]
    goals_rc: NDArray[np.int32]
    routes: list[NDArray[np.int32]]
    paths: list[NDArray[np.int32]]
    cluster_of_robot: list[int]
    centers_rc: NDArray[np.int32]
    sizes: list[int]
    done_reason: str | None
    rng: dict[str, Any]
    state_digest: str
    centre_ms: float

    @classmethod
    def of(
        cls, round_: int, active: list[int], decision: Decision, rng: dict[str, Any], centre_ms: float
    ) -> DecisionReply:
        return cls(
            round_,
            active,
            decision.goals_rc,
            decision.routes,
            decision.paths,
            [int(k) for k in decision.assignment.cluster_of_robot],
            decision.clusters.centers_rc,
            [int(s) for s in decision.clusters.sizes],
            decision.done_reason,
            rng,
            state_digest(decision.state),
            centre_ms,
        )

    def decision(self, state: StateGrid, frontiers: Frontiers) -> Decision:
        """The decision as the mission applies it, on ``state`` and its ``frontiers`` (the simulator's own copy
        of the centre's grid, equal where :attr:`state_digest` says so)."""
        clusters = Clusters(
            self.centers_rc.reshape(-1, 2).astype(np.int32),
            np.asarray(self.sizes, dtype=np.int32),
            np.zeros((0, 2), np.int32),
            np.zeros(0, np.int32),
        )
        return Decision(
            state,
            frontiers,
            clusters,
            Assignment(np.asarray(self.cluster_of_robot, dtype=np.int64)),
            self.goals_rc.reshape(-1, 2).astype(np.int32),
            self.routes,
            self.paths,
            self.done_reason,
        )

    def to_json(self) -> str:
        return json.dumps(
            {
                "round": self.round,
                "active": self.active,
                "goals": _rows(self.goals_rc),
                "routes": [_rows(r) for r in self.routes],
                "paths": [_rows(p) for p in self.paths],
                "cluster_of_robot": self.cluster_of_robot,
                "centers": _rows(self.centers_rc),
                "sizes": self.sizes,
                "done_reason": self.done_reason,
                "rng": self.rng,
                "state_digest": self.state_digest,
                "centre_ms": self.centre_ms,
            },
            separators=(",", ":"),
        )

    @classmethod
    def from_json(cls, text: str) -> DecisionReply:
        d = _parse(text, "decision reply")
        try:
            return cls(
                int(d["round"]),
                [int(i) for i in d["active"]],
                _cells(d["goals"]),
                [_cells(r) for r in d["routes"]],
                [_cells(p) for p in d["paths"]],
                [int(k) for k in d["cluster_of_robot"]],
                _cells(d["centers"]),
                [int(s) for s in d["sizes"]],
                None if d["done_reason"] is None else str(d["done_reason"]),
                dict(d["rng"]),
                str(d["state_digest"]),
                float(d["centre_ms"]),
            )
        except (KeyError, TypeError, ValueError, IndexError) as exc:
            raise MrExploreError(f"decision reply lacks or mistypes a field ({exc})") from None


def decide_lockstep(planner: TeamPlanner, request: DecisionRequest) -> tuple[Decision, DecisionReply, list[int]]:
    """The centre's decision on the simulator's ``request``, taken by ``planner`` on the maps it holds, with
    the simulator's generator state and reports: the decision, the reply for the simulator, and the robots
    the centre would assign to (the simulator's ``active`` where both heard the same robots)."""
    t0 = time.perf_counter()
    active = np.asarray(request.active, dtype=np.int64)
    mine = planner.assignable(request.round).tolist()
    blacklist = np.zeros(planner.team.map.shape, dtype=bool)
    blacklist.flat[request.blacklist] = True
    rng = np.random.default_rng()
    rng.bit_generator.state = request.rng
    decision = planner.strategy.decide(planner.decision_input(request.round, blacklist, request.current, rng, active))
    planner.decision = decision
    planner.decisions += 1
    for j, i in enumerate(map(int, active)):
        planner.book.assign(i, decision.goals_rc[j], decision.routes[j][1:])
    if decision.done_reason is not None:
        planner.done_reason = decision.done_reason
    ms = (time.perf_counter() - t0) * 1e3
    return decision, DecisionReply.of(request.round, request.active, decision, rng.bit_generator.state, ms), mine
