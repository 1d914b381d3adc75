"""Faults: a robot lost mid-mission, lost messages and acknowledgements, a restarting centre, radio range."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import require_shared_maps, state_grid

from mrexplore.config import FaultConfig, MapConfig, MissionConfig, PreprocessConfig, SensorConfig, SimConfig
from mrexplore.global_planning.protocol import UNASSIGNED
from mrexplore.maps.loaders import load_map
from mrexplore.mission import Mission, MissionSpec, run_mission
from mrexplore.pipeline import make_strategy, strategy_names
from mrexplore.preprocessing.link import TeamLink
from mrexplore.preprocessing.reconstruction import CentreMap
from mrexplore.preprocessing.sparse_map import sparse_frontier_map
from mrexplore.sim.belief import Belief
from mrexplore.types import CellState, MrExploreError

REAL_MAPS = ("houseexpo/json/0a1b29dba355df2ab02630133187bfab.json", "dungeon/easy_img_15.png")
STRATEGIES = ("utility", "hier")
FINISHED = ("no_frontiers", "no_reachable_frontiers")
"""A mission that ended by itself: no frontier left, or none the team can reach (a 2-cell piece seen
through a gap, say)."""


@pytest.fixture(scope="module")
def real_maps():
    root = require_shared_maps()
    return [load_map(str(root / m), MapConfig(resolution_m=0.1)) for m in REAL_MAPS]


@pytest.fixture(scope="module")
def small_map():
    return load_map("generated:3", MapConfig(resolution_m=0.2))


def _run(truth, strategy: str, faults: FaultConfig, robots: int = 3, seed: int = 1):
    cfg = MissionConfig(max_steps=4000, faults=faults)
    return run_mission(
        MissionSpec(truth, make_strategy(strategy), SimConfig(robots=robots), cfg, seed=seed), progress=False
    )


@pytest.mark.parametrize("strategy", STRATEGIES)
@pytest.mark.parametrize("which", [0, 1])
def test_one_robot_of_three_lost_mid_mission_the_others_finish(real_maps, strategy: str, which: int) -> None:
    truth = real_maps[which]
    clean = _run(truth, strategy, FaultConfig()).measures
    fail_at = clean.steps // 2
    seen_after: list[np.ndarray] = []
    where_after: list[list[int]] = []
    mission = Mission(
        MissionSpec(
            truth,
            make_strategy(strategy),
            SimConfig(robots=3),
            MissionConfig(max_steps=4000, faults=FaultConfig(robot_failures=((1, fail_at),))),
            seed=1,
        ),
        progress=False,
    )
    while mission.advance():
        decision = mission.decide()
        if mission.steps > fail_at:
            seen_after.append(decision.assignment.cluster_of_robot.copy())
            where_after.append(mission.sim.positions_rc[1].tolist())
    m = mission.result().measures
    assert m.coverage >= 0.99 and m.done_reason in FINISHED
    assert m.robots_failed == 1 and not mission.sim.alive[1]
    # The centre stops assigning to the silent robot after silence_rounds rounds (3), and never again.
    assert len(seen_after) > 3
    assert all(a[1] == UNASSIGNED for a in seen_after[3:])
    assert all(w == where_after[0] for w in where_after)  # the failed robot never moved again


@pytest.mark.parametrize("strategy", STRATEGIES)
@pytest.mark.parametrize("which", [0, 1])
def test_thirty_percent_message_loss_still_explores(real_maps, strategy: str, which: int) -> None:
    m = _run(real_maps[which], strategy, FaultConfig(message_loss=0.3)).measures
    assert m.coverage >= 0.99 and m.done_reason in FINISHED
    assert m.messages_lost > 0 and m.acks_lost > 0 and m.bytes_lost > 0
    # Every robot tries once a round; an unacknowledged robot sends its whole map, so no delta is refused.
    assert m.messages_sent == 3 * m.rounds and m.messages_resent == 0


@pytest.mark.parametrize("strategy", STRATEGIES)
@pytest.mark.parametrize("which", [0, 1])
def test_centre_restart_rebuilds_from_the_next_messages(real_maps, strategy: str, which: int) -> None:
    clean = _run(real_maps[which], strategy, FaultConfig()).measures
    m = _run(real_maps[which], strategy, FaultConfig(centre_restarts=(clean.steps // 3,))).measures
    assert m.coverage >= 0.99 and m.done_reason in FINISHED
    # The restarted centre holds no base: each robot's next delta is refused and its whole map resent once
    # (a robot whose delta was no smaller than its whole map sent the whole map, which needs no resend).
    assert m.centre_restarts == 1 and 1 <= m.messages_resent <= 3 and m.messages_lost == 0


@pytest.mark.parametrize("strategy", STRATEGIES)
def test_robots_out_of_radio_range_explore_alone_and_sync(real_maps, strategy: str) -> None:
    clean = _run(real_maps[1], strategy, FaultConfig()).measures
    m = _run(real_maps[1], strategy, FaultConfig(comm_range_m=6.0)).measures
    assert m.coverage >= 0.99 and m.done_reason in FINISHED
    assert m.messages_sent < 3 * m.rounds  # some rounds found a robot out of range
    assert clean.messages_sent == 3 * clean.rounds


@pytest.mark.parametrize("strategy", [s for s in strategy_names() if s != "oracle"])
@pytest.mark.parametrize(
    "faults",
    [
        FaultConfig(robot_failures=((0, 40),)),
        FaultConfig(message_loss=0.3),
        FaultConfig(centre_restarts=(30, 60)),
        FaultConfig(comm_range_m=4.0),
    ],
    ids=["failure", "loss", "restart", "range"],
)
def test_every_strategy_keeps_working_under_each_fault(small_map, strategy: str, faults: FaultConfig) -> None:
    m = _run(small_map, strategy, faults, robots=2).measures
    assert m.coverage >= 0.99 and m.done_reason in FINISHED


def test_the_oracle_runs_under_faults(small_map) -> None:
    m = _run(small_map, "oracle", FaultConfig(message_loss=0.3, robot_failures=((1, 40),)), robots=2).measures
    assert m.done_reason == "plan_done" and m.robots_failed == 1


def test_losing_every_robot_ends_the_mission(small_map) -> None:
    m = _run(small_map, "utility", FaultConfig(robot_failures=((0, 10), (1, 20))), robots=2).measures
    assert m.done_reason == "robots_lost" and m.steps == 21 and m.robots_failed == 2


def test_a_failure_of_a_robot_outside_the_team_is_refused(small_map) -> None:
    with pytest.raises(MrExploreError) as err:
        _run(small_map, "utility", FaultConfig(robot_failures=((3, 10),)), robots=2)
    assert str(err.value) == "robot failure names robot 3, but the team has robots 0..1; pass an id of the team"


class _Script:
    """A stand-in generator whose draws are given: 0.0 loses a message (below any loss), 0.99 keeps it."""

    def __init__(self, draws: list[float]) -> None:
        self.draws = list(draws)

    def random(self) -> float:
        return self.draws.pop(0)


ROOM = """
    #########
    #.......#
    #.......#
    #.......#
    #########
"""
LOSE, KEEP = 0.0, 0.99


def _belief_seeing(cols: int) -> Belief:
    """A belief that has observed the room's first ``cols`` columns (walls included)."""
    truth = state_grid(ROOM)
    b = Belief.empty(truth.shape)
    b.observed[:, :cols] = True
    b.log_odds[:, :cols] = np.where(truth[:, :cols] == CellState.OCCUPIED, 2.0, -2.0)
    b.note_window((0, truth.shape[0], 0, cols))
    return b


def test_lost_message_and_lost_acknowledgement_by_hand() -> None:
    shape = state_grid(ROOM).shape
    link = TeamLink(1, shape, PreprocessConfig(closing_size_cells=1), SensorConfig(), message_loss=0.5)
    pos = np.array([[2, 1]])
    t = link.totals

    def round_(cols: int, draws: list[float]) -> tuple[int, int]:
        """One round; returns the bytes of the whole map and of what the robot sent."""
        link._rng = _Script(draws)  # noqa: SLF001 - the script replaces the seeded draws
        whole, sent = t.bytes_sparse, t.bytes_sparse_delta
        link.exchange([_belief_seeing(cols)], pos)
        assert not link._rng.draws  # noqa: SLF001 - every scripted draw was used
        return t.bytes_sparse - whole, t.bytes_sparse_delta - sent

    # Round 0: the whole map arrives; its acknowledgement is lost.
    round_(4, [KEEP, LOSE])
    assert (t.messages_sent, t.acks_lost, link.status.heard.tolist()) == (1, 1, [True])
    # Round 1: unacknowledged, the robot sends its whole map again; it arrives and is acknowledged.
    whole, sent = round_(6, [KEEP, KEEP])
    assert sent == whole
    # Round 2: a delta on round 1 (shorter than the whole map), lost on the way; the centre keeps round 1.
    whole, sent = round_(8, [LOSE])
    assert sent < whole and (t.messages_lost, link.status.heard.tolist()) == (1, [False])
    # Round 3: nothing acknowledged round 2, so the whole map again: taken and acknowledged.
    whole, sent = round_(9, [KEEP, KEEP])
    assert sent == whole and t.messages_sent == 4
    # Round 4: a delta on round 3, taken. The centre restarts before round 5: it holds no base, refuses the
    # delta on round 4, asks for the whole map, and the robot resends it at once.
    whole, sent = round_(9, [KEEP, KEEP])
    assert sent < whole
    link.restart_centre()
    whole, sent = round_(9, [KEEP, KEEP, KEEP, KEEP])  # delta, request, resend, acknowledgement
    assert (t.messages_sent, t.messages_resent, t.bytes_resent, t.acks_lost) == (7, 1, whole, 1)
    assert link.status.heard.tolist() == [True]
    link.message_loss = 0.0
    assert (link.exchange([_belief_seeing(9)], pos) == CellState.FREE).sum() == 21  # the whole room


def test_delta_centre_equals_the_lossless_one_once_robots_resync(small_map) -> None:
    """Run a mission with 30% loss, then one lossless round: the centre's grid built from deltas (and the
    resends the losses caused) equals a fresh centre's built from whole maps of the same beliefs."""
    mission = Mission(
        MissionSpec(
            small_map,
            make_strategy("utility"),
            SimConfig(robots=3),
            MissionConfig(max_steps=150, faults=FaultConfig(message_loss=0.3)),
            seed=2,
        ),
        progress=False,
    )
    while mission.advance():
        mission.decide()
    link = mission.link
    assert link.totals.messages_lost > 0 and link.totals.acks_lost > 0
    link.message_loss = 0.0
    resynced = link.exchange(mission.sim.beliefs, mission.sim.positions_rc)
    fresh = TeamLink(3, small_map.shape, link.preprocess, link.sensor, mode="full")
    assert np.array_equal(resynced, fresh.exchange(mission.sim.beliefs, mission.sim.positions_rc))


def test_centre_refuses_a_delta_on_a_base_it_lacks() -> None:
    grid = state_grid(ROOM)
    centre = CentreMap(1, grid.shape, 1)
    full = sparse_frontier_map(grid, 0, 4, (2, 1))
    delta = sparse_frontier_map(grid, 0, 5, (2, 1))
    delta = type(delta)(0, 5, grid.shape, (2, 1), delta.cells[:0], delta.codes[:0], delta.seeds, base_round=3)
    assert centre.accepts(full) and not centre.accepts(delta)
    centre.receive(full)
    assert not centre.accepts(delta)  # holds round 4, the delta is on 3
    with pytest.raises(MrExploreError, match="applies to round 3, the centre holds round 4"):
        centre.receive(delta)


def test_gif_frames_draw_failed_and_unheard_robots() -> None:
    from mrexplore.mission.render import render_frame

    occ = np.zeros((20, 20), bool)
    state = np.full((20, 20), CellState.FREE, np.uint8)
    pos = np.array([[5, 5], [5, 14], [14, 10]])
    none = np.tile([-1, -1], (3, 1))
    img = render_frame(
        occ,
        state,
        pos,
        [],
        None,
        none,
        scale=10.0,
        failed=np.array([False, True, False]),
        unheard=np.array([False, False, True]),
    )
    px = np.asarray(img)
    assert tuple(px[55, 55]) == (0, 114, 178)  # robot 0 filled in its colour
    assert tuple(px[55, 155]) == (128, 128, 128)  # robot 1 failed: grey (crossed out through its centre)
    assert tuple(px[145, 105]) == (255, 255, 255)  # robot 2 not heard: a ring, its centre unfilled


def test_rounds_where_the_centre_hears_nobody_pose_nothing_and_the_mission_goes_on(small_map) -> None:
    """With 80% loss some rounds bring no message at all: no decision is taken there, and the stepped
    interfaces (pose/commit, the decision-level env) run on to the end."""
    from mrexplore.mission.decision_env import DecisionEnv

    faults = FaultConfig(message_loss=0.8, silence_rounds=1)
    cfg = MissionConfig(max_steps=3000, faults=faults)
    mission = Mission(
        MissionSpec(small_map, make_strategy("utility"), SimConfig(robots=1), cfg, seed=0), progress=False
    )
    idle = 0
    while mission.advance():
        if mission.pose() is None:
            idle += not mission.done
            continue
        mission.commit()
    assert idle > 0 and mission.done_reason in FINISHED and mission.sim.coverage >= 0.99
    env = DecisionEnv(MissionSpec(small_map, make_strategy("utility"), SimConfig(robots=1), cfg))
    problem, info = env.reset(seed=0)
    done = False
    while not done:
        problem, reward, terminated, truncated, info = env.step(None)
        done = terminated or truncated
    assert terminated and info["coverage"] >= 0.99
