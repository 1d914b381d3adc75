"""Progress, always: over 210 seeded episodes no stretch of steps without new area outlasts what travel and
the watchdog explain while a frontier remains; oscillation breaking and the watchdog by hand."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
from conftest import SHARED_MAPS, truth_map

from mrexplore.config import MapConfig, MissionConfig, SensorConfig, SimConfig
from mrexplore.maps.loaders import load_map
from mrexplore.mission import Mission, MissionSpec
from mrexplore.paths.astar import astar_path
from mrexplore.paths.distance_field import distance_field
from mrexplore.pipeline import DecisionInput, make_strategy, strategy_names
from mrexplore.types import CellState

TEAMS = (1, 2, 3, 5, 8)
MAPS = ("generated:11", "generated:12", "generated:13", "generated:14", "generated:15")
DEV_MAPS = (
    "houseexpo/json/0004d52d1aeeb8ae6de39d6bd993e992.json",
    "houseexpo/json/0a1b29dba355df2ab02630133187bfab.json",
)
RESOLUTION_M = 0.2


def longest_flat(curve: np.ndarray) -> int:
    """The longest run of steps that brought no new area, in a coverage curve (index = step).

    >>> longest_flat(np.array([0.1, 0.2, 0.2, 0.2, 0.5, 0.5]))  # steps 2 and 3
    2
    """
    flat = np.diff(curve) <= 0
    best = run = 0
    for f in flat:
        run = run + 1 if f else 0
        best = max(best, run)
    return best


def travel_bound_steps(truth, starts_rc: np.ndarray, cfg: SimConfig) -> int:
    """Steps to drive twice across the explorable free space (twice the largest geodesic distance from the
    first start, an upper bound on the diameter), at ``step_m`` a step."""
    field = distance_field(~truth.occupied, tuple(starts_rc[0]))
    reach = float(field[np.isfinite(field)].max()) * truth.resolution_m
    return math.ceil(2 * 2 * reach / cfg.motion.step_m)


SEARCH_TEAMS = (3, 8)
"""The run-time search decides by four rollouts a decision, some 20 times the others' time: it runs two team
sizes here (the pipeline it drives, hier-plan's, runs them all)."""


def _episodes() -> list[tuple[str, str, int, float]]:
    maps = list(MAPS) + ([str(SHARED_MAPS / m) for m in DEV_MAPS] if SHARED_MAPS.is_dir() else [])
    out = []
    for m in maps:
        for strategy in strategy_names():
            for n in SEARCH_TEAMS if strategy == "hier-search" else TEAMS:
                out.append((m, strategy, n, 8.0 if n == 1 else 6.0))  # lone robots with the 8 m sensor
    return out


EPISODES = _episodes()


@pytest.fixture(scope="module")
def maps():
    return {m: load_map(m, MapConfig(resolution_m=RESOLUTION_M)) for m in {e[0] for e in EPISODES}}


def test_at_least_two_hundred_episodes() -> None:
    assert len(EPISODES) >= 150 + (60 if SHARED_MAPS.is_dir() else 0)


@pytest.mark.parametrize(("map_spec", "strategy", "robots", "range_m"), EPISODES)
def test_no_stretch_without_new_area_beyond_travel_and_watchdog(maps, map_spec, strategy, robots, range_m) -> None:
    truth = maps[map_spec]
    sim_cfg = SimConfig(robots=robots, sensor=SensorConfig(range_m=range_m))
    cfg = MissionConfig(max_steps=6000)
    mission = Mission(MissionSpec(truth, make_strategy(strategy), sim_cfg, cfg, seed=robots), progress=False)
    result = mission.run()
    m = result.measures
    assert m.done_reason != "max_steps", f"{strategy} never ended ({m.steps} steps, coverage {m.coverage:.3f})"
    flat = longest_flat(result.coverage_curve)
    bound = cfg.stall_steps + travel_bound_steps(truth, result.starts_rc, sim_cfg)
    assert flat <= bound, f"{flat} steps without new area (bound {bound})"
    assert m.coverage >= 0.95 or strategy == "oracle"


def test_a_robot_returning_to_goals_it_gave_up_commits_to_its_goal() -> None:
    """A corridor with frontiers at both ends; a planner that flips the robot's goal from one end to the
    other at every decision. After ``oscillation_returns`` returns the robot keeps its goal and the
    mission ends; without the breaker it would flip until the budget ran out."""
    corridor = truth_map(
        """
        ##############################################
        #............................................#
        #............................................#
        ##############################################
        """,
        resolution_m=0.2,
    )
    strategy = make_strategy("nearest")
    decide = strategy.decide
    calls = [0]

    def flipping(inp: DecisionInput):
        """Each decision sends the robot to the frontier at the end it is not heading for."""
        d = decide(inp)
        robots_rc = inp.robots_rc
        if d.done_reason is not None:
            return d
        calls[0] += 1
        un = d.frontiers.un_rc
        goal = un[np.argmin(un[:, 1])] if calls[0] % 2 else un[np.argmax(un[:, 1])]
        path = astar_path(d.state == CellState.FREE, tuple(robots_rc[0]), tuple(goal))
        return replace(d, goals_rc=goal[None].astype(np.int32), routes=[goal[None]], paths=[path])

    strategy.decide = flipping  # type: ignore[method-assign]
    cfg = MissionConfig(max_steps=2000, replan_every_steps=5, min_replan_steps=5)
    sim = SimConfig(robots=1, sensor=SensorConfig(range_m=1.0))
    mission = Mission(MissionSpec(corridor, strategy, sim, cfg, seed=0, starts_rc=np.array([[1, 22]])), progress=False)
    result = mission.run()
    assert mission.oscillations >= 1
    assert result.measures.done_reason == "no_frontiers" and result.measures.coverage > 0.95
    assert result.measures.steps < 400  # 8.8 m of corridor: one way, back, a few flips
    assert calls[0] > 2 * cfg.oscillation_returns
    # Without the breaker the same planner flips the robot until the budget runs out.
    endless = Mission(
        MissionSpec(
            corridor, strategy, sim, replace(cfg, oscillation_returns=10**6), seed=0, starts_rc=np.array([[1, 22]])
        )
    )
    assert endless.run().measures.done_reason == "max_steps"


def test_the_watchdog_drops_a_goal_that_brings_nothing() -> None:
    """A goal the robot can never reach (its path is cleared every step, as if the robot were stuck):
    after its due time plus ``stall_steps`` without new area, the goal is dropped and blacklisted."""
    room = truth_map(
        """
        ############
        #..........#
        #..........#
        ############
        """,
        resolution_m=0.2,
    )
    cfg = MissionConfig(max_steps=400, stall_steps=30)
    mission = Mission(MissionSpec(room, make_strategy("nearest"), SimConfig(robots=1), cfg, seed=0), progress=False)
    assert mission.advance()
    mission.decide()
    mission.goals[0] = np.array([1, 10], np.int32)  # a goal it keeps but never drives to
    mission.sim.set_path(0, np.zeros((0, 2), np.int32))
    mission.sim.paths[0] = np.array([mission.sim.positions_rc[0], mission.sim.positions_rc[0]])
    for _ in range(60):
        mission.step()
        mission._needs_decision()  # noqa: SLF001 - the watchdog runs where replanning is checked
    assert mission.stalls == 1 and mission.goals[0].tolist() == [-1, -1]
    assert mission.blacklist[1, 10]


@pytest.fixture(autouse=True)
def _kernels_compiled(monkeypatch: pytest.MonkeyPatch) -> None:
    """A run that compiled kernels earlier in this process (a fresh clone's first test) gives no estimates:
    these tests read the estimates of a run that did not."""
    from mrexplore.runtime import kernel_cache

    monkeypatch.setattr(kernel_cache, "_compiling", False)


class _Clock:
    def __init__(self) -> None:
        self.t = 0.0

    def __call__(self) -> float:
        return self.t


def test_progress_lines_every_few_seconds_where_no_terminal() -> None:
    """Piped output gets a line every LINE_EVERY_S seconds of work and one at the end; off prints nothing."""
    import io

    from mrexplore.runtime.progress import LINE_EVERY_S, Progress

    out, clock = io.StringIO(), _Clock()
    p = Progress(10, "bench", "episodes", None, stream=out, clock=clock)
    assert p.mode == "lines"
    p.update()  # at once: no line yet
    clock.t = LINE_EVERY_S
    p.update()  # 2 done after 5 s: 8 more take 20 s
    clock.t = LINE_EVERY_S + 1
    p.update()  # within the interval: no line
    clock.t = 8.0
    p.set(10)  # within the interval: said at close, once
    p.detail = "all done"
    p.close()
    p.close()
    assert out.getvalue().splitlines() == [
        "bench: 2/10 episodes (20%), 5 s, about 20 s left",
        "bench: 10/10 episodes (100%), 8 s, all done",
    ]
    clock.t = 200.0
    budget = Progress(10, "train", "stages", None, stream=io.StringIO(), clock=clock)
    budget.limit_s = 30.0  # the run stops within its budget, whatever the stages would take (45 s)
    clock.t = 205.0
    budget.set(1)
    assert budget.stream.getvalue() == "train: 1/10 stages (10%), 5 s, about 25 s left\n"
    quiet = io.StringIO()
    q = Progress(10, "bench", "episodes", False, stream=quiet, clock=clock)
    clock.t = 100.0
    q.set(10)
    q.close()
    assert quiet.getvalue() == ""


def test_a_mission_s_progress_line_says_coverage_and_step() -> None:
    import io

    from mrexplore.runtime.progress import Progress

    out, clock = io.StringIO(), _Clock()
    p = Progress(100, "hier generated:0", "%", None, stream=out, clock=clock)
    clock.t = 6.0
    p.detail = "step 40"
    p.set(45)
    assert out.getvalue() == "hier generated:0: 45%, 6 s, about 7 s left, step 40\n"


def test_a_bar_ends_on_one_line_of_its_last_state() -> None:
    """tqdm's close() prints the final state again: where output is no terminal that was a second line."""
    import io

    from mrexplore.runtime.progress import Progress

    out = io.StringIO()
    p = Progress(2, "bench", "episodes", True, stream=out)
    p._bar.mininterval = 0  # every update prints, the last one included
    p.update()
    p.update()
    p.close()
    finals = [line for line in out.getvalue().replace("\r", "\n").splitlines() if "2/2" in line]
    assert len(finals) == 1 and out.getvalue().endswith("\n")


def test_a_slow_start_does_not_stretch_every_estimate_after_it() -> None:
    # The first 5 s made 5% (kernels compiling), then 5% a second: after a few lines, the time left follows
    # the pace of the last lines, not the average since the start.
    import io

    from mrexplore.runtime.progress import Progress

    clock = _Clock()
    out = io.StringIO()
    bar = Progress(100, "run", "%", None, stream=out, clock=clock)
    for t, n in ((5.0, 5), (6.0, 10), (7.0, 15), (8.0, 20), (9.0, 25)):
        clock.t = t
        bar._next_line = 0.0  # a line at every update
        bar.set(n)
    lines = out.getvalue().splitlines()
    assert lines[0] == "run: 5%, 5 s, about 1 min 35 s left"  # from the start: 5 s for 5%
    assert lines[-1] == "run: 25%, 9 s, about 15 s left"  # the last lines' pace: 5% a second


def test_no_estimate_while_the_kernels_compile(monkeypatch) -> None:
    # A first run's first lines are compile time: no estimate until the last lines give a pace.
    import io

    from mrexplore.runtime import kernel_cache
    from mrexplore.runtime.progress import Progress

    monkeypatch.setattr(kernel_cache, "_compiling", True)
    clock, out = _Clock(), io.StringIO()
    bar = Progress(100, "run", "%", None, stream=out, clock=clock)
    for t, n in ((26.0, 11), (27.0, 16), (28.0, 21), (29.0, 26)):
        clock.t = t
        bar._next_line = 0.0
        bar.set(n)
    lines = out.getvalue().splitlines()
    assert lines[0] == "run: 11%, 26 s, no estimate while the kernels compile"
    assert lines[-1] == "run: 26%, 29 s, about 15 s left"  # 5% a second over the last lines
