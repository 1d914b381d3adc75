"""The run-time search: rollouts in the world the centre knows, scored by hand on a corridor, the choice it
makes from the scores, and the strategy end to end (in a mission and at the ROS-free team centre)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from conftest import posed_mission, state_grid

from mrexplore.config import MapConfig, MissionConfig, SensorConfig, SimConfig
from mrexplore.global_planning.protocol import AssignmentProblem
from mrexplore.maps.loaders import load_map
from mrexplore.mission import Mission, MissionSpec
from mrexplore.mission.centre import TeamPlanner
from mrexplore.mission.search import RolloutSearch, SearchPlanner, rollout_world, seed_beliefs
from mrexplore.pipeline import make_strategy
from mrexplore.pipeline.decision import DecisionInput
from mrexplore.preprocessing.agents import RobotAgent
from mrexplore.preprocessing.sparse_codec import decode
from mrexplore.types import CellState

# A corridor three cells wide, known from column 5 to 34, unknown beyond both ends, walls all round.
CORRIDOR = "\n".join(["#" * 40, *["#????" + "." * 30 + "????#"] * 3, "#" * 40])
SHORT_SENSOR = replace(SimConfig(robots=1), sensor=replace(SensorConfig(), range_m=0.25))  # 2.5 cells at 0.1 m


def _problem(pipeline, state: np.ndarray, robots: list[tuple[int, int]]) -> AssignmentProblem:
    n = len(robots)
    inp = DecisionInput(
        state, np.array(robots, dtype=np.int32), 0.1, np.zeros(state.shape, bool), [np.zeros((0, 2), np.int32)] * n
    )
    posed = pipeline.pose(inp)
    assert posed.problem is not None
    return posed.problem


def test_the_rollout_world_keeps_only_what_the_centre_knows_free() -> None:
    state = state_grid(CORRIDOR)
    world = rollout_world(state, 0.1, np.array([[2, 10]]))
    assert np.array_equal(world.occupied, state != CellState.FREE) and world.resolution_m == 0.1


def test_a_rollout_starts_from_the_centres_grid_and_problem() -> None:
    # A real mission's centre grid after a few decisions: the rollout's robots, seeded with it, send what
    # rebuilds the same grid, and its first problem has the same clusters.
    _, problem = posed_mission("generated:3", "hier", 4, seed=0)
    world = rollout_world(problem.state, problem.resolution_m, problem.robots_rc)
    spec = MissionSpec(world, make_strategy("hier"), SimConfig(robots=3), starts_rc=problem.robots_rc)
    rollout = Mission(spec, progress=False)
    seed_beliefs(rollout.sim, problem.state)
    assert rollout.advance()
    again = rollout.pose()
    assert again is not None
    assert np.array_equal(again.state, problem.state)
    assert np.array_equal(again.clusters.centers_rc, problem.clusters.centers_rc)


def test_rollout_scores_are_the_steps_until_no_frontier_is_left() -> None:
    # One robot at column 10; the frontiers are the corridor's ends (cluster centres at columns 5 and 34).
    # Left first: 5 cells to the left end, then 29 across to the right one, one cell a step: 34 steps. Right
    # first: the 2.5-cell sensor sees the right end's unknown cells from column 32 (22 steps), and the left
    # end's from column 7 (25 more): 47.
    pipeline = make_strategy("hier-search-nolocal")
    problem = _problem(pipeline, state_grid(CORRIDOR), [(2, 10)])
    assert problem.clusters.centers_rc.tolist() == [[2, 5], [2, 34]]
    search = RolloutSearch(make_strategy("hier-nolocal"), SHORT_SENSOR)
    assert search.scores(problem, [np.array([0]), np.array([1])]).tolist() == [-34.0, -47.0]
    # Cut at 40 steps, right first is at column 14, heading west: 40 steps plus the team plan's 9 cells still to
    # drive to the west end's centre.
    short = RolloutSearch(make_strategy("hier-nolocal"), SHORT_SENSOR, horizon_steps=40)
    assert short.scores(problem, [np.array([0]), np.array([1])]).tolist() == [-34.0, -49.0]


def test_the_planner_takes_the_best_score_and_the_learned_choice_on_ties(monkeypatch) -> None:
    pipeline = make_strategy("hier-search-nolocal")
    planner = pipeline.planner
    assert isinstance(planner, SearchPlanner) and planner.search is not None
    problem = _problem(pipeline, state_grid(CORRIDOR), [(2, 10), (2, 30)])
    candidates = [np.array([0, 1]), np.array([1, 0])]
    monkeypatch.setattr("mrexplore.mission.search.search_candidates", lambda p, planners: candidates)
    for scores, chosen in (([-50.0, -40.0], [1, 0]), ([-40.0, -40.0], [0, 1]), ([-30.0, -40.0], [0, 1])):
        monkeypatch.setattr(planner.search, "scores", lambda p, c, s=scores: np.array(s))
        assert planner.assign(problem).cluster_of_robot.tolist() == chosen
        assert planner.last_scores.tolist() == scores


def test_one_candidate_needs_no_rollout(monkeypatch) -> None:
    pipeline = make_strategy("hier-search")
    planner = pipeline.planner
    assert isinstance(planner, SearchPlanner) and planner.search is not None

    def no_rollouts(p, c):
        raise AssertionError("rolled out a single candidate")

    monkeypatch.setattr(planner.search, "scores", no_rollouts)
    problem = _problem(pipeline, state_grid(CORRIDOR), [(2, 10)])
    planner.assign(problem)
    assert len(planner.last_candidates) == 1 and len(planner.last_scores) == 0


def test_the_rollouts_follow_the_pipelines_local_layer_and_the_missions_sensor() -> None:
    with_local, without = make_strategy("hier-search"), make_strategy("hier-search-nolocal")
    for pipeline in (with_local, without):
        planner = pipeline.planner
        assert isinstance(planner, SearchPlanner) and planner.search is not None
        assert (planner.search.continuation.local is None) == (pipeline.local is None)
        assert planner.search.continuation.planner is planner.lead
    truth = load_map("generated:3", MapConfig(resolution_m=0.1))
    sim = replace(SimConfig(robots=2), sensor=replace(SensorConfig(), range_m=4.0))
    Mission(MissionSpec(truth, with_local, sim, seed=0), progress=False)
    assert with_local.planner.search.sim_cfg.sensor.range_m == 4.0


def test_hier_search_explores_a_map_and_is_deterministic() -> None:
    truth = load_map("generated:3", MapConfig(resolution_m=0.1))
    runs = []
    for _ in range(2):
        pipeline = make_strategy("hier-search")
        m = Mission(MissionSpec(truth, pipeline, SimConfig(robots=3), MissionConfig(max_steps=3000), 0), progress=False)
        searched = 0
        while m.advance():
            m.decide()
            searched += len(pipeline.planner.last_scores) > 0
        runs.append((m.steps, m.done_reason, round(m.sim.coverage, 6), searched))
    assert runs[0] == runs[1]
    assert runs[0][1] == "no_frontiers" and runs[0][2] >= 0.99 and runs[0][3] > 0


def test_the_team_centre_runs_the_search_on_the_robots_messages() -> None:
    # The centre of the ROS 2 nodes (no ROS needed): the robots' sparse frontier maps in, goals out; the
    # robot at column 10 takes the west end, the one at 30 the east end.
    state = state_grid(CORRIDOR)
    strategy = make_strategy("hier-search")
    centre = TeamPlanner(2, state.shape, 0.1, strategy)
    for i, rc in enumerate([(2, 10), (2, 30)]):
        agent = RobotAgent(i, state.shape, strategy.preprocess, SensorConfig())
        agent.sense_state(state)
        centre.receive(decode(agent.compose(0, rc, agent.window()).full_bytes()), 0)
    sent = centre.plan(0, now=0.0)
    assert sorted(sent) == [0, 1] and (sent[0][1], sent[1][1]) == (5, 34)
