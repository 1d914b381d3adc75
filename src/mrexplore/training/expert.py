"""The lookahead expert (training only, may use the simulator's truth): candidate assignments run forward
from the same decision and scored by the return of paper eq. 9 over a horizon."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import NDArray

from mrexplore.config import GlobalPlanningConfig
from mrexplore.global_planning.classical import NearestPlanner, UtilityPlanner, utility_cost
from mrexplore.global_planning.hungarian import match_min_cost
from mrexplore.global_planning.learned.features import GraphInputs
from mrexplore.global_planning.protocol import Assignment, AssignmentProblem, GlobalPlanner
from mrexplore.mission import Mission

__all__ = [
    "ExpertLabel",
    "candidate_assignments",
    "lookahead_returns",
    "known_world_returns",
    "predicted_world_returns",
    "horizon_return",
    "privileged_scalars",
]


@dataclass(frozen=True)
class ExpertLabel:
    """One decision the expert ranked: the network's inputs, the candidates and their returns."""

    inputs: GraphInputs
    candidates: NDArray[np.int64]
    """``(M, R) int64`` cluster per robot of each candidate (-1: none)."""
    returns: NDArray[np.float64]
    """``(M,) float64`` eq. 9 return of each candidate over the horizon."""


def candidate_assignments(
    problem: AssignmentProblem,
    student: Assignment,
    heuristic: GlobalPlanningConfig,
    noisy: int,
    noise_m: float,
    rng: np.random.Generator,
) -> list[NDArray[np.int64]]:
    """Distinct assignments worth comparing: the student's, utility's, nearest's and ``noisy`` utility
    matchings whose cost carries Gumbel noise of scale ``noise_m`` metres of detour."""
    out = [student.cluster_of_robot, UtilityPlanner(heuristic).assign(problem).cluster_of_robot]
    out.append(NearestPlanner().assign(problem).cluster_of_robot)
    cost = utility_cost(problem, heuristic)
    for _ in range(noisy):
        noise = rng.gumbel(0.0, noise_m * heuristic.distance_weight, size=cost.shape)
        out.append(match_min_cost(cost + noise))
    unique: dict[tuple[int, ...], NDArray[np.int64]] = {}
    for a in out:
        unique.setdefault(tuple(int(v) for v in a), np.asarray(a, dtype=np.int64))
    return list(unique.values())


def horizon_return(mission: Mission, start_steps: int, start_known: int) -> float:
    """Eq. 9 summed from (``start_steps``, ``start_known`` cells) to now: R_time per step plus lambda times
    the newly known explorable area in m^2."""
    r = mission.sim_cfg.reward
    steps = mission.steps - start_steps
    new_m2 = (mission.sim.known_cells - start_known) * mission.truth.resolution_m**2
    return float(r.time_reward * steps + r.area_weight * new_m2)


def _roll_forward(
    mission: Mission,
    candidates: list[NDArray[np.int64]],
    horizon_steps: int,
    continuation: GlobalPlanner,
    score: Callable[[Mission, int, int], float],
    walls: NDArray[np.bool_] | None = None,
) -> NDArray[np.float64]:
    """``score(mission, start steps, start known cells)`` of each candidate: commit it at the posed
    decision (the rollout's scans seeing ``walls`` where given), then let ``continuation`` decide until
    ``horizon_steps`` steps passed or the mission ended. The mission is left as it was (posed)."""
    snap = mission.snapshot()
    own = mission.strategy.planner
    start_steps, start_known = mission.steps, mission.sim.known_cells
    budget = min(mission.mission_cfg.max_steps, start_steps + horizon_steps)
    returns = np.zeros(len(candidates))
    mission.strategy.planner = continuation
    try:
        for j, cand in enumerate(candidates):
            mission.restore(snap)
            if walls is not None:
                mission.sim.use_walls(walls)
            # The horizon as a step budget, so every candidate is measured over the same steps (restored after).
            mission.mission_cfg = replace(mission.mission_cfg, max_steps=budget)
            mission.commit(Assignment(cand))
            while mission.advance():
                mission.decide()
            returns[j] = score(mission, start_steps, start_known)
    finally:
        mission.strategy.planner = own
        mission.restore(snap)
    return returns


def lookahead_returns(
    mission: Mission, candidates: list[NDArray[np.int64]], horizon_steps: int, continuation: GlobalPlanner
) -> NDArray[np.float64]:
    """Return of each candidate: commit it at the posed decision, then let ``continuation`` decide until
    ``horizon_steps`` steps passed or the mission ended; scored by :func:`horizon_return`. The mission is
    left as it was (posed)."""
    return _roll_forward(mission, candidates, horizon_steps, continuation, horizon_return)


def known_world_returns(
    mission: Mission, candidates: list[NDArray[np.int64]], horizon_steps: int, continuation: GlobalPlanner
) -> NDArray[np.float64]:
    """Minus the steps each candidate takes until no frontier is left (``horizon_steps`` where that takes
    longer), run forward as :func:`lookahead_returns` runs them but in the world the team has observed:
    every cell no robot has seen is a wall to the rollout's scans. Nothing the team has not seen enters
    the score, so it ranks candidates by what a robot team could know at the decision (the seen cells are
    taken from the truth: the beliefs' rare misread cells aside, what the team knows). The mission is left
    as it was (posed)."""
    known = np.where(mission.sim.team_observed, mission.truth.occupied, True)

    def steps_taken(m: Mission, start_steps: int, start_known: int) -> float:
        return -float(m.steps - start_steps)

    return _roll_forward(mission, candidates, horizon_steps, continuation, steps_taken, known)


def predicted_world_returns(
    mission: Mission,
    candidates: list[NDArray[np.int64]],
    horizon_steps: int,
    continuation: GlobalPlanner,
    p_free: NDArray[np.floating],
) -> NDArray[np.float64]:
    """Eq. 9's return of each candidate run forward as :func:`lookahead_returns` runs them, but in the world
    a map predictor completes: the cells the team has observed as they are, every other cell a wall where
    ``p_free`` (the predictor's, ``(H, W)``, on the centre's grid) is below 0.5 and free elsewhere; the area
    term counts the free cells of that world newly observed. Nothing the team has not seen but the prediction
    enters the score. The mission is left as it was (posed)."""
    walls = np.where(mission.sim.team_observed, mission.truth.occupied, np.asarray(p_free) < 0.5)
    free = ~walls
    r = mission.sim_cfg.reward
    cell_m2 = mission.truth.resolution_m**2
    start_seen = int((mission.sim.team_observed & free).sum())

    def predicted_return(m: Mission, start_steps: int, start_known: int) -> float:
        new_m2 = (int((m.sim.team_observed & free).sum()) - start_seen) * cell_m2
        return float(r.time_reward * (m.steps - start_steps) + r.area_weight * new_m2)

    return _roll_forward(mission, candidates, horizon_steps, continuation, predicted_return, walls)


def privileged_scalars(mission: Mission) -> NDArray[np.float32]:
    """The critic's extra inputs (never the actor's): remaining explorable area (100 m^2), coverage,
    steps (1000s), team size (tens)."""
    sim = mission.sim
    remaining_m2 = (sim.n_explorable - sim.known_cells) * mission.truth.resolution_m**2
    return np.array([remaining_m2 / 100.0, sim.coverage, sim.steps / 1000.0, sim.n_robots / 10.0], np.float32)
