"""The decision-level environment: eq. 9 rewards add up to the mission's, terminated differs from truncated."""

from __future__ import annotations

import numpy as np

from mrexplore.config import MapConfig, MissionConfig, SimConfig
from mrexplore.global_planning.classical import NearestPlanner
from mrexplore.maps.loaders import load_map
from mrexplore.mission import MissionSpec
from mrexplore.mission.decision_env import DecisionEnv
from mrexplore.pipeline import make_strategy


def test_rewards_add_up_to_eq9_and_the_episode_terminates() -> None:
    truth = load_map("generated:1", MapConfig(resolution_m=0.2))
    env = DecisionEnv(MissionSpec(truth, make_strategy("utility"), SimConfig(robots=2)))
    problem, _ = env.reset(seed=3)
    total, steps, terminated, truncated = 0.0, 0, False, False
    known0 = env.mission.sim.known_cells if env.mission else 0
    while not (terminated or truncated):
        action = NearestPlanner().assign(problem) if steps % 2 else None  # any planner may answer
        problem, reward, terminated, truncated, info = env.step(action)
        total += reward
        steps += 1
    m = env.mission
    assert m is not None and terminated and not truncated and problem is None
    area = (m.sim.known_cells - known0) * 0.2**2
    assert np.isclose(total, -1.0 * m.steps + 2.0 * area)  # R_time per step + lambda * new m^2


def test_budget_truncates() -> None:
    truth = load_map("generated:1", MapConfig(resolution_m=0.2))
    env = DecisionEnv(MissionSpec(truth, make_strategy("utility"), mission_cfg=MissionConfig(max_steps=7)))
    env.reset(seed=0)
    done = False
    while not done:
        _, _, terminated, truncated, info = env.step(None)
        done = terminated or truncated
    assert truncated and not terminated and info["steps"] == 7 and info["done_reason"] == "max_steps"
