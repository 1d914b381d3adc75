"""The full-knowledge yardstick as a pipeline: routes planned on the ground truth before the mission, one
candidate per robot, owned by it."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from mrexplore.config import SimConfig
from mrexplore.global_planning.oracle import plan_oracle_routes
from mrexplore.global_planning.protocol import AssignmentProblem
from mrexplore.maps.ground_truth import GroundTruthMap, explorable_region
from mrexplore.pipeline.base import ExplorationPipeline
from mrexplore.pipeline.decision import NO_ROUTE, CandidateQuery, CandidateSet, PosedWork
from mrexplore.preprocessing.clustering import Clusters
from mrexplore.types import CellState, MrExploreError, StateGrid

__all__ = ["OraclePipeline"]


@dataclass
class OraclePipeline(ExplorationPipeline):
    """The full-knowledge yardstick (``oracle``): follows routes planned on the ground truth before the
    mission (:mod:`~mrexplore.global_planning.oracle`). It still receives the robots' maps each round, so
    its bytes are counted like any strategy's, but plans on the truth."""

    viewpoint_spacing_m: float = 1.0
    """Lattice step of the candidate viewpoints, metres."""
    _truth_state: StateGrid | None = field(default=None, repr=False)
    _plan: list[NDArray[np.int32]] | None = field(default=None, repr=False)

    def prepare(self, truth: GroundTruthMap, starts_rc: NDArray[np.integer], sim: SimConfig) -> None:
        explorable = explorable_region(truth.occupied, starts_rc)
        plan = plan_oracle_routes(
            truth.occupied,
            explorable,
            starts_rc,
            sim.sensor.range_m / truth.resolution_m,
            sim.sensor.ray_oversampling,
            max(1, round(self.viewpoint_spacing_m / truth.resolution_m)),
        )
        self._plan = plan.routes
        self._truth_state = np.where(truth.occupied, CellState.OCCUPIED, CellState.FREE).astype(np.uint8)

    def planning_state(self, state: StateGrid) -> StateGrid:
        if self._truth_state is None:
            raise MrExploreError("the oracle needs the ground truth: call prepare() before decide()")
        return self._truth_state

    def candidates(self, q: CandidateQuery) -> CandidateSet:
        """Each robot's route is one candidate, owned by that robot: the plan at the first decision, what
        is left of it later."""
        if self._plan is None:
            raise MrExploreError("the oracle needs the ground truth: call prepare() before decide()")
        current = q.current
        routes = list(current) if current is not None and any(len(c) for c in current) else self._plan
        self._plan = [NO_ROUTE] * len(q.robots_rc)
        owners = np.array([i for i, r in enumerate(routes) if len(r)], dtype=np.int64)
        if len(owners) == 0:
            return CandidateSet(Clusters.empty(), "plan_done")
        members = np.vstack([routes[i] for i in owners]).astype(np.int32)
        labels = np.repeat(np.arange(len(owners)), [len(routes[i]) for i in owners]).astype(np.int32)
        centres = np.stack([routes[i][0] for i in owners]).astype(np.int32)
        sizes = np.array([len(routes[i]) for i in owners], dtype=np.int32)
        return CandidateSet(Clusters(centres, sizes, members, labels), owners=owners)

    def own_reads(
        self, robots_rc: NDArray[np.int32], candidates: CandidateSet, resolution_m: float
    ) -> list[NDArray[np.int32]] | None:
        """Each robot's next viewpoint: the robots own their routes, so a path to its own route's first
        target is all a robot's distances are read for."""
        owners, centres = candidates.owners, candidates.clusters.centers_rc
        assert owners is not None  # the oracle's candidates always name their owners
        return [centres[owners == i] for i in range(len(robots_rc))]

    def route(self, i: int, k: int, problem: AssignmentProblem, work: PosedWork) -> NDArray[np.int32]:
        """The robot's own route, in its order."""
        return problem.clusters.members_of(k)
