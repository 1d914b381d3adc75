"""The base pipeline every strategy shares: layer 1 at the centre, the robots' distances, the global
planner's problem and answer, and layer 3's routes and paths; a strategy that chooses its own candidates
overrides the seam (:meth:`ExplorationPipeline.candidates`, ``route``, ``own_reads``, ``planning_state``)."""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from mrexplore.config import GlobalPlanningConfig, PreprocessConfig, SimConfig
from mrexplore.global_planning.protocol import UNASSIGNED, Assignment, AssignmentProblem, GlobalPlanner
from mrexplore.local_planning.router import LocalRouter
from mrexplore.maps.boxes import Box, mask_box
from mrexplore.maps.ground_truth import GroundTruthMap
from mrexplore.paths.distance_field import distance_fields, distances_at, nearest_fields
from mrexplore.paths.far_field import coarse_grid, finer_side, path_to
from mrexplore.paths.portals import PortalGraph
from mrexplore.pipeline.decision import (
    NO_GOAL,
    NO_ROUTE,
    CandidateQuery,
    CandidateSet,
    Decision,
    DecisionInput,
    FarDistances,
    PosedDecision,
    PosedWork,
    RobotField,
)
from mrexplore.preprocessing.clustering import Clusters, cluster_frontiers, split_for_team
from mrexplore.preprocessing.denoise import denoised_frontier_cells
from mrexplore.preprocessing.frontiers import Frontiers, detect_frontiers
from mrexplore.runtime.threads import map_threads
from mrexplore.runtime.timing import PhaseTimes, timed
from mrexplore.types import BoolGrid, CellState, MrExploreError, StateGrid

__all__ = ["ExplorationPipeline"]

_THREADED_ROUTES_CELLS = 2_000_000
"""Grids from which :meth:`ExplorationPipeline.finish` routes the robots on the threads (the KTH floors at
0.05 m, where a 16-robot mission's local routes late on cost a whole decision's worth on one thread)."""


def _ended(state: StateGrid, frontiers: Frontiers, clusters: Clusters, n: int, reason: str) -> Decision:
    """A decision that ends the mission: no goal, route or path for anyone."""
    none = [NO_ROUTE] * n
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
            paths.append(NO_ROUTE)
    return Decision(state, frontiers, clusters, assignment, goals, routes, paths, None)


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
    predictor: dict[str, str] | None = None
    """Where a predictive strategy's map predictor came from: ``{"path", "sha256"}`` (path ``none``: every
    unknown cell taken for free); None: the strategy predicts nothing."""
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
    timer: PhaseTimes | None = field(default=None, repr=False, compare=False)
    """Where a benchmark's timing hooks record the decision's phases (candidates, distances, assignment,
    routes); None: not timed."""
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
        return [NO_ROUTE] * len(robots_rc) if self.nearest_only else None

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
        un_rc = denoised_frontier_cells(q.frontiers, q.blacklist, speck).astype(np.int32)
        cap = self.preprocess.bandwidth_max_m
        clusters = cluster_frontiers(un_rc, self.preprocess, None, None if cap is None else cap / q.resolution_m)
        if self.preprocess.split_for_team:
            pp = self.preprocess
            shortest = math.ceil(round(pp.split_min_frontier_m / q.resolution_m, 6))  # metres to members
            clusters = split_for_team(clusters, len(q.robots_rc), pp.min_cluster_size, shortest)
        return CandidateSet(clusters)

    def route(self, i: int, k: int, problem: AssignmentProblem, work: PosedWork) -> NDArray[np.int32]:
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
    def pose(self, inp: DecisionInput, own_planner: bool = False) -> PosedDecision:
        """Layer 1 and the distances: the :class:`PosedDecision` a global planner answers (or the end).

        ``own_planner``: the problem goes to this pipeline's own planner only (:meth:`decide`), so the
        searches may stop where it stops reading (:meth:`own_reads`, :attr:`stop_searches`).
        """
        state, robots_rc, resolution_m, current = inp.state, inp.robots_rc, inp.resolution_m, inp.current
        frontiers = inp.frontiers if inp.frontiers is not None else detect_frontiers(state)
        planning = self.planning_state(state)
        begin = getattr(self.planner, "begin", None)
        if own_planner and begin is not None:
            # A planner that reads more of the grid than the problem holds (a map prediction) starts on it now,
            # beside the clustering and the distance searches below.
            begin(planning, resolution_m)
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

        with timed(self.timer, "candidates"):
            cand = self.candidates(
                CandidateQuery(state, frontiers, inp.blacklist, robots_rc, fields_now, current, resolution_m, far)
            )
        clusters = cand.clusters
        n = len(robots_rc)
        if cand.ended is not None:
            return PosedDecision(None, _ended(planning, frontiers, clusters, n, cand.ended))
        if len(clusters) == 0:
            return PosedDecision(None, _ended(planning, frontiers, clusters, n, "no_frontiers"))
        own = goals if self.commitment < 1 else []  # a robot's own goal is read for hysteresis only
        barring = any(b is not None for b in inp.barred or ())  # every centre's distance is read then
        stop = self.stop_searches and own_planner and far is None and not computed and not barring
        reads = self.own_reads(robots_rc, cand, resolution_m) if stop else None
        with timed(self.timer, "distances"):
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
        for i, barred in enumerate(inp.barred or ()):
            if barred is not None:
                dist[i, barred[clusters.centers_rc[:, 0], clusters.centers_rc[:, 1]]] = np.inf
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
            rng=inp.rng,
        )
        return PosedDecision(problem, None, PosedWork(frontiers, fields, passable, kept, cand))

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
            with timed(self.timer, "assignment"):
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
            return NO_ROUTE if k == UNASSIGNED else self.route(i, k, p, w)

        # Each robot's route is its own search (the distance kernels release the GIL): on the threads where
        # the map is large enough for its searches to outweigh handing them over.
        items = [(i, int(k)) for i, k in enumerate(assignment.cluster_of_robot)]
        with timed(self.timer, "routes"):
            threaded = w.passable.size >= _THREADED_ROUTES_CELLS
            routes = map_threads(route, items) if threaded else [route(x) for x in items]
        return _decision(p.state, w.frontiers, p.clusters, assignment, routes, w.fields, w.passable, p.robots_rc)

    def decide(self, inp: DecisionInput) -> Decision:
        """Run layers 1-3 on the centre's grid and give every robot a goal, a route and a path
        (:meth:`pose`, the global planner's answer, :meth:`finish`)."""
        posed = self.pose(inp, own_planner=True)
        if posed.final is not None:
            return posed.final
        return self.finish(posed, self.assign(posed))
