"""One exploration mission: simulator + strategy, the replanning events, termination and measures.

Replanning is the same for every strategy. A decision (the whole team re-assigned at the centre) is
taken when a robot reached its goal, when its path is blocked, when its goal is no longer a frontier
and ``min_replan_steps`` passed since the last decision, and at least every ``replan_every_steps``
steps. A robot with a local route (paper IV-C) first moves on to the next target of its route that is
still a frontier; only when none is left does its goal count as reached. The mission ends as the
paper's: no cluster of the minimum size left, or none reachable; or when the step budget runs out
(``max_steps``, never success), or when every robot has failed (``robots_lost``).

Faults (:class:`~mrexplore.config.FaultConfig`) act here: a failed robot stops for good and sends
nothing; the centre assigns only to robots it heard from within ``silence_rounds`` rounds, at the cell
of their last message that arrived, and a robot whose assigned path starts elsewhere plans its own way
there; a restarting centre drops its maps and blacklist. A robot out of radio range neither sends nor
receives: it finishes its route, then explores on its own grid (nearest frontier) and, with none
left there, drives back into range to sync. Assignments
reach every robot in range (they are a few bytes, resent until acknowledged); the loss of map
messages and of their acknowledgements is simulated by the link (:class:`TeamLink`).
"""

from __future__ import annotations

import copy
import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mrexplore.config import FaultConfig, MissionConfig, SimConfig
from mrexplore.global_planning.protocol import UNASSIGNED, Assignment, AssignmentProblem
from mrexplore.maps.ground_truth import GroundTruthMap
from mrexplore.paths.astar import astar_path
from mrexplore.paths.distance_field import descend_path, distance_fields, distances_at
from mrexplore.pipeline import NO_GOAL, NO_ROUTE, Decision, DecisionInput, ExplorationPipeline, PosedDecision
from mrexplore.preprocessing.frontiers import close_unknown_holes, detect_frontiers
from mrexplore.preprocessing.link import TeamLink
from mrexplore.preprocessing.transmission import LinkStatus
from mrexplore.runtime.memory import peak_mb, reset_peak
from mrexplore.runtime.progress import Progress
from mrexplore.runtime.timing import timed
from mrexplore.sim.belief import classify
from mrexplore.sim.measures import EpisodeMeasures, lower_bound_steps
from mrexplore.sim.starts import draw_starts
from mrexplore.sim.world import ExplorationSim, StepResult
from mrexplore.team.goal_book import GoalBook, KeepsGoals, decision_due
from mrexplore.types import BoolGrid, CellState, MrExploreError

__all__ = [
    "Mission",
    "MissionSpec",
    "MissionResult",
    "MissionSnapshot",
    "FaultSchedule",
    "MeasuresRecorder",
    "run_mission",
    "Observer",
    "Centre",
]

Observer = Callable[[ExplorationSim, Decision | None, NDArray[np.int32], LinkStatus], None]
"""Called after the first scan and after every step with the sim, the latest decision, the goals and
what the centre knows of each robot."""

Centre = Callable[[DecisionInput], Decision]
"""Who answers a decision: the strategy's own pipeline in this process (the default), or a centre elsewhere
that answers the same input from the messages it received itself (``mrexplore ros2 sim --lockstep``)."""


@dataclass
class MissionResult:
    """Outcome of one mission."""

    measures: EpisodeMeasures
    coverage_curve: NDArray[np.float64]
    """``(steps + 1,) float64`` team coverage after each step (index 0: after the first scan)."""
    starts_rc: NDArray[np.int32]
    final_state: NDArray[np.uint8] = field(repr=False)
    """``(H, W) uint8`` the centre's grid at the last decision."""
    sim: ExplorationSim = field(repr=False)


@dataclass(frozen=True)
class MissionSpec:
    """What one mission is made of: the map, the strategy, the settings, the seed and, where given, the
    starts. :class:`Mission`, :func:`run_mission` and :class:`~mrexplore.mission.decision_env.DecisionEnv` are
    built from it."""

    truth: GroundTruthMap
    strategy: ExplorationPipeline
    sim_cfg: SimConfig = field(default_factory=SimConfig)
    mission_cfg: MissionConfig = field(default_factory=MissionConfig)
    seed: int = 0
    """Seeds the starts, the simulator and the planners (one generator); lost messages draw from a second."""
    starts_rc: NDArray[np.integer] | None = None
    """``(n_robots, 2) int`` start cells; drawn close together from ``seed`` when None."""


class FaultSchedule:
    """When the mission's scheduled faults strike (:class:`~mrexplore.config.FaultConfig`): robots that fail
    for good at a step, and centre restarts. Lost messages and the radio range act in the link and the
    replanning loop."""

    def __init__(self, faults: FaultConfig, n_robots: int) -> None:
        for robot, _ in faults.robot_failures:
            if robot >= n_robots:
                raise MrExploreError(
                    f"robot failure names robot {robot}, but the team has robots 0..{n_robots - 1}; "
                    "pass an id of the team"
                )
        self._restarts = sorted(faults.centre_restarts)
        self._failures = sorted((step, robot) for robot, step in faults.robot_failures)

    def failures_due(self, step: int) -> list[int]:
        """The robots that fail by ``step`` and have not failed yet, in the order they fail."""
        due = []
        while self._failures and self._failures[0][0] <= step:
            due.append(self._failures.pop(0)[1])
        return due

    def restarts_due(self, step: int) -> int:
        """How many centre restarts fall due by ``step`` (each counted once)."""
        n = 0
        while self._restarts and self._restarts[0] <= step:
            self._restarts.pop(0)
            n += 1
        return n


@dataclass
class MeasuresRecorder:
    """What a mission records as it goes, for :class:`~mrexplore.sim.measures.EpisodeMeasures`."""

    curve: list[float]
    """Team coverage after the first scan and after every step."""
    plan_ms: list[float] = field(default_factory=list)
    """The centre's time at each decision, ms."""
    onboard_ms: list[float] = field(default_factory=list)
    """Each robot's on-board work in each round it sent a map, ms (see :class:`TeamLink`)."""

    def measures(
        self,
        truth: GroundTruthMap,
        sim: ExplorationSim,
        sim_cfg: SimConfig,
        starts_rc: NDArray[np.int32],
        wall_s: float,
        done_reason: str,
        transmission: dict[str, Any],
    ) -> EpisodeMeasures:
        """The episode's measures so far (``transmission``: the link's byte and IoU fields)."""
        return EpisodeMeasures.from_run(
            np.asarray(self.curve),
            sim.robot_coverage,
            sim.path_len_m,
            self.plan_ms,
            wall_s,
            done_reason,
            transmission,
            lower_bound_steps(~truth.occupied, sim.explorable, starts_rc, truth.resolution_m, sim_cfg),
            int((~sim.alive).sum()),
            peak_mb(),
            self.onboard_ms,
        )


def _goal_still_frontier(team_observed: np.ndarray, goal: NDArray[np.int32]) -> bool:
    """Whether a goal cell still has an unobserved 4-neighbour (cheap per-step test, no full detection)."""
    r, c = int(goal[0]), int(goal[1])
    H, W = team_observed.shape
    for rr, cc in ((r - 1, c), (r + 1, c), (r, c - 1), (r, c + 1)):
        if 0 <= rr < H and 0 <= cc < W and not team_observed[rr, cc]:
            return True
    return False


@dataclass(frozen=True)
class MissionSnapshot:
    """A mission's whole state at one moment (simulator, link, centre, routes, generator), to try
    something forward and come back (:meth:`Mission.snapshot`, :meth:`Mission.restore`)."""

    state: dict[str, object] = field(repr=False)


_NOT_COPIED = ("spec", "strategy", "observer", "_bar", "truth", "centre")
"""Shared, read-only during a mission (the ground truth) or owned by the caller: never snapshotted."""


class Mission(KeepsGoals):
    """One exploration mission that can be stepped decision by decision.

    The one replanning loop of the package: :func:`run_mission`, the trainer's rollouts, the lookahead
    expert and the benchmarks all drive this object. :meth:`advance` runs simulation steps until the team needs
    a decision (True) or the mission ends (False); the decision is then taken whole by :meth:`decide`,
    or in two halves, :meth:`pose` (the centre's problem) and :meth:`commit` (any assignment), which is
    how a learned planner is trained.

    Examples
    --------
    >>> from mrexplore.config import MapConfig
    >>> from mrexplore.maps.loaders import load_map
    >>> from mrexplore.pipeline import make_strategy
    >>> truth = load_map("generated:0", MapConfig(resolution_m=0.2))
    >>> m = Mission(MissionSpec(truth, make_strategy("utility"), seed=0), progress=False)
    >>> while m.advance():
    ...     decision = m.decide()
    >>> m.done_reason in ("no_frontiers", "no_reachable_frontiers", "max_steps")
    True
    """

    def __init__(
        self,
        spec: MissionSpec,
        observer: Observer | None = None,
        progress: bool | None = None,
        centre: Centre | None = None,
    ) -> None:
        """``progress``: show a coverage bar; default: only when stderr is a terminal. ``centre``: who answers
        :meth:`decide` (default: ``spec.strategy.decide``)."""
        reset_peak()  # the episode's peak memory, from here (the map is already loaded)
        self.spec = spec
        self.sim_cfg = sim_cfg = spec.sim_cfg
        self.mission_cfg = mission_cfg = spec.mission_cfg
        self.truth = truth = spec.truth
        self.strategy = strategy = spec.strategy
        self.observer = observer
        self.centre = centre if centre is not None else strategy.decide
        self.rng = rng = np.random.default_rng(spec.seed)
        starts_rc = spec.starts_rc
        if starts_rc is None:
            starts_rc = draw_starts(truth, sim_cfg.robots, sim_cfg.start_spread_m, rng)
        starts: NDArray[np.int32] = np.asarray(starts_rc, dtype=np.int32)
        if len(starts) != sim_cfg.robots:
            raise MrExploreError(f"starts must give one cell per robot ({sim_cfg.robots}), got {len(starts)}")
        faults = mission_cfg.faults
        self.faults = FaultSchedule(faults, sim_cfg.robots)
        self.starts_rc = starts
        self._t0 = time.perf_counter()
        strategy.prepare(truth, starts, sim_cfg)
        self.sim = sim = ExplorationSim(truth, starts, sim_cfg, rng)
        n = sim.n_robots
        self.book = GoalBook(n, truth.shape)
        """Each robot's goal and route, and the team's blacklist: the rules the real team's centre keeps too."""
        self.record = MeasuresRecorder([sim.coverage])
        self.last_decision_step = -mission_cfg.replan_every_steps
        self.decision: Decision | None = None
        # Every strategy plans on the grid the centre rebuilds from the robots' sparse frontier maps (IV-A).
        # Lost messages draw from a generator of their own, so that a run without faults is the same run.
        self.link = TeamLink(
            n,
            truth.shape,
            strategy.preprocess,
            sim_cfg.sensor,
            mission_cfg.transmission,
            faults.message_loss,
            np.random.default_rng([spec.seed, _LINK_STREAM]),
            faults.silence_rounds,
            mission_cfg.baseline_bytes,
        )
        self._relay_rc = starts[0].copy()
        self._range_cells = None if faults.comm_range_m is None else faults.comm_range_m / truth.resolution_m
        self._active = np.arange(n)
        """Robots of the pending decision (those the centre assigns to), in robot order."""
        # Oscillation breaking and the progress watchdog (module docstring).
        self._abandoned: list[list[NDArray[np.int32]]] = [[] for _ in range(n)]
        self._returns = np.zeros(n, dtype=np.int64)
        self.committed = np.zeros(n, dtype=bool)
        """``(n_robots,) bool``: the robot returned to goals it gave up too often and now keeps its goal."""
        self._goal_due = np.zeros(n, dtype=np.int64)
        """Step by which the robot should have reached its goal (assignment + path length / step)."""
        self._last_gain = np.zeros(n, dtype=np.int64)
        self._known_before = sim.robot_known_cells.copy()
        self.oscillations = 0
        """Times a robot was committed to its goal because it kept returning to goals it gave up."""
        self.stalls = 0
        """Goals the progress watchdog dropped."""
        self.pathless_goals = 0
        """Goals the centre assigned with no path to them, blacklisted (:meth:`_apply`)."""
        self.state = np.full(truth.shape, CellState.UNKNOWN, dtype=np.uint8)  # until the first round
        self.done_reason: str | None = None
        self._bar = Progress(100, f"{strategy.name} {truth.name}", "%", progress, leave=False)
        self.blocked = np.zeros(n, dtype=bool)
        self.passable = self.state == CellState.FREE
        self.reward_since_decision = 0.0
        """Paper eq. 9 summed over the simulation steps since the last decision: R_time per step plus
        lambda times the newly known explorable area, m^2."""
        self._just_decided = False
        self._posed: tuple[PosedDecision, float] | None = None
        if observer:
            observer(sim, None, self.goals, self.link.status)

    # -- state -----------------------------------------------------------------------------------------
    @property
    def done(self) -> bool:
        return self.done_reason is not None

    @property
    def steps(self) -> int:
        return self.sim.steps

    @property
    def active(self) -> NDArray[np.int64]:
        """The robots of the pending decision (those the centre may assign to), in robot order."""
        return self._active

    def snapshot(self) -> MissionSnapshot:
        """Copy of everything a step or a decision changes (the strategy, observer and truth are shared).
        Taken between :meth:`pose` and :meth:`commit`, it holds the posed decision too: a lookahead expert
        restores it once per candidate assignment and commits that."""
        keep = {k: v for k, v in self.__dict__.items() if k not in _NOT_COPIED}
        return MissionSnapshot(copy.deepcopy(keep))

    def restore(self, snap: MissionSnapshot) -> None:
        """Return to ``snap`` (which stays valid: it can be restored again)."""
        self.__dict__.update(copy.deepcopy(snap.state))

    # -- the loop ---------------------------------------------------------------------------------------
    @property
    def blacklist(self) -> BoolGrid:
        """``(H, W) bool`` cells no robot is sent to again."""
        return self.book.blacklist

    def _advance_route(self, i: int) -> bool:
        """Move robot i on to the next target of its route it can drive to; False when the route is used up."""
        sim = self.sim

        def take(target: NDArray[np.int32]) -> bool:
            if self.strategy.goals_are_frontiers and (
                self.blacklist[target[0], target[1]] or not _goal_still_frontier(sim.team_observed, target)
            ):
                return False
            path = astar_path(self.passable, tuple(sim.positions_rc[i]), tuple(target))
            if len(path):
                sim.set_path(i, path)
                self._set_due(i, path)
            return bool(len(path))

        return self.book.next_target(i, take)

    def _needs_decision(self) -> bool:
        """The replanning events (module docstring); moves robots on along their routes on the way."""
        sim, goals, cfg = self.sim, self.goals, self.mission_cfg
        frontier_goals = self.strategy.goals_are_frontiers
        need = decision_due(sim.steps, self.last_decision_step, cfg.replan_every_steps, asked=False)
        in_range = self._in_range()
        for i in range(sim.n_robots):
            if not sim.alive[i]:
                continue  # a failed robot asks for nothing
            if not in_range[i]:
                if self.blocked[i] or sim.path_ahead_blocked(i) or (sim.at_path_end(i) and not self._advance_route(i)):
                    self._explore_alone(i)  # out of range: nobody to ask
                continue
            if goals[i, 0] < 0:
                continue
            if sim.steps - max(int(self._goal_due[i]), int(self._last_gain[i])) > cfg.stall_steps:
                self._drop_stalled(i)
                need = True
                continue
            reached = sim.at_path_end(i)
            if (
                frontier_goals
                and reached
                and np.array_equal(sim.positions_rc[i], goals[i])
                and _goal_still_frontier(sim.team_observed, goals[i])
            ):
                self.book.stood_on(goals[i], still_frontier=True)
            if self.blocked[i] or sim.path_ahead_blocked(i):
                self._release(i)
                need = True
            elif reached:
                self._release(i)
                need |= not self._advance_route(i)
            elif (
                frontier_goals
                and sim.steps - self.last_decision_step >= cfg.min_replan_steps
                and not _goal_still_frontier(sim.team_observed, goals[i])
            ):
                # Driving on towards a goal already seen costs little; a decision costs the whole team.
                self._release(i)
                need |= not self._advance_route(i)
        return need

    def _release(self, i: int) -> None:
        """Robot i's goal came to an end (reached, resolved, blocked): it is free again."""
        self.committed[i] = False
        self._returns[i] = 0
        self._abandoned[i].clear()

    def _drop_stalled(self, i: int) -> None:
        """The watchdog: robot i gained nothing long after it should have reached its goal; the goal's
        neighbourhood stops being a candidate and the robot waits for the next decision."""
        self._blacklist_around(self.goals[i])
        self.book.drop(i)
        self.sim.set_path(i, NO_ROUTE)
        self._release(i)
        self.stalls += 1

    def _blacklist_around(self, goal: NDArray[np.int32]) -> None:
        """The cells within ``oscillation_radius_m`` / 4 of ``goal`` stop being candidates."""
        self.book.blacklist_around(
            goal, max(1, round(self.mission_cfg.oscillation_radius_m / 4 / self.truth.resolution_m))
        )

    def _keeps_goal(self, i: int, goal: NDArray[np.int32]) -> bool:
        """Whether robot i keeps its current goal instead of ``goal`` (oscillation breaking): it does when
        committed, and commits when ``goal`` returns it to a goal it gave up for the
        ``oscillation_returns``-th time. Records the goal given up otherwise."""
        cur = self.goals[i]
        if cur[0] < 0 or np.array_equal(cur, goal) or self.sim.at_path_end(i):
            return False
        if self.strategy.goals_are_frontiers and not _goal_still_frontier(self.sim.team_observed, cur):
            return False
        if self.committed[i]:
            return True
        radius_cells = self.mission_cfg.oscillation_radius_m / self.truth.resolution_m
        if goal[0] >= 0 and any(np.hypot(*(goal - a)) <= radius_cells for a in self._abandoned[i]):
            self._returns[i] += 1
            if self._returns[i] >= self.mission_cfg.oscillation_returns:
                self.committed[i] = True
                self.oscillations += 1
                return True
        self._abandoned[i] = [*self._abandoned[i][-(_ABANDONED_KEPT - 1) :], cur.copy()]
        return False

    def sending(self) -> NDArray[np.bool_]:
        """``(n_robots,) bool`` robots that send their maps at a round: alive and within radio range."""
        return self.sim.alive & self._in_range()

    def _in_range(self) -> NDArray[np.bool_]:
        """``(n_robots,) bool`` robots within radio range of the relay (all without a range limit)."""
        if self._range_cells is None:
            return np.ones(self.sim.n_robots, dtype=bool)
        d = np.hypot(*(self.sim.positions_rc - self._relay_rc).T)
        return np.asarray(d <= self._range_cells)

    def _explore_alone(self, i: int) -> None:
        """Robot i, out of range with its route done, picks the nearest frontier of its own grid; with
        none left it drives back towards the relay until it is in range again, to sync."""
        sim = self.sim
        belief, here = sim.beliefs[i], sim.positions_rc[i]
        if self.strategy.goals_are_frontiers and _goal_still_frontier(sim.team_observed, here):
            self.book.stood_on(here, still_frontier=True)
        window = belief.window(1)
        origin = np.array([window[0].start, window[1].start], dtype=np.int32)
        own = classify(belief.log_odds[window], belief.observed[window], self.sim_cfg.sensor)
        own = close_unknown_holes(own, self.strategy.preprocess.closing_size_cells)
        passable = own == CellState.FREE
        passable[here[0] - origin[0], here[1] - origin[1]] = True
        targets = detect_frontiers(own).un_rc
        if len(targets):
            targets = targets[~self.blacklist[targets[:, 0] + origin[0], targets[:, 1] + origin[1]]]
        field = distance_fields(passable, (here - origin)[None], targets)[0]
        d = distances_at(field, targets) if len(targets) else np.zeros(0)
        if len(d) and np.isfinite(d.min()):
            goal = targets[int(np.argmin(d))]
            path = descend_path(field, passable, (int(goal[0]), int(goal[1]))) + origin
        else:
            whole = np.zeros(self.truth.shape, dtype=bool)
            whole[window] = passable
            path = astar_path(whole | self.passable, (int(here[0]), int(here[1])), tuple(self._relay_rc))
            near = np.hypot(*(path - self._relay_rc).T) <= self._range_cells if len(path) else np.zeros(0, bool)
            if near.any():
                path = path[: int(np.argmax(near)) + 1]  # back in range is enough
        self.goals[i] = path[-1] if len(path) else NO_GOAL
        self.routes[i] = NO_ROUTE
        sim.set_path(i, path)
        self._set_due(i, path)

    def step(self) -> StepResult:
        """One simulation step (no replanning check): fail robots due to fail, drive, scan, record."""
        for robot in self.faults.failures_due(self.sim.steps):
            self.sim.fail(robot)
        with timed(self.strategy.timer, "step"):
            result = self.sim.step()
        self.blocked = result.blocked
        gained = self.sim.robot_known_cells > self._known_before
        self._last_gain[gained] = self.sim.steps
        self._known_before = self.sim.robot_known_cells.copy()
        self.record.curve.append(self.sim.coverage)
        r = self.sim_cfg.reward
        new_m2 = result.new_known_cells * self.truth.resolution_m**2
        self.reward_since_decision += r.time_reward + r.area_weight * new_m2
        self._bar.detail = f"step {self.sim.steps}"
        self._bar.set(round(100 * self.sim.coverage))
        if self.observer:
            self.observer(self.sim, self.decision, self.goals, self.link.status)
        return result

    def advance(self) -> bool:
        """Step until the team needs a decision (True) or the mission ends (False: budget spent or done)."""
        while not self.done:
            if self._just_decided:
                self._just_decided = False  # the step right after a decision is never a replanning point
            elif self._needs_decision():
                return True
            if self.sim.steps >= self.mission_cfg.max_steps:
                self.done_reason = "max_steps"
                break
            if not self.sim.alive.any():
                self.done_reason = "robots_lost"
                break
            self.step()
        return False

    def _current(self) -> list[NDArray[np.int32]]:
        """Only goals still ahead and still bordering unknown space may hold their robot (hysteresis)."""
        sim, goals, frontier_goals = self.sim, self.goals, self.strategy.goals_are_frontiers
        return [
            np.vstack([goals[i : i + 1], self.routes[i]])
            if goals[i, 0] >= 0
            and not sim.at_path_end(i)
            and (not frontier_goals or _goal_still_frontier(sim.team_observed, goals[i]))
            else (NO_ROUTE if frontier_goals else self.routes[i])
            for i in range(sim.n_robots)
        ]

    def _round(self) -> tuple[float, DecisionInput]:
        """The centre's round (robots send, the centre rebuilds): the start time and what every strategy
        decides on."""
        t = time.perf_counter()
        sim, link = self.sim, self.link
        for _ in range(self.faults.restarts_due(sim.steps)):
            link.restart_centre()
            self.book.forget()  # the centre's memory too
        with timed(self.strategy.timer, "round"):
            self.state = link.exchange(sim.beliefs, sim.positions_rc, self.sending())
        self.record.onboard_ms.extend(link.robot_ms_each)
        self._active = np.flatnonzero(link.status.assignable)
        current = self._current()
        return t, DecisionInput(
            self.state,
            link.status.positions_rc[self._active],
            self.truth.resolution_m,
            self.blacklist,
            [current[i] for i in self._active],
            self.rng,
            link.centre.frontiers(),
        )

    def _centre_ms(self, t: float) -> float:
        """The centre's time since ``t``: decoding, rebuilding and planning; the robots encode on board, and
        the byte accounting is neither's work."""
        return (time.perf_counter() - t) * 1e3 - self.link.robot_ms - self.link.accounting_ms

    def decide(self) -> Decision | None:
        """Take the pending decision with the strategy's own planner and apply it; None where the centre
        heard no robot in time (faults): no decision, the robots carry on with what they have."""
        t, inp = self._round()
        if len(self._active) == 0:
            self.record.plan_ms.append(self._centre_ms(t))
            self._idle_round()
            return None
        decision = self._expand(self.centre(inp))
        self.record.plan_ms.append(self._centre_ms(t))
        self._apply(decision)
        return decision

    def pose(self) -> AssignmentProblem | None:
        """First half of a decision: the centre's round and layer 1. Returns the problem a global planner
        answers with :meth:`commit`, or None when the mission ended here (no frontier left or reachable,
        :attr:`done`) or, under faults, when the centre heard no robot in time (not done: advance on)."""
        t, inp = self._round()
        if len(self._active) == 0:
            self.record.plan_ms.append(self._centre_ms(t))
            self._idle_round()
            return None
        posed = self.strategy.pose(inp)
        ms = self._centre_ms(t)
        if posed.final is not None:
            self.record.plan_ms.append(ms)
            self._apply(self._expand(posed.final))
            return None
        self._posed = (posed, ms)
        return posed.problem

    def commit(self, assignment: Assignment | None = None) -> Decision:
        """Second half: finish the posed decision with ``assignment`` (None: the strategy's planner's)."""
        if self._posed is None:
            raise MrExploreError("commit() without a posed decision; call pose() first")
        posed, ms = self._posed
        self._posed = None
        t = time.perf_counter()
        decision = self._expand(self.strategy.finish(posed, assignment or self.strategy.assign(posed)))
        self.record.plan_ms.append(ms + (time.perf_counter() - t) * 1e3)
        self._apply(decision)
        return decision

    def _expand(self, decision: Decision) -> Decision:
        """A decision over the robots the centre assigned to, spread over the whole team (the others get
        nothing: they keep what they have, see :meth:`_apply`)."""
        n, active = self.sim.n_robots, self._active
        if len(active) == n:
            return decision
        goals = np.tile(NO_GOAL, (n, 1))
        goals[active] = decision.goals_rc
        cluster_of_robot = np.full(n, UNASSIGNED, dtype=np.int64)
        cluster_of_robot[active] = decision.assignment.cluster_of_robot
        routes, paths = [NO_ROUTE] * n, [NO_ROUTE] * n
        for j, i in enumerate(active):
            routes[i], paths[i] = decision.routes[j], decision.paths[j]
        return replace(
            decision,
            goals_rc=goals,
            routes=routes,
            paths=paths,
            assignment=replace(decision.assignment, cluster_of_robot=cluster_of_robot),
        )

    def _idle_round(self) -> None:
        """A round in which the centre could assign to nobody: no decision (the reward since the last one
        keeps accumulating); the robots drive on."""
        self.last_decision_step = self.sim.steps
        self._just_decided = True

    def _apply(self, decision: Decision) -> None:
        self.last_decision_step = self.sim.steps
        self.reward_since_decision = 0.0
        self.decision = decision
        if decision.done_reason is not None:
            self.done_reason = decision.done_reason
            return
        self.passable = decision.state == CellState.FREE
        reached = self.sim.alive & self._in_range()
        for i in map(int, self._active):
            if not reached[i]:
                continue  # failed, or out of range: the assignment never arrives
            path = decision.paths[i]
            goal = decision.goals_rc[i]
            if goal[0] >= 0 and len(path) == 0 and self.strategy.goals_are_frontiers:
                # The centre chose a goal it found no path to (its distance was an estimate on a large map):
                # explore_lite blacklists such goals; kept, the same choice would come back every decision.
                self._blacklist_around(goal)
                self.pathless_goals += 1
            if self._keeps_goal(i, goal):
                continue  # committed: drives on to its goal, whatever this decision says
            if len(path) and not np.array_equal(path[0], self.sim.positions_rc[i]):
                # Planned from the cell of the robot's last message that arrived; it is elsewhere now.
                here = _cell_mask(self.passable.shape, self.sim.positions_rc[i])
                path = astar_path(self.passable | here, tuple(self.sim.positions_rc[i]), tuple(goal))
            self.sim.set_path(i, path)
            self.routes[i] = decision.routes[i][1:]
            self.goals[i] = goal if len(path) else NO_GOAL
            self._set_due(i, path)
        self._just_decided = True

    def _set_due(self, i: int, path: NDArray[np.int32]) -> None:
        """Robot i should reach the end of ``path`` by now plus its length at ``step_m`` per step."""
        steps_needed = _path_len_cells(path) / (self.sim_cfg.motion.step_m / self.truth.resolution_m)
        self._goal_due[i] = self.sim.steps + math.ceil(steps_needed)

    def run(self) -> MissionResult:
        """Run to the end with the strategy's own decisions."""
        while self.advance():
            self.decide()
        return self.result()

    def result(self) -> MissionResult:
        """The measures of the mission so far (closes the progress bar)."""
        self._bar.close()
        truth, sim = self.truth, self.sim
        wall_s = time.perf_counter() - self._t0
        transmission = self.link.totals.as_measures()
        measures = self.record.measures(
            truth, sim, self.sim_cfg, self.starts_rc, wall_s, self.done_reason or "max_steps", transmission
        )
        return MissionResult(measures, np.asarray(self.record.curve), self.starts_rc.copy(), self.state, sim)


_ABANDONED_KEPT = 4
"""Goals given up that a robot remembers for oscillation breaking."""
_LINK_STREAM = 0x4C494E4B
"""Second word of the seed of the link's generator (lost messages), apart from the mission's."""


def _path_len_cells(path: NDArray[np.int32]) -> float:
    """Length of an 8-connected cell path, cells (diagonal steps sqrt(2))."""
    if len(path) < 2:
        return 0.0
    d = np.abs(np.diff(path, axis=0))
    return float(np.where((d[:, 0] > 0) & (d[:, 1] > 0), math.sqrt(2.0), 1.0).sum())


def _cell_mask(shape: tuple[int, int], rc: NDArray[np.integer]) -> NDArray[np.bool_]:
    """``(H, W) bool`` with only ``rc`` set: a robot may always leave the cell it stands on."""
    mask = np.zeros(shape, dtype=bool)
    mask[int(rc[0]), int(rc[1])] = True
    return mask


def run_mission(spec: MissionSpec, observer: Observer | None = None, progress: bool | None = None) -> MissionResult:
    """Explore ``spec.truth`` with ``spec.strategy`` until done or out of budget (a :class:`Mission` run
    whole); ``progress``: show a coverage bar (default: only when stderr is a terminal)."""
    return Mission(spec, observer, progress).run()
