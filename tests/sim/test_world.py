"""The simulator: motion budget per step, collisions, coverage counting, seeded starts."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import truth_map
from hypothesis import given, settings
from hypothesis import strategies as st

from mrexplore.config import MotionConfig, SimConfig
from mrexplore.maps.loaders import load_map
from mrexplore.sim.belief import logit
from mrexplore.sim.starts import draw_starts, starts_from_xy
from mrexplore.sim.world import ExplorationSim
from mrexplore.types import MrExploreError

CORRIDOR = """
    ##########
    #........#
    #........#
    ##########
"""


def _sim(text: str, starts: list[list[int]], **kw) -> ExplorationSim:
    cfg = SimConfig(robots=len(starts), **kw)
    return ExplorationSim(truth_map(text), np.array(starts), cfg, np.random.default_rng(0))


def test_step_drives_step_m_along_the_path() -> None:
    sim = _sim(CORRIDOR, [[1, 1]])  # 0.1 m per step at 0.05 m cells: two straight cells
    sim.set_path(0, np.array([[1, 1], [1, 2], [1, 3], [1, 4], [2, 5], [2, 6]]))
    res = sim.step()
    assert sim.positions_rc[0].tolist() == [1, 3] and res.moved_m[0] == pytest.approx(0.1)
    res = sim.step()  # one straight (1) then a diagonal (sqrt 2) would exceed 2 cells: 1 cell carried
    assert sim.positions_rc[0].tolist() == [1, 4] and res.moved_m[0] == pytest.approx(0.05)
    res = sim.step()  # 2 + 1 carried: the diagonal and the last straight cell
    assert sim.positions_rc[0].tolist() == [2, 6] and sim.at_path_end(0)
    assert res.moved_m[0] == pytest.approx(0.05 * (1 + np.sqrt(2)))
    assert sim.path_len_m[0] == pytest.approx(0.05 * (4 + np.sqrt(2)))


def test_cells_larger_than_a_step_are_crossed_at_constant_speed() -> None:
    slow = _sim(CORRIDOR, [[1, 1]], motion=MotionConfig(step_m=0.02))  # 0.4 cells per step
    slow.set_path(0, np.array([[1, 1], [1, 2], [1, 3]]))
    positions = []
    for _ in range(5):
        slow.step()
        positions.append(slow.positions_rc[0, 1].item())
    assert positions == [1, 1, 2, 2, 3]  # driven so far: 0.4, 0.8, 1.2, 1.6, 2.0 cells


def test_collision_stops_robot_and_reports_blocked() -> None:
    sim = _sim(CORRIDOR, [[1, 1]])
    sim.set_path(0, np.array([[1, 1], [0, 1]]))
    res = sim.step()
    assert res.blocked[0] and sim.positions_rc[0].tolist() == [1, 1]


def test_a_failed_robots_belief_blocks_no_path() -> None:
    sim = _sim(CORRIDOR, [[1, 1], [2, 8]])
    sim.set_path(0, np.array([[1, 1], [1, 2], [1, 3], [1, 4]]))
    sim.beliefs[1].log_odds[1, 3] = 5.0  # robot 1 alone believes a cell of robot 0's path occupied
    assert sim.path_ahead_blocked(0)
    sim.fail(1)  # its belief never reaches the centre again: robot 0 drives on and sees for itself
    assert not sim.path_ahead_blocked(0)


@settings(max_examples=60, deadline=None)
@given(st.integers(0, 10**6))
def test_path_ahead_blocked_sums_the_live_beliefs_in_float32_as_numpy_does(seed: int) -> None:
    # Log-odds drawn from sums of the sensor's own steps, so that team sums land on and near the threshold.
    rng = np.random.default_rng(seed)
    sim = _sim(CORRIDOR, [[1, 1], [1, 2], [2, 1]])
    sensor = sim.cfg.sensor
    steps = np.array([logit(sensor.p_hit), logit(sensor.p_miss), 0.0], np.float32)
    for b in sim.beliefs:
        b.log_odds[:] = rng.choice(steps, size=(3, b.log_odds.size)).sum(axis=0).reshape(b.log_odds.shape)
    sim.set_path(0, np.array([[1, 1], [1, 2], [1, 3], [2, 4], [2, 5], [1, 6], [1, 7]]))
    for i in 1 + np.flatnonzero(rng.random(2) < 0.4):
        sim.fail(int(i))  # a failed robot's belief counts no more
    ahead = sim.remaining_path(0)[1:]
    total = np.zeros(len(ahead), np.float32)
    for i in np.flatnonzero(sim.alive):
        total += sim.beliefs[i].log_odds[ahead[:, 0], ahead[:, 1]]
    assert sim.path_ahead_blocked(0) == bool(np.any(total > logit(sensor.p_occupied)))


def test_path_must_start_at_robot() -> None:
    sim = _sim(CORRIDOR, [[1, 1]])
    with pytest.raises(ValueError, match=r"path of robot 0 must start at its cell \[1, 1\]"):
        sim.set_path(0, np.array([[1, 2]]))


def test_coverage_counts_match_a_recount() -> None:
    truth = load_map("generated:2")
    rng = np.random.default_rng(3)
    starts = draw_starts(truth, 3, 1.0, rng)
    sim = ExplorationSim(truth, starts, SimConfig(), rng)
    for i in range(3):
        sim.set_path(i, np.array([starts[i], starts[i] + [0, 1], starts[i] + [0, 2]]))
    sim.step()
    team = np.logical_or.reduce([b.observed for b in sim.beliefs])
    assert sim.known_cells == int((team & sim.explorable).sum())
    per_robot = [int((b.observed & sim.explorable).sum()) for b in sim.beliefs]
    assert sim.robot_known_cells.tolist() == per_robot
    assert sim.coverage == pytest.approx(sim.known_cells / sim.explorable.sum())


def test_starts_drawn_close_together_and_seeded() -> None:
    truth = load_map("generated:0")
    a = draw_starts(truth, 4, 1.0, np.random.default_rng(7))
    b = draw_starts(truth, 4, 1.0, np.random.default_rng(7))
    assert np.array_equal(a, b) and len({tuple(r) for r in a.tolist()}) == 4
    assert not truth.occupied[a[:, 0], a[:, 1]].any()
    assert np.abs(a - a[0]).max() <= 1.0 / truth.resolution_m


def test_given_start_in_wall_or_outside_refused() -> None:
    truth = truth_map(CORRIDOR)
    assert starts_from_xy(truth, [(0.075, 0.125)]).tolist() == [[1, 1]]
    with pytest.raises(MrExploreError, match=r"start \(0.01, 0.01\) lies inside a wall"):
        starts_from_xy(truth, [(0.01, 0.01)])
    with pytest.raises(MrExploreError, match=r"start \(5.0, 5.0\) lies outside the map"):
        starts_from_xy(truth, [(5.0, 5.0)])
