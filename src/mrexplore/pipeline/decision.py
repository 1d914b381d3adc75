"""The data passed between the mission and a strategy: what a decision is taken on (:class:`DecisionInput`),
what a strategy's candidates are built from and offer (:class:`CandidateQuery`, :class:`CandidateSet`), and
the answer, half taken (:class:`PosedDecision`) or whole (:class:`Decision`)."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mrexplore.global_planning.protocol import Assignment, AssignmentProblem
from mrexplore.paths.distance_field import Field
from mrexplore.paths.far_field import CoarseGrid, NearFarField, far_fields
from mrexplore.preprocessing.clustering import Clusters
from mrexplore.preprocessing.frontiers import Frontiers
from mrexplore.team.goal_book import NO_GOAL, NO_ROUTE  # the goal book owns them; re-exported here
from mrexplore.types import BoolGrid, StateGrid

__all__ = [
    "NO_GOAL",
    "NO_ROUTE",
    "RobotField",
    "DecisionInput",
    "Decision",
    "FarDistances",
    "CandidateQuery",
    "CandidateSet",
    "PosedWork",
    "PosedDecision",
]


RobotField = Field | NearFarField
"""A robot's distances at a decision: exact (:class:`Field`), or exact near it and estimated far away on a
large map (:class:`~mrexplore.paths.far_field.NearFarField`)."""


@dataclass(frozen=True)
class DecisionInput:
    """What the centre decides on at one round: the mission hands it to a strategy's
    :meth:`~mrexplore.pipeline.base.ExplorationPipeline.decide` or
    :meth:`~mrexplore.pipeline.base.ExplorationPipeline.pose`.

    Examples
    --------
    >>> import numpy as np
    >>> from mrexplore.types import CellState
    >>> grid = np.full((5, 5), CellState.FREE, np.uint8); grid[:, 4] = CellState.UNKNOWN
    >>> inp = DecisionInput(grid, np.array([[2, 0]], np.int32), resolution_m=0.1)
    >>> len(inp.robots_rc), inp.blacklist is None
    (1, True)
    """

    state: StateGrid
    """``(H, W) uint8`` the centre's grid, rebuilt from the robots' sparse frontier maps and closed."""
    robots_rc: NDArray[np.int32]
    """``(n_robots, 2) int32`` the cells of the robots the centre assigns to (their last messages')."""
    resolution_m: float
    """Cell size, metres."""
    blacklist: BoolGrid | None = None
    """``(H, W) bool`` frontier cells a robot stood on without resolving them; they are not candidates any
    more (explore_lite blacklists such goals too). None: none."""
    current: Sequence[NDArray[np.int32]] | None = None
    """Each robot's current route (its goal first; empty for none): a goal still on a frontier makes its
    cluster cheaper for that robot by the pipeline's ``commitment``, and a robot assigned that cluster again
    keeps its route. Without it, Mean-Shift's snapped centres of large clusters jump between far pieces from
    one decision to the next and robots turn back and forth. None: no robot has a goal."""
    rng: np.random.Generator | None = None
    """Reaches the planner in the problem (a seeded generator for stochastic planners)."""
    frontiers: Frontiers | None = None
    """Those of ``state`` where the caller has them (the centre keeps them where the grid changed); None:
    detected from ``state``."""
    barred: Sequence[BoolGrid | None] | None = None
    """Per robot, ``(H, W) bool`` cells whose clusters are kept from that robot alone (its navigation aborted a
    goal there, :class:`~mrexplore.mission.centre.TeamPlanner`): a cluster centred there reads unreachable for it.
    None: none."""


@dataclass(frozen=True)
class Decision:
    """The centre's answer at one decision.

    Attributes
    ----------
    state:
        ``(H, W) uint8`` the centre's grid after closing, on which everything was planned.
    frontiers, clusters:
        Layer 1 output.
    assignment:
        Layer 2 output.
    goals_rc:
        ``(n_robots, 2) int32`` goal cell per robot; ``(-1, -1)`` for none.
    routes:
        One ``(m, 2) int32`` ordered list of targets per robot; the first is its goal. Longer than one
        where the local layer routed through sub-clusters (paper IV-C).
    paths:
        One ``(k, 2) int32`` path per robot from its cell to its goal (empty for none).
    done_reason:
        ``None`` while exploring; ``"no_frontiers"`` (no cluster of the minimum size left) or
        ``"no_reachable_frontiers"`` (no robot can reach any cluster): the paper's termination criteria.
    """

    state: StateGrid
    frontiers: Frontiers
    clusters: Clusters
    assignment: Assignment
    goals_rc: NDArray[np.int32]
    routes: list[NDArray[np.int32]]
    paths: list[NDArray[np.int32]]
    done_reason: str | None


@dataclass(frozen=True)
class FarDistances:
    """Distances on a large map: exact within ``radius_cells`` of the source, estimated beyond on ``grid``'s
    blocks (:func:`~mrexplore.paths.far_field.far_fields`); one pooled grid shared by a decision's searches."""

    radius_cells: int
    grid: CoarseGrid

    def fields(
        self,
        passable: BoolGrid,
        sources_rc: NDArray[np.integer],
        must_rc: NDArray[np.integer] | None = None,
        own_rc: Sequence[NDArray[np.int32]] | None = None,
        own_needed: Callable[[NDArray[np.float64]], NDArray[np.bool_]] | None = None,
    ) -> list[NearFarField]:
        """One near/far field per source (``must_rc``, ``own_rc``, ``own_needed``: as :func:`far_fields`)."""
        return far_fields(
            passable, sources_rc, self.radius_cells, self.grid.factor, must_rc, own_rc, self.grid, own_needed
        )


@dataclass(frozen=True)
class CandidateQuery:
    """What a strategy may look at when it builds its candidates (one decision at the centre)."""

    state: StateGrid
    """``(H, W) uint8`` the centre's closed grid."""
    frontiers: Frontiers
    blacklist: BoolGrid | None
    """Frontier cells that stopped being candidates (stood on without resolving them; stalled goals)."""
    robots_rc: NDArray[np.int32]
    """``(n_robots, 2) int32`` the cells of the robots assigned to."""
    fields: Callable[..., list[RobotField]]
    """``fields(read_rc=None, needed=None)``: each robot's distances on the planning grid, computed once, on
    the first call. Exact fields: whole ones, or with ``read_rc`` ``(k, 2)`` each search stopped once it has
    reached those cells, the robots and the current goals (the candidates' cells must be among ``read_rc``).
    Near/far fields where :attr:`far` is set, which answer the cells ``read_rc`` that their coarse grid leaves
    at ``inf`` by an exact search from the robot (``own_rc`` of :func:`~mrexplore.paths.far_field.far_fields`),
    only those that ``needed`` keeps where it is given (its ``own_needed``)."""
    current: Sequence[NDArray[np.int32]] | None
    """Each robot's current route (its goal first; empty for none)."""
    resolution_m: float
    far: FarDistances | None = None
    """How distances beyond an exact radius are estimated where the known passable box holds more than
    ``far_above_cells``; None where every distance is exact."""


@dataclass(frozen=True)
class CandidateSet:
    """What a strategy offers its robots at one decision: the seam through which a strategy supplies its
    own candidates (Mean-Shift clusters, CoScan tasks, oracle routes, ...), everything else being shared."""

    clusters: Clusters
    """The candidates, as clusters: a centre (the target distances are measured to), members, sizes."""
    ended: str | None = None
    """Why the mission ends here, where it does (``no_frontiers``, ``no_reachable_frontiers``,
    ``plan_done``); None: the shared checks decide (no candidate left, or none reachable)."""
    context: Any = None
    """What the strategy's own routing reuses from building the candidates (CoScan's task distances)."""
    owners: NDArray[np.int64] | None = None
    """``(n_clusters,) int64`` the robot each candidate belongs to, where the strategy fixes it (the
    oracle's routes); None: the global planner assigns."""


@dataclass(frozen=True)
class PosedWork:
    """What layer 3 reuses from layer 1 and the distances of the same decision."""

    frontiers: Frontiers
    fields: list[RobotField]
    passable: BoolGrid
    kept: dict[int, tuple[int, NDArray[np.int32]]]
    """Robots that keep their cluster: ``{robot: (cluster, route)}`` (goal hysteresis)."""
    candidates: CandidateSet | None = None


@dataclass(frozen=True)
class PosedDecision:
    """A decision half taken: the problem for the global planner, or the mission's end.

    Exactly one of ``problem`` and ``final`` is set. A trainer or an expert answers ``problem`` with any
    :class:`~mrexplore.global_planning.protocol.Assignment` and hands it to
    :meth:`~mrexplore.pipeline.base.ExplorationPipeline.finish`.
    """

    problem: AssignmentProblem | None
    final: Decision | None
    work: PosedWork | None = field(default=None, repr=False)
