"""PettingZoo ParallelEnv over the simulator, for users who bring their own policies.

One agent per robot. An action is a goal cell ``(row, col)``; the robot drives there along an A* path on
its own belief (replanned when the goal changes or the path turns out blocked) and stands still when the
goal is unreachable. Every agent receives the team reward of paper eq. 9. An episode is ``terminated``
when the team has observed ``done_coverage`` of the explorable region, ``truncated`` at ``max_steps``.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from gymnasium import spaces
from pettingzoo import ParallelEnv

from mrexplore.config import SimConfig
from mrexplore.maps.ground_truth import GroundTruthMap
from mrexplore.paths.astar import astar_path
from mrexplore.sim.belief import logit
from mrexplore.sim.starts import draw_starts
from mrexplore.sim.world import ExplorationSim
from mrexplore.types import CellState, MrExploreError

__all__ = ["ExplorationParallelEnv"]


class ExplorationParallelEnv(ParallelEnv):
    """Multi-robot exploration as a PettingZoo parallel environment.

    Observations per agent: ``{"belief": (H, W) uint8 CellState of its own grid,
    "position_rc": (2,) int32}``. Actions: ``MultiDiscrete([H, W])`` goal cell.
    """

    metadata = {"name": "mrexplore_v0", "render_modes": ["rgb_array"], "is_parallelizable": True}

    def __init__(
        self,
        truth: GroundTruthMap,
        sim_cfg: SimConfig | None = None,
        max_steps: int = 2000,
        done_coverage: float = 0.99,
        render_mode: str | None = None,
    ) -> None:
        if max_steps < 1:
            raise MrExploreError(f"max_steps must be >= 1, got {max_steps}")
        if not 0 < done_coverage <= 1:
            raise MrExploreError(f"done_coverage must be in (0, 1], got {done_coverage}")
        if render_mode not in (None, "rgb_array"):
            raise MrExploreError(f"render_mode must be None or 'rgb_array', got {render_mode!r}")
        self.truth = truth
        self.sim_cfg = sim_cfg or SimConfig()
        self.max_steps = max_steps
        self.done_coverage = done_coverage
        self.render_mode = render_mode
        self.possible_agents = [f"robot_{i}" for i in range(self.sim_cfg.robots)]
        self.agents: list[str] = []
        H, W = truth.shape
        self._obs_space = spaces.Dict(
            {
                "belief": spaces.Box(0, int(CellState.UNKNOWN), shape=(H, W), dtype=np.uint8),
                "position_rc": spaces.Box(0, max(H, W) - 1, shape=(2,), dtype=np.int32),
            }
        )
        self._act_space = spaces.MultiDiscrete([H, W])
        self._sim: ExplorationSim | None = None
        self._goals = np.full((self.sim_cfg.robots, 2), -1, dtype=np.int64)

    def observation_space(self, agent: str) -> spaces.Space:
        return self._obs_space

    def action_space(self, agent: str) -> spaces.Space:
        return self._act_space

    def reset(
        self, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[dict[str, Any], dict[str, Any]]:
        rng = np.random.default_rng(seed)
        starts = (options or {}).get("starts_rc")
        if starts is None:
            starts = draw_starts(self.truth, self.sim_cfg.robots, self.sim_cfg.start_spread_m, rng)
        self._sim = ExplorationSim(self.truth, np.asarray(starts), self.sim_cfg, rng)
        self._goals[:] = -1
        self.agents = list(self.possible_agents)
        return self._observations(), {a: {} for a in self.agents}

    def _observations(self) -> dict[str, Any]:
        sim = self._require_sim()
        return {
            a: {
                "belief": sim.beliefs[i].state(self.sim_cfg.sensor),
                "position_rc": sim.positions_rc[i].astype(np.int32),
            }
            for i, a in enumerate(self.possible_agents)
            if a in self.agents
        }

    def _require_sim(self) -> ExplorationSim:
        if self._sim is None:
            raise RuntimeError("call reset() before step()")
        return self._sim

    def _plan(self, i: int, goal: np.ndarray) -> None:
        sim = self._require_sim()
        b = sim.beliefs[i]
        passable = b.observed & (b.log_odds <= logit(self.sim_cfg.sensor.p_occupied))
        sim.set_path(i, astar_path(passable, tuple(sim.positions_rc[i]), (int(goal[0]), int(goal[1]))))
        self._goals[i] = goal

    def step(
        self, actions: dict[str, Any]
    ) -> tuple[dict[str, Any], dict[str, float], dict[str, bool], dict[str, bool], dict[str, Any]]:
        sim = self._require_sim()
        for i, a in enumerate(self.possible_agents):
            if a in actions and a in self.agents:
                goal = np.asarray(actions[a], dtype=np.int64).reshape(2)
                if not np.array_equal(goal, self._goals[i]) or sim.path_ahead_blocked(i):
                    self._plan(i, goal)
        result = sim.step()
        cell_m2 = self.truth.resolution_m**2
        r = self.sim_cfg.reward
        reward = float(r.time_reward + r.area_weight * result.new_known_cells * cell_m2)
        terminated = sim.coverage >= self.done_coverage
        truncated = sim.steps >= self.max_steps and not terminated
        obs = self._observations()
        agents = list(self.agents)
        infos = {
            a: {"coverage": sim.coverage, "goal_reachable": len(sim.paths[i]) > 0}
            for i, a in enumerate(self.possible_agents)
            if a in agents
        }
        if terminated or truncated:
            self.agents = []
        return (
            obs,
            {a: reward for a in agents},
            {a: terminated for a in agents},
            {a: truncated for a in agents},
            infos,
        )

    def render(self) -> np.ndarray | None:
        if self.render_mode != "rgb_array":
            return None
        sim = self._require_sim()
        rgb = np.full((*self.truth.shape, 3), 205, dtype=np.uint8)
        rgb[sim.team_observed] = 255
        rgb[self.truth.occupied & sim.team_observed] = 20
        rgb[sim.positions_rc[:, 0], sim.positions_rc[:, 1]] = (220, 50, 47)
        return rgb

    def close(self) -> None:
        self._sim = None
