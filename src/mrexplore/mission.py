"""One exploration mission: simulator + strategy, the replanning events, termination and measures.

Replanning is the same for every strategy. A decision (the whole team re-assigned at the centre) is
taken when a robot reached its goal, when its path is blocked, when its goal is no longer a frontier
and ``min_replan_steps`` passed since the last decision, and at least every ``replan_every_steps``
steps. A robot with a local route (paper IV-C) first moves on to the next target of its route that is
still a frontier; only when none is left does its goal count as reached. The mission ends as the
paper's: no cluster of the minimum size left, or none reachable; or when the step budget runs out
(``max_steps``, never success).
"""

from __future__ import annotations

import sys
import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray
from tqdm import tqdm

from mrexplore.config import MissionConfig, SimConfig
from mrexplore.maps.ground_truth import GroundTruthMap
from mrexplore.paths.astar import astar_path
from mrexplore.preprocessing.transmission import TeamLink
from mrexplore.sim.measures import EpisodeMeasures, lower_bound_steps
from mrexplore.sim.starts import draw_starts
from mrexplore.sim.world import ExplorationSim
from mrexplore.strategies import NO_GOAL, Decision, ExplorationPipeline
from mrexplore.types import CellState, MrExploreError

__all__ = ["MissionResult", "run_mission", "Observer"]

Observer = Callable[[ExplorationSim, Decision | None, NDArray[np.int32]], None]
"""Called after the first scan and after every step with the sim, the latest decision and the goals."""


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


def _goal_still_frontier(team_observed: np.ndarray, goal: NDArray[np.int32]) -> bool:
    """Whether a goal cell still has an unobserved 4-neighbour (cheap per-step test, no full detection)."""
    r, c = int(goal[0]), int(goal[1])
    H, W = team_observed.shape
    for rr, cc in ((r - 1, c), (r + 1, c), (r, c - 1), (r, c + 1)):
        if 0 <= rr < H and 0 <= cc < W and not team_observed[rr, cc]:
            return True
    return False


def run_mission(
    truth: GroundTruthMap,
    strategy: ExplorationPipeline,
    sim_cfg: SimConfig | None = None,
    mission_cfg: MissionConfig | None = None,
    seed: int = 0,
    starts_rc: NDArray[np.integer] | None = None,
    observer: Observer | None = None,
    progress: bool | None = None,
) -> MissionResult:
    """Explore ``truth`` with ``strategy`` until done or out of budget.

    Parameters
    ----------
    starts_rc:
        ``(n_robots, 2) int`` start cells; drawn close together from ``seed`` when None.
    progress:
        Show a coverage bar; default: only when stderr is a terminal.
    """
    sim_cfg = sim_cfg or SimConfig()
    mission_cfg = mission_cfg or MissionConfig()
    rng = np.random.default_rng(seed)
    if starts_rc is None:
        starts_rc = draw_starts(truth, sim_cfg.robots, sim_cfg.start_spread_m, rng)
    starts_rc = np.asarray(starts_rc, dtype=np.int32)
    if len(starts_rc) != sim_cfg.robots:
        raise MrExploreError(f"starts must give one cell per robot ({sim_cfg.robots}), got {len(starts_rc)}")
    t0 = time.perf_counter()
    strategy.prepare(truth, starts_rc, sim_cfg)
    sim = ExplorationSim(truth, starts_rc, sim_cfg, rng)
    n = sim.n_robots
    goals = np.tile(NO_GOAL, (n, 1))
    blacklist = np.zeros(truth.shape, dtype=bool)
    curve = [sim.coverage]
    plan_ms: list[float] = []
    last_decision_step = -mission_cfg.replan_every_steps
    decision: Decision | None = None
    # Every strategy plans on the grid the centre rebuilds from the robots' sparse frontier maps (IV-A).
    link = TeamLink(n, truth.shape, strategy.preprocess, sim_cfg.sensor, mission_cfg.transmission)  # type: ignore[arg-type]
    state = np.full(truth.shape, CellState.UNKNOWN, dtype=np.uint8)  # until the first round
    done_reason = "max_steps"
    show = sys.stderr.isatty() if progress is None else progress
    bar = tqdm(total=100, unit="%", desc=f"{strategy.name} {truth.name}", disable=not show, leave=False)
    blocked = np.zeros(n, dtype=bool)
    no_route = np.zeros((0, 2), dtype=np.int32)
    routes = [no_route] * n  # targets after the current goal
    passable = state == CellState.FREE
    frontier_goals = strategy.goals_are_frontiers

    def advance(i: int) -> bool:
        """Move robot i on to the next target of its route; False when the route is used up."""
        while len(routes[i]):
            target, routes[i] = routes[i][0], routes[i][1:]
            if frontier_goals and (
                blacklist[target[0], target[1]] or not _goal_still_frontier(sim.team_observed, target)
            ):
                continue
            path = astar_path(passable, tuple(sim.positions_rc[i]), tuple(target))
            if len(path):
                goals[i] = target
                sim.set_path(i, path)
                return True
        return False

    if observer:
        observer(sim, decision, goals)
    while True:
        need = sim.steps - last_decision_step >= mission_cfg.replan_every_steps
        for i in range(n):
            has_goal = goals[i, 0] >= 0
            if not has_goal:
                continue
            reached = sim.at_path_end(i)
            if (
                frontier_goals
                and reached
                and np.array_equal(sim.positions_rc[i], goals[i])
                and _goal_still_frontier(sim.team_observed, goals[i])
            ):
                blacklist[goals[i, 0], goals[i, 1]] = True  # stood on it and it stayed a frontier
            if blocked[i] or sim.path_ahead_blocked(i):
                need = True
            elif reached:
                need |= not advance(i)
            elif (
                frontier_goals
                and sim.steps - last_decision_step >= mission_cfg.min_replan_steps
                and not _goal_still_frontier(sim.team_observed, goals[i])
            ):
                # Driving on towards a goal already seen costs little; a decision costs the whole team.
                need |= not advance(i)
        if need:
            t = time.perf_counter()
            state = link.exchange(sim.beliefs, sim.positions_rc)
            # Only goals still ahead and still bordering unknown space may hold their robot (hysteresis).
            current = [
                np.vstack([goals[i : i + 1], routes[i]])
                if goals[i, 0] >= 0
                and not sim.at_path_end(i)
                and (not frontier_goals or _goal_still_frontier(sim.team_observed, goals[i]))
                else (no_route if frontier_goals else routes[i])
                for i in range(n)
            ]
            decision = strategy.decide(state, sim.positions_rc.copy(), truth.resolution_m, blacklist, current)
            # The centre's time: decoding, rebuilding and planning; the robots encode on board.
            plan_ms.append((time.perf_counter() - t) * 1e3 - link.robot_ms)
            last_decision_step = sim.steps
            if decision.done_reason is not None:
                done_reason = decision.done_reason
                break
            goals = decision.goals_rc.copy()
            passable = decision.state == CellState.FREE
            for i in range(n):
                sim.set_path(i, decision.paths[i])
                routes[i] = decision.routes[i][1:]
                if len(decision.paths[i]) == 0:
                    goals[i] = NO_GOAL
        if sim.steps >= mission_cfg.max_steps:
            break
        result = sim.step()
        blocked = result.blocked
        curve.append(sim.coverage)
        bar.update(round(100 * sim.coverage) - bar.n)
        if observer:
            observer(sim, decision, goals)
    bar.close()
    measures = EpisodeMeasures.from_run(
        np.asarray(curve),
        sim.robot_coverage,
        sim.path_len_m,
        plan_ms,
        time.perf_counter() - t0,
        done_reason,
        link.totals.as_measures(),
        lower_bound_steps(~truth.occupied, sim.explorable, starts_rc, truth.resolution_m, sim_cfg),
    )
    return MissionResult(measures, np.asarray(curve), np.asarray(starts_rc, dtype=np.int32), state, sim)
