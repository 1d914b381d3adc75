"""A search at run time: few candidate assignments, each run forward in the world the centre knows.

At each decision the centre gathers a few distinct assignments (``hier-plan``'s, the learned planner's own, the
team plan's and explore_lite's utility matching, :func:`search_candidates`) and, where they differ, runs each
forward in a rollout simulator built from its own grid alone (:class:`RolloutSearch`): every cell it knows free
stays free, every other cell is a wall, each robot starts where it stands with the centre's grid as its belief.
``hier-plan``'s planner decides in the rollouts; each candidate is scored by the steps until no frontier is left
(a rollout cut at the horizon adds the team plan's makespan over what is left then), and the fewest wins, ties
going to ``hier-plan``'s own. A robot that leaves a pocket half-seen pays for it in the rollout, when someone
must come back for it: this is what the search sees that a one-step assignment does not.

Nothing the centre does not know enters the search (no ground truth, no robot's own grid), so the same planner
runs in the simulator's missions and on the ROS 2 centre. It costs a few rollouts per decision; the strategy
therefore ships under its own name, ``hier-search``, with its time per decision stated against the time a robot
drives between decisions (docs/learned.md, "A search at run time").
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np
from numpy.typing import NDArray

from mrexplore.config import GlobalPlanningConfig, MissionConfig, SimConfig
from mrexplore.global_planning.classical import UtilityPlanner
from mrexplore.global_planning.learned.policy import LearnedPlanner
from mrexplore.global_planning.protocol import UNASSIGNED, Assignment, AssignmentProblem, GlobalPlanner
from mrexplore.global_planning.team_plan import PlanCostPlanner, TeamPlanPlanner
from mrexplore.maps.frame import GridFrame
from mrexplore.maps.ground_truth import GroundTruthMap
from mrexplore.mission.loop import Mission, MissionSpec
from mrexplore.pipeline.base import ExplorationPipeline
from mrexplore.pipeline.registry import PipelineConfigs
from mrexplore.pipeline.strategies import hier
from mrexplore.sim.belief import logit
from mrexplore.sim.world import ExplorationSim
from mrexplore.types import CellState, StateGrid

__all__ = [
    "rollout_world",
    "seed_beliefs",
    "search_candidates",
    "RolloutSearch",
    "SearchPlanner",
    "SearchPipeline",
    "hier_search",
]


def rollout_world(state: StateGrid, resolution_m: float, robots_rc: NDArray[np.integer]) -> GroundTruthMap:
    """The world a rollout runs in: the centre's grid ``state`` ``(H, W) uint8`` with every cell it knows free
    free, and the robots' cells ``robots_rc`` ``(n, 2)``; every other cell (occupied or unknown) a wall.

    Examples
    --------
    >>> s = np.array([[0, 2, 1, 2]], dtype=np.uint8)  # FREE, UNKNOWN, OCCUPIED, UNKNOWN
    >>> rollout_world(s, 0.1, np.array([[0, 3]])).occupied.tolist()
    [[False, True, True, False]]
    """
    h, w = state.shape
    walls = state != CellState.FREE
    walls[robots_rc[:, 0], robots_rc[:, 1]] = False
    return GroundTruthMap(walls, GridFrame(h, w, resolution_m, (0.0, 0.0)), "rollout")


def seed_beliefs(sim: ExplorationSim, state: StateGrid) -> None:
    """Every robot of ``sim`` believes the centre's grid ``state``: its free and occupied cells observed, at
    the clamping log-odds of the sim's sensor, its unknown cells unknown (the team's record of them too)."""
    s = sim.cfg.sensor
    known = state != CellState.UNKNOWN
    lo = np.where(state == CellState.OCCUPIED, logit(s.p_clamp_max), 0.0)
    lo = np.where(state == CellState.FREE, logit(s.p_clamp_min), lo).astype(np.float32)
    h, w = state.shape
    for b in sim.beliefs:
        b.log_odds[:] = lo
        b.observed[:] = known
        b.note_window((0, h, 0, w))
    sim.team_observed[:] = known


def search_candidates(problem: AssignmentProblem, planners: tuple[GlobalPlanner, ...]) -> list[NDArray[np.int64]]:
    """The distinct assignments of ``planners`` to ``problem``, in their order (the first is kept on ties)."""
    unique: dict[tuple[int, ...], NDArray[np.int64]] = {}
    for planner in planners:
        a = planner.assign(problem).cluster_of_robot
        unique.setdefault(tuple(int(v) for v in a), np.asarray(a, dtype=np.int64))
    return list(unique.values())


def _matched(target: AssignmentProblem, source: AssignmentProblem, cand: NDArray[np.int64]) -> NDArray[np.int64]:
    """``cand`` (an answer to ``source``) as an answer to ``target``: each cluster by its centre, the nearest
    of ``target``'s centres where none is the same cell."""
    out = np.full(target.n_robots, UNASSIGNED, dtype=np.int64)
    if target.n_clusters == 0:
        return out
    to = target.clusters.centers_rc.astype(np.float64)
    for i, k in enumerate(cand):
        if k != UNASSIGNED:
            c = source.clusters.centers_rc[int(k)]
            out[i] = int(np.argmin(((to - c) ** 2).sum(axis=1)))
    return out


@dataclass
class RolloutSearch:
    """Scores candidate assignments by running them forward in :func:`rollout_world`.

    ``continuation``: the pipeline deciding in the rollouts after the candidate's first decision. ``sim_cfg``:
    the robots' sensor and motion (the team size is the problem's). ``horizon_steps``: the rollouts' step budget;
    a rollout cut there is scored by its steps plus the team plan's estimate of the steps it still needs.
    """

    continuation: ExplorationPipeline
    sim_cfg: SimConfig = field(default_factory=SimConfig)
    horizon_steps: int = 400
    replan_every_steps: int = 25
    plan: TeamPlanPlanner = field(default_factory=TeamPlanPlanner, repr=False)
    """The team plan whose makespan estimates what a rollout cut at the horizon still needs."""

    def scores(self, problem: AssignmentProblem, candidates: list[NDArray[np.int64]]) -> NDArray[np.float64]:
        """Minus the steps each candidate's rollout takes until no frontier is left; a rollout still running at
        ``horizon_steps`` adds the team plan's makespan over what is left then (:meth:`_to_go`)."""
        world = rollout_world(problem.state, problem.resolution_m, problem.robots_rc)
        mission_cfg = MissionConfig(
            max_steps=self.horizon_steps, replan_every_steps=self.replan_every_steps, baseline_bytes=False
        )
        sim_cfg = replace(self.sim_cfg, robots=problem.n_robots)
        spec = MissionSpec(world, self.continuation, sim_cfg, mission_cfg, 0, starts_rc=problem.robots_rc)
        m = Mission(spec, progress=False)
        seed_beliefs(m.sim, problem.state)
        out = np.full(len(candidates), -float(self.horizon_steps))
        if not m.advance():
            return out
        posed = m.pose()
        if posed is None:  # the centre's grid holds no reachable frontier: every candidate ends at once
            return np.zeros(len(candidates))
        snap = m.snapshot()
        for j, cand in enumerate(candidates):
            m.restore(snap)
            m.commit(Assignment(_matched(posed, problem, cand)))
            while m.advance():
                m.decide()
            out[j] = -float(m.steps) - (self._to_go(m) if m.done_reason == "max_steps" else 0.0)
        return out

    def _to_go(self, m: Mission) -> float:
        """Steps a rollout cut at the horizon still needs, estimated: the team plan's makespan over the clusters
        left (the time until the last known frontier is reached), at the robots' speed."""
        end = m.pose()
        if end is None or end.n_clusters == 0:
            return 0.0
        return self.plan.plan(end).makespan / self.sim_cfg.motion.step_m


@dataclass
class SearchPlanner:
    """``hier-plan``'s assignment (the learned cost under the team plan's), unless a rollout in the centre's known
    world (:class:`RolloutSearch`) finds another candidate that leaves no frontier sooner: the learned planner's
    own, the team plan's or utility's (:func:`search_candidates`). ``search``: the rollouts (None until the
    pipeline sets them)."""

    base: LearnedPlanner
    cfg: GlobalPlanningConfig = field(default_factory=GlobalPlanningConfig)
    name: str = "search"
    lead: PlanCostPlanner = field(init=False, repr=False)
    """The learned cost under the team plan's (``hier-plan``'s planner): the first candidate, kept on ties, and
    the planner deciding in the rollouts."""
    search: RolloutSearch | None = None
    last_candidates: list[NDArray[np.int64]] = field(default_factory=list, repr=False)
    """The candidates of the last decision, :attr:`lead`'s first."""
    last_scores: NDArray[np.float64] = field(default_factory=lambda: np.zeros(0), repr=False)
    """Their rollouts' scores (empty where there was one candidate only)."""
    _others: tuple[GlobalPlanner, ...] = field(init=False, repr=False)

    def __post_init__(self) -> None:
        self.lead = PlanCostPlanner(self.base, self.cfg)
        self._others = (self.base, TeamPlanPlanner(self.cfg), UtilityPlanner(self.cfg))

    def begin(self, state: StateGrid, resolution_m: float) -> None:
        self.base.begin(state, resolution_m)

    def assign(self, problem: AssignmentProblem) -> Assignment:
        if problem.n_clusters == 0:
            return Assignment(np.full(problem.n_robots, UNASSIGNED, dtype=np.int64))
        cands = search_candidates(problem, (self.lead, *self._others))
        self.last_candidates, self.last_scores = cands, np.zeros(0)
        if len(cands) == 1 or self.search is None:
            return Assignment(cands[0])
        self.last_scores = self.search.scores(problem, cands)
        return Assignment(cands[int(np.argmax(self.last_scores))])


class SearchPipeline(ExplorationPipeline):
    """A pipeline whose planner is a :class:`SearchPlanner`; its rollouts run a copy of this pipeline with the
    planner's :attr:`~SearchPlanner.lead` deciding (local layer or not, as this one). A mission's
    :meth:`prepare` gives the rollouts the team's sensor and motion (the ground truth it is handed is not
    read)."""

    def prepare(self, truth: GroundTruthMap, starts_rc: NDArray[np.integer], sim: SimConfig) -> None:
        search = self._search()
        search.sim_cfg = sim

    def _search(self) -> RolloutSearch:
        planner = self.planner
        assert isinstance(planner, SearchPlanner)
        if planner.search is None:
            planner.search = RolloutSearch(
                self._continuation(),
                horizon_steps=planner.cfg.search_horizon_steps,
                plan=TeamPlanPlanner(planner.cfg),
            )
        return planner.search

    def _continuation(self) -> ExplorationPipeline:
        planner = self.planner
        assert isinstance(planner, SearchPlanner)
        return ExplorationPipeline(
            self.name + "-rollout",
            planner.lead,
            self.preprocess,
            self.local,
            self.commitment,
            distances=self.distances,
        )

    def __setattr__(self, name: str, value: object) -> None:
        super().__setattr__(name, value)
        # The rollouts follow this pipeline's local layer (make_strategy's -nolocal removes it after building).
        planner = self.__dict__.get("planner")
        if name == "local" and isinstance(planner, SearchPlanner) and planner.search is not None:
            planner.search.continuation.local = value  # type: ignore[assignment]


def hier_search(c: PipelineConfigs, policy: str | None) -> ExplorationPipeline:
    """``hier-search``: hier's pipeline, its assignment searched among few candidates by rollouts in the
    centre's known world."""
    base = hier(c, policy)
    learned = base.planner
    assert isinstance(learned, LearnedPlanner)
    pipeline = SearchPipeline(
        "hier-search",
        SearchPlanner(learned, c.global_),
        base.preprocess,
        base.local,
        base.commitment,
        policy=base.policy,
        distances=base.distances,
    )
    pipeline.predictor = base.predictor
    pipeline._search().sim_cfg = c.sim
    return pipeline
