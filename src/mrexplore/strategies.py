"""Named complete pipelines (preprocessing -> global assignment -> local routing) for the CLI and the bench."""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from functools import partial
from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import connected_components

from mrexplore.boxes import Box, grown_slices, mask_box
from mrexplore.config import CoScanConfig, GlobalPlanningConfig, LocalPlanningConfig, PreprocessConfig, SimConfig
from mrexplore.global_planning.classical import GeodesicPlanner, NearestPlanner, UtilityPlanner
from mrexplore.global_planning.coscan import (
    TaskRows,
    cap_tasks,
    lloyd_clusters,
    matrix_rows,
    sample_tasks,
    tasks_in_reach,
    two_opt_tour,
)
from mrexplore.global_planning.ncm_nodes import in_window, ncm_frontier, pool_nodes
from mrexplore.global_planning.oracle import plan_oracle_routes
from mrexplore.global_planning.protocol import UNASSIGNED, Assignment, AssignmentProblem, GlobalPlanner
from mrexplore.local_planning.router import LocalRouter
from mrexplore.maps.ground_truth import GroundTruthMap, explorable_region
from mrexplore.paths.distance_field import (
    Field,
    distance_fields,
    distance_matrix,
    distances_at,
    nearest_fields,
    pairwise_distances,
)
from mrexplore.paths.far_field import CoarseGrid, NearFarField, coarse_grid, far_fields, finer_side, path_to
from mrexplore.paths.portals import PortalGraph
from mrexplore.preprocessing.clustering import Clusters, cluster_frontiers, split_for_team
from mrexplore.preprocessing.frontiers import Frontiers, detect_frontiers
from mrexplore.threads import map_threads
from mrexplore.types import BoolGrid, CellState, MrExploreError, StateGrid

__all__ = [
    "Decision",
    "PosedDecision",
    "CandidateQuery",
    "CandidateSet",
    "FarDistances",
    "ExplorationPipeline",
    "STRATEGIES",
    "policy_for",
    "make_strategy",
    "strategy_names",
    "NO_GOAL",
    "LEARNED",
]

NO_GOAL = np.array([-1, -1], dtype=np.int32)
NO_LOCAL_SUFFIX = "-nolocal"
"""A strategy name with this suffix (``hier-nolocal``) runs without its local layer."""


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


_NO_ROUTE = np.zeros((0, 2), dtype=np.int32)

RobotField = Field | NearFarField
"""A robot's distances at a decision: exact (:class:`Field`), or exact near it and estimated far away on a
large map (:class:`~mrexplore.paths.far_field.NearFarField`)."""


def _ended(state: StateGrid, frontiers: Frontiers, clusters: Clusters, n: int, reason: str) -> Decision:
    """A decision that ends the mission: no goal, route or path for anyone."""
    none = [_NO_ROUTE] * n
    unassigned = Assignment(np.full(n, UNASSIGNED, dtype=np.int64))
    return Decision(state, frontiers, clusters, unassigned, np.tile(NO_GOAL, (n, 1)), none, none, reason)


def _decision(
    state: StateGrid,
    frontiers: Frontiers,
    clusters: Clusters,
    assignment: Assignment,
    routes: list[NDArray[np.int32]],
    fields: list[RobotField],
    passable: BoolGrid,
    robots_rc: NDArray[np.int32],
) -> Decision:
    """Each robot's goal is the first target of its route (empty: none); its path is read off its own
    distance field, which already holds every shortest distance from it (or, for a goal beyond the exact
    part of a :class:`~mrexplore.paths.far_field.NearFarField`, searched along its coarse way there)."""
    goals = np.tile(NO_GOAL, (len(routes), 1))
    paths = []
    for i, route in enumerate(routes):
        if len(route):
            goals[i] = route[0]
            paths.append(path_to(fields[i], passable, tuple(robots_rc[i]), tuple(goals[i])))
        else:
            paths.append(_NO_ROUTE)
    return Decision(state, frontiers, clusters, assignment, goals, routes, paths, None)


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
class _Posed:
    """What layer 3 reuses from layer 1 and the distances of the same decision."""

    frontiers: Frontiers
    fields: list[RobotField]
    passable: BoolGrid
    kept: dict[int, tuple[int, NDArray[np.int32]]]
    candidates: CandidateSet | None = None


@dataclass(frozen=True)
class PosedDecision:
    """A decision half taken: the problem for the global planner, or the mission's end.

    Exactly one of ``problem`` and ``final`` is set. A trainer or an expert answers ``problem`` with any
    :class:`~mrexplore.global_planning.protocol.Assignment` and hands it to
    :meth:`ExplorationPipeline.finish`.
    """

    problem: AssignmentProblem | None
    final: Decision | None
    work: _Posed | None = field(default=None, repr=False)


def _current_clusters(clusters: Clusters, current: Sequence[NDArray[np.int32]] | None, n: int) -> NDArray[np.int64]:
    """``(n,) int64`` the cluster each robot's current goal is a member of; -1 for none."""
    out = np.full(n, -1, dtype=np.int64)
    if current is None or len(clusters.members_rc) == 0:
        return out
    m = clusters.members_rc
    for i, route in enumerate(current):
        if len(route):
            hit = np.flatnonzero((m[:, 0] == route[0, 0]) & (m[:, 1] == route[0, 1]))
            if len(hit):
                out[i] = int(clusters.labels[hit[0]])
    return out


@dataclass
class ExplorationPipeline:
    """A complete strategy: the centre's preprocessing, a global planner, and optionally local routing.

    Without a local router a robot's goal is its cluster's centre; with one, a cluster of more than theta
    members is split into sub-clusters and the robot follows the best route through them.
    """

    name: str
    planner: GlobalPlanner
    preprocess: PreprocessConfig = field(default_factory=PreprocessConfig)
    local: LocalRouter | None = None
    commitment: float = 1.0
    """Goal hysteresis in [0, 1] (see :class:`~mrexplore.config.GlobalPlanningConfig`); 1: none."""
    goals_are_frontiers: bool = True
    """Goals are frontier cells: a goal that stops bordering unknown space is resolved (False for the
    oracle, whose goals are viewpoints)."""
    policy: dict[str, str] | None = None
    """Where a learned planner's weights came from: ``{"path", "sha256", "code_version"}``; None: no network."""
    nearest_only: bool = False
    """The planner reads only each robot's nearest cluster (and its current goal's, for hysteresis)
    (:meth:`own_reads`)."""
    stop_searches: bool = True
    """Where the planner and the routes read fewer distances than every robot's to every centre
    (:meth:`own_reads`), the pipeline's own decisions (:meth:`decide`) stop each exact search once it has
    those (:func:`nearest_fields`); a problem posed for another planner (:meth:`pose`) has every distance.
    False: whole searches, the same decisions (for tests and timings)."""
    distances: GlobalPlanningConfig = field(default_factory=GlobalPlanningConfig)
    """Where robot distances stop being exact on large maps (``far_above_cells``, ``exact_radius_m``,
    ``coarse_cell_m``, ``portal_sector_blocks``)."""
    _portals: dict[tuple[int, int, int], PortalGraph] = field(
        default_factory=dict, init=False, repr=False, compare=False
    )
    """The portal graph of each grid shape and block size far distances were searched on, kept from decision
    to decision (:mod:`~mrexplore.paths.portals`)."""

    def prepare(self, truth: GroundTruthMap, starts_rc: NDArray[np.integer], sim: SimConfig) -> None:
        """Called once before a mission; only a yardstick that knows the map uses it."""

    def own_reads(
        self, robots_rc: NDArray[np.int32], candidates: CandidateSet, resolution_m: float
    ) -> list[NDArray[np.int32]] | None:
        """The cells, per robot, at which this pipeline's own planner and routes read its distance besides
        its nearest centre (and its goal, for hysteresis), where that is fewer than every centre's; None:
        every centre's (the default). With :attr:`stop_searches` its own decisions' exact searches stop
        once each robot has settled those, its goal and its nearest centre: every centre left unread then
        reads ``inf`` or its exact distance, and one reads finite wherever any centre is reachable (the
        decision's end is the same). The planner must never pick for robot i a centre outside its cells
        that read ``inf``, and the routes' first targets must be among the cells (their paths are read).
        :attr:`nearest_only`: none besides the nearest."""
        return [_NO_ROUTE] * len(robots_rc) if self.nearest_only else None

    def _committed(
        self,
        clusters: Clusters,
        fields: list[RobotField],
        current: Sequence[NDArray[np.int32]],
        dist: NDArray[np.float64],
    ) -> dict[int, tuple[int, NDArray[np.int32]]]:
        """Robots whose goal is still a member of a cluster: ``{robot: (cluster, route)}``; discounts
        ``dist`` in place for those pairs (goal hysteresis)."""
        members = clusters.members_rc
        kept: dict[int, tuple[int, NDArray[np.int32]]] = {}
        for i, route in enumerate(current):
            if len(route) == 0:
                continue
            # The goal's member row (a dict of every member cost a millisecond a decision on a large map).
            hit = np.flatnonzero((members[:, 0] == route[0, 0]) & (members[:, 1] == route[0, 1]))
            if len(hit) == 0:
                continue
            k = int(clusters.labels[hit[-1]])
            d_goal = fields[i].value(route[0, 0], route[0, 1])
            if np.isfinite(d_goal):
                dist[i, k] = min(dist[i, k], self.commitment * d_goal)
                kept[i] = (k, route)
        return kept

    # -- the seam: what a strategy may supply ---------------------------------------------------------
    def planning_state(self, state: StateGrid) -> StateGrid:
        """The grid paths are planned on (the centre's; the oracle plans on the truth)."""
        return state

    def candidates(self, q: CandidateQuery) -> CandidateSet:
        """Layer 1's candidates: F_un (less blacklisted cells) clustered by Mean-Shift (paper IV-A)."""
        speck = self.preprocess.min_cluster_size if self.preprocess.drop_specks else 1  # 1: none dropped
        un_rc = _denoised_un(q.frontiers, q.blacklist, speck).astype(np.int32)
        cap = self.preprocess.bandwidth_max_m
        clusters = cluster_frontiers(un_rc, self.preprocess, None, None if cap is None else cap / q.resolution_m)
        if self.preprocess.split_for_team:
            pp = self.preprocess
            shortest = math.ceil(round(pp.split_min_frontier_m / q.resolution_m, 6))  # metres to members
            clusters = split_for_team(clusters, len(q.robots_rc), pp.min_cluster_size, shortest)
        return CandidateSet(clusters)

    def route(self, i: int, k: int, problem: AssignmentProblem, work: _Posed) -> NDArray[np.int32]:
        """Robot i's targets in its assigned candidate k: its current route where it keeps the cluster
        (hysteresis), a local route through sub-clusters (paper IV-C), or the cluster's centre."""
        clusters, fields = problem.clusters, work.fields
        if work.kept.get(i, (None,))[0] == k:
            return work.kept[i][1]
        if self.local is not None and self.local.applies(int(clusters.sizes[k])):
            route = self.local.route(
                work.passable, tuple(problem.robots_rc[i]), fields[i], clusters.members_of(k), problem.resolution_m
            )
            return route.targets_rc if route is not None else clusters.centers_rc[k : k + 1]
        return clusters.centers_rc[k : k + 1]

    # -- the shared decision ---------------------------------------------------------------------------
    def pose(
        self,
        state: StateGrid,
        robots_rc: NDArray[np.int32],
        resolution_m: float,
        blacklist: BoolGrid | None = None,
        current: Sequence[NDArray[np.int32]] | None = None,
        rng: np.random.Generator | None = None,
        frontiers: Frontiers | None = None,
        own_planner: bool = False,
    ) -> PosedDecision:
        """Layer 1 and the distances: the :class:`PosedDecision` a global planner answers (or the end).

        ``blacklist`` marks frontier cells a robot stood on without resolving them; they are not
        candidates any more (explore_lite blacklists such goals too). ``current`` holds each robot's
        current route (its goal first; empty for none): a goal still on a frontier makes its cluster
        cheaper for that robot by ``commitment``, and a robot assigned that cluster again keeps its
        route. Without it, Mean-Shift's snapped centres of large clusters jump between far pieces from
        one decision to the next and robots turn back and forth. ``frontiers``: those of ``state`` where the
        caller has them (the centre keeps them where the grid changed; None: detected here).
        ``own_planner``: the problem goes to this pipeline's own planner only (:meth:`decide`), so the
        searches may stop where it stops reading (:meth:`own_reads`, :attr:`stop_searches`).
        """
        if frontiers is None:
            frontiers = detect_frontiers(state)
        planning = self.planning_state(state)
        passable = planning == CellState.FREE
        computed: list[list[RobotField]] = []
        box, far = self._extent(passable, resolution_m)
        goals = [r[:1] for r in current] if current is not None else []

        def fields_now(
            read_rc: NDArray[np.int32] | None = None,
            needed: Callable[[NDArray[np.float64]], NDArray[np.bool_]] | None = None,
        ) -> list[RobotField]:
            if not computed:
                if far is None:
                    # The strategy's cells are its candidates' members and centres; each search stops once
                    # it has them, the robots and the current goals (all the decision reads).
                    targets = None if read_rc is None else np.vstack([read_rc, robots_rc, *goals])
                    computed.append(list(distance_fields(passable, robots_rc, targets, box=box)))
                else:
                    own = None if read_rc is None else [read_rc] * len(robots_rc)
                    computed.append(list(far.fields(passable, robots_rc, own_rc=own, own_needed=needed)))
            return computed[0]

        cand = self.candidates(
            CandidateQuery(state, frontiers, blacklist, robots_rc, fields_now, current, resolution_m, far)
        )
        clusters = cand.clusters
        n = len(robots_rc)
        if cand.ended is not None:
            return PosedDecision(None, _ended(planning, frontiers, clusters, n, cand.ended))
        if len(clusters) == 0:
            return PosedDecision(None, _ended(planning, frontiers, clusters, n, "no_frontiers"))
        own = goals if self.commitment < 1 else []  # a robot's own goal is read for hysteresis only
        stop = self.stop_searches and own_planner and far is None and not computed
        reads = self.own_reads(robots_rc, cand, resolution_m) if stop else None
        if computed:  # the strategy's candidates asked for them
            fields = computed[0]
        elif reads is not None:
            # Each robot's own cells, its nearest centre (ties too) and its goal are all the planner and the
            # paths read.
            mine = [np.vstack([r, *own[i : i + 1]]) for i, r in enumerate(reads)]
            fields = list(nearest_fields(passable, robots_rc, clusters.centers_rc, mine, box=box))
        elif far is None:
            # Every cell a field is read at from here on: centres, members (routes and goals), robots,
            # current goals. Each search stops once it has them all.
            targets = np.vstack([clusters.centers_rc, clusters.members_rc, robots_rc, *goals])
            fields = list(distance_fields(passable, robots_rc, targets, box=box))
        else:
            fields = list(far.fields(passable, robots_rc, clusters.centers_rc, own))
        dist = np.stack([distances_at(f, clusters.centers_rc) for f in fields])
        kept = self._committed(clusters, fields, current, dist) if current is not None and self.commitment < 1 else {}
        if not np.isfinite(dist).any():
            return PosedDecision(None, _ended(planning, frontiers, clusters, n, "no_reachable_frontiers"))
        robots = np.asarray(robots_rc, np.int32)
        problem = AssignmentProblem(
            robots,
            clusters,
            dist,
            resolution_m,
            planning,
            current_cluster=_current_clusters(clusters, current, n),
            robot_dist_cells=None if reads is not None else np.stack([distances_at(f, robots) for f in fields]),
            rng=rng,
        )
        return PosedDecision(problem, None, _Posed(frontiers, fields, passable, kept, cand))

    def _extent(self, passable: BoolGrid, resolution_m: float) -> tuple[Box | None, FarDistances | None]:
        """Where robots' distances are searched: the known passable box (None: the whole grid), and near/far
        fields where that box holds more than ``far_above_cells`` (None: exact fields, stopped once they
        reach every cell they are read at)."""
        cfg = self.distances
        factor = round(cfg.coarse_cell_m / resolution_m)
        if passable.size <= cfg.far_above_cells or factor < 2:
            return None, None
        box = mask_box(passable)
        if box is None or (box[1] - box[0]) * (box[3] - box[2]) <= cfg.far_above_cells:
            return box, None
        portals = finer = None
        if cfg.portal_sector_blocks:
            portals = self._portal_graph(passable.shape, factor)
            side = finer_side(factor)
            finer = self._portal_graph(passable.shape, side) if side is not None else None
        grid = coarse_grid(passable, factor, portals, finer)
        assert grid is not None  # the box holds a passable cell
        return box, FarDistances(max(1, round(cfg.exact_radius_m / resolution_m)), grid)

    def _portal_graph(self, shape: tuple[int, ...], factor: int) -> PortalGraph:
        """The portal graph kept for a grid of ``shape`` cells pooled into blocks of ``factor``."""
        key = (int(shape[0]), int(shape[1]), factor)
        graph = self._portals.get(key)
        if graph is None:
            cfg = self.distances
            blocks = (-(-key[0] // factor), -(-key[1] // factor))
            graph = PortalGraph(blocks, cfg.portal_sector_blocks, cfg.portal_spacing_blocks)
            self._portals[key] = graph
        return graph

    def assign(self, posed: PosedDecision) -> Assignment:
        """The global layer's answer to a posed decision: the planner's, or the owners the strategy fixed."""
        if posed.problem is None or posed.work is None:
            raise MrExploreError("assign() needs a posed decision with a problem; an ended one is already final")
        owners = posed.work.candidates.owners if posed.work.candidates is not None else None
        if owners is None:
            return self.planner.assign(posed.problem)
        out = np.full(posed.problem.n_robots, UNASSIGNED, dtype=np.int64)
        out[owners] = np.arange(len(owners))
        return Assignment(out)

    def finish(self, posed: PosedDecision, assignment: Assignment) -> Decision:
        """Layer 3: routes and paths for the robots of ``assignment`` (an answer to ``posed.problem``)."""
        if posed.problem is None or posed.work is None:
            raise MrExploreError("finish() needs a posed decision with a problem; an ended one is already final")
        p, w = posed.problem, posed.work

        def route(ik: tuple[int, int]) -> NDArray[np.int32]:
            i, k = ik
            return _NO_ROUTE if k == UNASSIGNED else self.route(i, k, p, w)

        # Each robot's route is its own search (the distance kernels release the GIL): on the threads where
        # the map is large enough for its searches to outweigh handing them over.
        items = [(i, int(k)) for i, k in enumerate(assignment.cluster_of_robot)]
        routes = map_threads(route, items) if w.passable.size >= _THREADED_ROUTES_CELLS else [route(x) for x in items]
        return _decision(p.state, w.frontiers, p.clusters, assignment, routes, w.fields, w.passable, p.robots_rc)

    def decide(
        self,
        state: StateGrid,
        robots_rc: NDArray[np.int32],
        resolution_m: float,
        blacklist: BoolGrid | None = None,
        current: Sequence[NDArray[np.int32]] | None = None,
        rng: np.random.Generator | None = None,
        frontiers: Frontiers | None = None,
    ) -> Decision:
        """Run layers 1-3 on the centre's grid and give every robot a goal, a route and a path
        (:meth:`pose`, the global planner's answer, :meth:`finish`); ``rng`` reaches the planner in the
        problem (a seeded generator for stochastic planners); ``frontiers`` as in :meth:`pose`."""
        posed = self.pose(state, robots_rc, resolution_m, blacklist, current, rng, frontiers, own_planner=True)
        if posed.problem is None:
            return posed.final  # type: ignore[return-value]
        return self.finish(posed, self.assign(posed))


def _denoised_un(frontiers: Frontiers, blacklist: BoolGrid | None, min_size: int) -> NDArray[np.int64]:
    """``(n, 2)`` F_un cells, row-major, less blacklisted cells and less 8-connected pieces under
    ``min_size`` cells (1: none): the noise rule of every strategy's candidates (the Mean-Shift ones'
    under ``preprocess.drop_specks``), so that every strategy ends on the same frontiers.

    Sparse: the pieces are the connected components of a graph on the frontier cells alone, each joined
    to its 8-neighbours found by binary search in the cells' sorted indices. Full-grid passes (copy,
    blacklist, labelling, indexing) cost 35 ms a decision on a KTH floor at 0.05 m, and labelling the
    cells' bounding box, which late in a mission is the whole floor, still 11 ms.
    """
    cells = frontiers.un_rc.astype(np.int64)
    if blacklist is not None and len(cells):
        cells = cells[~blacklist[cells[:, 0], cells[:, 1]]]
    if len(cells) == 0 or min_size <= 1:
        return cells
    width = int(cells[:, 1].max()) + 3  # a column either side: no neighbour wraps into the next row
    flat = cells[:, 0] * width + cells[:, 1] + 1  # increasing: the cells are row-major
    edges = []
    for step in (1, width - 1, width, width + 1):  # right and the three below: each pair once
        j = np.searchsorted(flat, flat + step)
        hit = j < len(flat)
        hit[hit] = flat[j[hit]] == flat[hit] + step
        edges.append(np.stack([np.flatnonzero(hit), j[hit]]))
    pairs = np.concatenate(edges, axis=1)
    graph = csr_matrix((np.ones(pairs.shape[1], np.int8), (pairs[0], pairs[1])), shape=(len(flat), len(flat)))
    _, piece = connected_components(graph, directed=False)
    return cells[np.bincount(piece)[piece] >= min_size]


@dataclass(frozen=True)
class _CoScanTasks:
    """CoScan's candidates' context: the tasks, robot-to-task distances, task-to-task distances (rows on
    demand), task labels, and the passable grid with the near/far extent where distances are estimated."""

    tasks_rc: NDArray[np.int32]
    d_robots: NDArray[np.float64]
    rows: TaskRows
    labels: NDArray[np.int64]
    passable: BoolGrid
    far: FarDistances | None

    def between(self, members: NDArray[np.int64]) -> NDArray[np.float64]:
        """``(k, k)`` distances between the tasks ``members``: rows of the whole matrix on a map searched
        exactly; on a near/far map, exact searches on the members' box grown by the exact radius (a cluster
        spans about ``2 delta_m``), rows of near/far fields for the pairs whose way leaves that box."""
        if self.far is None:
            return self.rows(members)[:, members]
        pts = self.tasks_rc[members].astype(np.int64)
        (r0, c0), (r1, c1) = pts.min(axis=0), pts.max(axis=0) + 1
        rows, cols = grown_slices((r0, r1, c0, c1), self.far.radius_cells, self.passable.shape)
        d = pairwise_distances(self.passable[rows, cols], pts - (rows.start, cols.start))
        gone = ~np.isfinite(d)
        if gone.any():  # a way round outside the box (d is symmetric, so both ends of a pair are here)
            lost = np.flatnonzero(gone.any(axis=1))
            d[lost] = np.where(gone[lost], self.rows(members[lost])[:, members], d[lost])
        return np.minimum(d, d.T)


class _NearFarRows:
    """Task-to-task distances on a near/far map, a row per task searched when first read (Lloyd reads its
    centroids' rows only: a whole matrix was 48 whole-floor searches a decision on a KTH floor at 0.05 m).

    Row i is task i's near/far field read at every task. Where the coarse grid leaves task j at ``inf``
    (behind a passage narrower than two blocks: common just after a floor's known box outgrows
    ``far_above_cells``), task j's own field read at task i is used, and where that is ``inf`` too, an exact
    search from task i stopped at the tasks still missing."""

    def __init__(self, passable: BoolGrid, tasks_rc: NDArray[np.int32], far: FarDistances) -> None:
        self.passable, self.tasks, self.far = passable, tasks_rc, far
        self.raw: dict[int, NDArray[np.float64]] = {}
        """Rows read off each task's own near/far field alone."""
        self.cache: dict[int, NDArray[np.float64]] = {}
        """Rows with their ``inf`` entries filled."""

    def _raw(self, idx: Sequence[int]) -> None:
        new = [i for i in dict.fromkeys(idx) if i not in self.raw]
        if new:
            for i, f in zip(new, self.far.fields(self.passable, self.tasks[new]), strict=True):
                self.raw[i] = f.at(self.tasks)

    def __call__(self, idx: NDArray[np.int64]) -> NDArray[np.float64]:
        new = [i for i in dict.fromkeys(np.asarray(idx).tolist()) if i not in self.cache]
        self._raw(new)
        self._raw([int(j) for i in new for j in np.flatnonzero(~np.isfinite(self.raw[i]))])
        for i in new:
            row = self.raw[i].copy()
            for j in np.flatnonzero(~np.isfinite(row)):
                row[j] = self.raw[int(j)][i]
            still = np.flatnonzero(~np.isfinite(row))
            if len(still):
                row[still] = distance_matrix(self.passable, self.tasks[i : i + 1], self.tasks[still])[0]
            self.cache[i] = row
        return np.stack([self.cache[int(i)] for i in idx]).reshape(len(idx), len(self.tasks))


@dataclass
class CoScanPipeline(ExplorationPipeline):
    """CoScan-2D: frontier tasks clustered by robot-seeded geodesic Lloyd iterations, clusters matched to
    robots by the Hungarian algorithm on geodesic distance, tasks visited in a 2-opt tour.

    Tasks come from F_un components of at least ``min_cluster_size`` cells (the other strategies' noise
    rule), so every strategy ends on the same frontiers. Where the known passable box holds more than
    ``far_above_cells`` (the KTH floors at 0.05 m), distances beyond ``exact_radius_m`` are estimated as
    for every other strategy, and only the task-to-task rows Lloyd reads are searched. Elsewhere the
    whole matrix between the tasks is searched, and the robots' searches stop once they reach the tasks.
    """

    coscan: CoScanConfig = field(default_factory=CoScanConfig)

    def candidates(self, q: CandidateQuery) -> CandidateSet:
        """Tasks sampled on F_un, capped by reachability, clustered by robot-seeded geodesic Lloyd
        iterations; each cluster's centre is its centroid task."""
        n = len(q.robots_rc)
        un = _denoised_un(q.frontiers, q.blacklist, self.preprocess.min_cluster_size)
        tasks = sample_tasks(un, self.coscan.task_spacing_m / q.resolution_m)
        if len(tasks) == 0:
            return CandidateSet(Clusters.empty(), "no_frontiers")
        passable = q.state == CellState.FREE
        cap = self.coscan.tasks_per_robot * n
        # On a near/far map a robot's task beyond the coarse grid costs a search of its own; a task that cannot
        # be among the kept ones needs none (the kept tasks and their distances stay the same).
        needed = partial(tasks_in_reach, robots_rc=q.robots_rc, tasks_rc=tasks, max_tasks=cap)
        d_robots = np.stack([distances_at(f, tasks) for f in q.fields(tasks, needed)])
        keep = cap_tasks(d_robots.min(axis=0), cap)
        if len(keep) == 0:
            return CandidateSet(Clusters.empty(), "no_reachable_frontiers")
        tasks, d_robots = tasks[keep], d_robots[:, keep]
        rows: TaskRows
        if q.far is None:
            # The whole matrix, made symmetric by the smaller of each pair's two float32 sums. Searching only
            # the rows Lloyd reads (about half) was tried: the rows then differ in the last place, and 27 of
            # 42 KTH missions parted, 2.8% [0.3, 6.5] more steps (docs/speed.md, "CoScan-2D's searches").
            d_tasks = distance_matrix(passable, tasks, tasks)
            d_tasks = np.minimum(d_tasks, d_tasks.T)  # equal up to float rounding; keep it symmetric
            rows = matrix_rows(d_tasks)
        else:
            rows = _NearFarRows(passable, tasks, q.far)
        lloyd = lloyd_clusters(tasks, rows, d_robots, self.coscan.delta_m / q.resolution_m, self.coscan.max_iterations)
        sizes = np.bincount(lloyd.labels, minlength=len(lloyd.centroids)).astype(np.int32)
        clusters = Clusters(tasks[lloyd.centroids], sizes, tasks, lloyd.labels.astype(np.int32))
        return CandidateSet(clusters, context=_CoScanTasks(tasks, d_robots, rows, lloyd.labels, passable, q.far))

    def route(self, i: int, k: int, problem: AssignmentProblem, work: _Posed) -> NDArray[np.int32]:
        """The cluster's tasks in a 2-opt tour from the robot."""
        assert work.candidates is not None
        c: _CoScanTasks = work.candidates.context
        members = np.flatnonzero(c.labels == k)
        order = two_opt_tour(c.d_robots[i, members], c.between(members))
        return c.tasks_rc[members[order]]


@dataclass
class NcmPipeline(ExplorationPipeline):
    """NeuralCoMapping re-implemented in 2D (Ye, Dong et al., CVPR 2022): its candidates are frontier
    cells clear of obstacles pooled to 0.4 m nodes (:mod:`~mrexplore.global_planning.ncm_nodes`), one node
    per cluster; its planner (:class:`~mrexplore.global_planning.learned.ncm_network.NcmPlanner`) lets
    every robot pick a node; robots drive to their node. Where no frontier cell keeps clear of obstacles
    (passages under 0.4 m wide) the plain F_un cells are pooled instead."""

    def own_reads(
        self, robots_rc: NDArray[np.int32], candidates: CandidateSet, resolution_m: float
    ) -> list[NDArray[np.int32]] | None:
        """Each robot's nodes within NCM's window (:data:`~mrexplore.global_planning.ncm_nodes.WINDOW_M`);
        all nodes for a robot with none there. NCM's planner allows robot i only the nodes it reaches
        within its window (:func:`in_window`, the test its input makes), or, where it reaches none there,
        every node it reaches. A search that settles the window's nodes has their exact distances; one
        that ends without settling them has searched the robot's whole component, so every node's distance
        is exact, and ``inf`` where unreachable."""
        centres = candidates.clusters.centers_rc
        near = in_window(robots_rc, centres, resolution_m)
        return [centres[row] if row.any() else centres for row in near]

    def candidates(self, q: CandidateQuery) -> CandidateSet:
        un = np.zeros(q.state.shape, dtype=bool)
        cells = _denoised_un(q.frontiers, q.blacklist, self.preprocess.min_cluster_size)
        un[cells[:, 0], cells[:, 1]] = True
        clear = ncm_frontier(q.state, Frontiers(un, q.frontiers.occ_mask), q.resolution_m)
        nodes = pool_nodes(clear if clear.any() else un, q.resolution_m)
        labels = np.arange(len(nodes), dtype=np.int32)
        return CandidateSet(Clusters(nodes, np.ones(len(nodes), np.int32), nodes, labels))


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
        self._plan = [_NO_ROUTE] * len(q.robots_rc)
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

    def route(self, i: int, k: int, problem: AssignmentProblem, work: _Posed) -> NDArray[np.int32]:
        """The robot's own route, in its order."""
        return problem.clusters.members_of(k)


_THREADED_ROUTES_CELLS = 2_000_000
"""Grids from which :meth:`ExplorationPipeline.finish` routes the robots on the threads (the KTH floors at
0.05 m: late in a 16-robot mission their local routes took 122 ms a decision on one thread under
cProfile, ``perf/profile_decision.py --strategy hier --robots 16 --from-coverage 0.5``)."""

CENTRE_COMMITMENT = 0.5
"""Default hysteresis of strategies whose goal is a cluster centre (measured on 6 maps x 2 seeds: utility
561 mean steps without, 414 with 0.5)."""


def _commitment(gp: GlobalPlanningConfig, default: float) -> float:
    return default if gp.commitment is None else gp.commitment


def _nearest(
    gp: GlobalPlanningConfig, pp: PreprocessConfig, lp: LocalPlanningConfig, policy: str | None
) -> ExplorationPipeline:
    commitment = _commitment(gp, CENTRE_COMMITMENT)
    return ExplorationPipeline("nearest", NearestPlanner(), pp, commitment=commitment, nearest_only=True)


def _utility(
    gp: GlobalPlanningConfig, pp: PreprocessConfig, lp: LocalPlanningConfig, policy: str | None
) -> ExplorationPipeline:
    return ExplorationPipeline("utility", UtilityPlanner(gp), pp, commitment=_commitment(gp, CENTRE_COMMITMENT))


def _hier_heuristic(
    gp: GlobalPlanningConfig, pp: PreprocessConfig, lp: LocalPlanningConfig, policy: str | None
) -> ExplorationPipeline:
    # The paper's three layers with explore_lite's cost as the global affinity. No hysteresis by default: a
    # route already commits the robot to a sequence of targets (measured on 6 maps x 2 seeds: 442 mean
    # steps without, 480 with commitment 0.5).
    return ExplorationPipeline("hier-heuristic", UtilityPlanner(gp), pp, LocalRouter(lp, pp), _commitment(gp, 1.0))


def _hier(
    gp: GlobalPlanningConfig, pp: PreprocessConfig, lp: LocalPlanningConfig, policy: str | None
) -> ExplorationPipeline:
    # The paper's three layers with the learned global layer (mGNN affinities, Hungarian decoding); torch is
    # imported here only, so that every other strategy runs without it.
    from pathlib import Path

    from mrexplore.global_planning.learned.checkpoint import load_policy
    from mrexplore.global_planning.learned.policy import LearnedPlanner

    loaded = load_policy(Path(policy) if policy else None)
    info = {"path": str(loaded.path), "sha256": loaded.sha256, "code_version": str(loaded.meta["code_version"])}
    planner = LearnedPlanner(loaded.net, gp)
    return ExplorationPipeline("hier", planner, pp, LocalRouter(lp, pp), _commitment(gp, 1.0), policy=info)


def _ncm_factory(
    name: str, sample: bool = False, match: bool = False
) -> Callable[[GlobalPlanningConfig, PreprocessConfig, LocalPlanningConfig, str | None], ExplorationPipeline]:
    def make(
        gp: GlobalPlanningConfig, pp: PreprocessConfig, lp: LocalPlanningConfig, policy: str | None
    ) -> ExplorationPipeline:
        # NeuralCoMapping re-implemented: no hysteresis (it replans every robot every decision), no local
        # layer (each robot drives to its node); torch is imported here only, as for hier.
        from pathlib import Path

        from mrexplore.global_planning.learned.checkpoint import load_ncm_policy
        from mrexplore.global_planning.learned.ncm_network import NcmPlanner

        loaded = load_ncm_policy(Path(policy) if policy else None)
        info = {"path": str(loaded.path), "sha256": loaded.sha256, "code_version": str(loaded.meta["code_version"])}
        return NcmPipeline(name, NcmPlanner(loaded.net, sample=sample, name=name, match=match), pp, policy=info)

    return make


def _coscan(
    gp: GlobalPlanningConfig, pp: PreprocessConfig, lp: LocalPlanningConfig, policy: str | None
) -> ExplorationPipeline:
    return CoScanPipeline("coscan", GeodesicPlanner(), pp)


def _oracle(
    gp: GlobalPlanningConfig, pp: PreprocessConfig, lp: LocalPlanningConfig, policy: str | None
) -> ExplorationPipeline:
    return OraclePipeline("oracle", NearestPlanner(), pp, goals_are_frontiers=False)


STRATEGIES: dict[
    str, Callable[[GlobalPlanningConfig, PreprocessConfig, LocalPlanningConfig, str | None], ExplorationPipeline]
] = {
    "hier": _hier,
    "hier-heuristic": _hier_heuristic,
    "nearest": _nearest,
    "utility": _utility,
    "coscan": _coscan,
    "ncm": _ncm_factory("ncm"),
    "ncm-sampled": _ncm_factory("ncm-sampled", sample=True),
    "ncm-matched": _ncm_factory("ncm-matched", match=True),
    "oracle": _oracle,
}
"""Strategy name -> factory of its pipeline (the last argument: a policy file for learned planners, None
for the shipped one)."""

LEARNED = {"hier": "hier", "ncm": "ncm", "ncm-sampled": "ncm", "ncm-matched": "ncm"}
"""Strategies with a network, which ``policy`` selects -> the kind of policy file they read (NCM's three
decodings share one)."""


def policy_for(name: str, policy: str | None) -> str | None:
    """The policy file strategy ``name`` runs, from a ``--policy`` value: ``FILE`` (for every learned
    strategy of the run) or ``KIND=FILE[,KIND=FILE]`` with KIND ``hier`` or ``ncm``; None: the shipped one.

    Examples
    --------
    >>> policy_for("ncm-sampled", "hier=a.pt,ncm=b.pt"), policy_for("hier", "ncm=b.pt"), policy_for("hier", "c.pt")
    ('b.pt', None, 'c.pt')
    """
    kind = LEARNED.get(name.removesuffix(NO_LOCAL_SUFFIX))
    if policy is None or kind is None:
        return None
    kinds = set(LEARNED.values())
    parts = [p.partition("=") for p in policy.split(",")]
    if not all(sep and k in kinds for k, sep, _ in parts):
        return policy  # a plain path (it may hold '=' or ',' of its own)
    files = {k: v for k, _, v in parts}
    return files.get(kind) or None


def strategy_names() -> list[str]:
    return list(STRATEGIES)


def make_strategy(
    name: str,
    global_cfg: GlobalPlanningConfig | None = None,
    preprocess_cfg: PreprocessConfig | None = None,
    local_cfg: LocalPlanningConfig | None = None,
    local: bool = True,
    policy: str | None = None,
    coscan_cfg: CoScanConfig | None = None,
) -> ExplorationPipeline:
    """The pipeline called ``name``; unknown names raise a one-line error listing the choices.

    ``local=False`` (or a ``-nolocal`` suffix on the name) removes the local layer: robots go to cluster
    centres, for ablations; the pipeline's name then carries the suffix. ``policy`` is the weights file
    of a learned strategy, or ``KIND=FILE`` pairs (:func:`policy_for`; None: the policy shipped in the
    package); ``coscan_cfg`` sets CoScan-2D's task sampling and clustering.
    """
    if name.endswith(NO_LOCAL_SUFFIX) and name.removesuffix(NO_LOCAL_SUFFIX) in STRATEGIES:
        name, local = name.removesuffix(NO_LOCAL_SUFFIX), False
    if name not in STRATEGIES:
        raise MrExploreError(f"unknown strategy {name!r}; choose one of {', '.join(STRATEGIES)}")
    pipeline = STRATEGIES[name](
        global_cfg or GlobalPlanningConfig(),
        preprocess_cfg or PreprocessConfig(),
        local_cfg or LocalPlanningConfig(),
        policy_for(name, policy),
    )
    if not local and pipeline.local is not None:
        pipeline.local = None
        pipeline.name += NO_LOCAL_SUFFIX
    pipeline.distances = global_cfg or GlobalPlanningConfig()
    if isinstance(pipeline, CoScanPipeline) and coscan_cfg is not None:
        pipeline.coscan = coscan_cfg
    return pipeline
