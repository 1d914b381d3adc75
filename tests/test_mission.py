"""Whole missions: termination criteria, seeded determinism, the step budget, and one decision by hand."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from conftest import state_grid
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy import ndimage

from mrexplore.config import GlobalPlanningConfig, MapConfig, MissionConfig, PreprocessConfig, SimConfig
from mrexplore.maps.floorplan import FloorplanSpec, generate_floorplan
from mrexplore.maps.ground_truth import GridFrame, GroundTruthMap
from mrexplore.maps.loaders import load_map
from mrexplore.mission import Mission, MissionSpec, run_mission
from mrexplore.paths.far_field import NearFarField
from mrexplore.pipeline import CandidateSet, DecisionInput, make_strategy
from mrexplore.preprocessing.clustering import Clusters
from mrexplore.preprocessing.denoise import denoised_frontier_cells
from mrexplore.preprocessing.frontiers import Frontiers
from mrexplore.types import MrExploreError

TIMING_KEYS = {"wall_s", "plan_ms_mean", "plan_ms_p95", "peak_mb", "onboard_ms_median", "onboard_ms_p95"}


@pytest.fixture(scope="module")
def small_map():
    return load_map("generated:3", MapConfig(resolution_m=0.1))


@pytest.mark.parametrize("strategy", ["nearest", "utility", "hier", "coscan", "oracle"])
def test_mission_explores_the_map(small_map, strategy: str) -> None:
    m = run_mission(MissionSpec(small_map, make_strategy(strategy), SimConfig(robots=2), seed=1)).measures
    assert m.coverage >= 0.99
    assert m.done_reason in {"no_frontiers", "no_reachable_frontiers", "plan_done"}
    assert 0 < m.lower_bound_steps <= m.steps
    assert m.steps_to_90 is not None and m.steps_to_90 <= m.steps
    assert m.path_len_max_m <= m.path_len_sum_m and m.decisions >= 1
    assert 0 < m.onboard_ms_median <= m.onboard_ms_p95  # every round's on-board work was timed


def test_same_seed_same_result_other_seed_other_result(small_map) -> None:
    runs = [run_mission(MissionSpec(small_map, make_strategy("utility"), seed=s)).measures.to_dict() for s in (4, 4, 5)]
    strip = [{k: v for k, v in r.items() if k not in TIMING_KEYS} for r in runs]
    assert strip[0] == strip[1]
    assert strip[0] != strip[2]


def test_budget_ends_as_max_steps_never_success(small_map) -> None:
    res = run_mission(MissionSpec(small_map, make_strategy("nearest"), mission_cfg=MissionConfig(max_steps=5), seed=0))
    assert res.measures.done_reason == "max_steps" and res.measures.steps == 5
    assert len(res.coverage_curve) == 6


def test_hier_routes_through_sub_clusters(small_map) -> None:
    seen: list[int] = []

    def observe(sim, decision, goals, status) -> None:
        if decision is not None:
            seen.append(max(len(r) for r in decision.routes))

    run_mission(MissionSpec(small_map, make_strategy("hier"), SimConfig(robots=2), seed=1), observer=observe)
    assert max(seen) > 1  # some decision routed a robot through several targets
    assert make_strategy("hier", local=False).local is None
    assert make_strategy("hier", local=False).name == "hier-nolocal"


def test_goals_with_no_path_are_blacklisted_not_chosen_forever(small_map, monkeypatch) -> None:
    # Every path comes back empty, as it did on a large floor where a distance was only an estimate (and
    # where float32 distances beyond 2,048 cells read back no path): each goal is blacklisted when given,
    # so the candidates run out and the mission ends instead of idling the team to its budget.
    import mrexplore.pipeline.base as base

    monkeypatch.setattr(base, "path_to", lambda *a: np.zeros((0, 2), np.int32))
    m = Mission(
        MissionSpec(small_map, make_strategy("utility"), SimConfig(robots=2), MissionConfig(max_steps=5000), seed=1)
    )
    m.run()
    assert m.done_reason == "no_frontiers" and m.steps < 5000
    assert m.pathless_goals >= 1 and m.blacklist.any()
    assert (m.sim.positions_rc == m.starts_rc).all()  # nobody ever had a path to drive


def test_wrong_number_of_starts_refused(small_map) -> None:
    with pytest.raises(MrExploreError, match=r"starts must give one cell per robot \(3\), got 1"):
        run_mission(MissionSpec(small_map, make_strategy("nearest"), starts_rc=np.array([[5, 5]])))


def test_one_decision_by_hand() -> None:
    # Two robots in a corridor, unknown at both ends: each end is a 3-cell frontier cluster.
    state = state_grid("""
        #########
        ?.......?
        ?.......?
        ?.......?
        #########
    """)
    pipeline = make_strategy("utility")
    d = pipeline.decide(DecisionInput(state, np.array([[2, 2], [2, 6]], np.int32), 0.05))
    assert d.done_reason is None
    assert d.clusters.centers_rc.tolist() == [[2, 1], [2, 7]] and d.clusters.sizes.tolist() == [3, 3]
    assert d.goals_rc.tolist() == [[2, 1], [2, 7]]  # each robot takes the end nearer to it
    assert d.paths[0].tolist() == [[2, 2], [2, 1]]
    assert d.paths[1].tolist() == [[2, 6], [2, 7]]


@pytest.mark.parametrize("sector", [0, 2, 24])
def test_far_distances_on_a_large_map_decide_a_corridor_as_exact_ones_do(sector: int) -> None:
    # A corridor with unknown at both ends; the robot at column 30 is 9 cells from the right end, beyond
    # an exact radius of 5 cells: its distance there is estimated on blocks of 2 x 2, its path searched.
    # Over every block (sector 0), on a portal graph of sectors of 2 blocks, and of 24 blocks: the whole
    # map in one sector, no portal, where the robot's own seed blocks reach the far cells inside it.
    state = state_grid("#" * 41 + "\n" + ("?" + "." * 39 + "?\n") * 3 + "#" * 41)
    robots = np.array([[2, 5], [2, 30]], np.int32)
    far_cfg = GlobalPlanningConfig(
        far_above_cells=0, exact_radius_m=0.25, coarse_cell_m=0.1, portal_sector_blocks=sector, portal_spacing_blocks=2
    )
    exact, far = make_strategy("utility"), make_strategy("utility", far_cfg)
    posed = far.pose(DecisionInput(state, robots, 0.05))
    assert posed.problem is not None and posed.work is not None
    fields = posed.work.fields
    assert all(isinstance(f, NearFarField) for f in fields)
    assert isinstance(fields[1], NearFarField) and not fields[1].is_exact(2, 39)
    # Over every block: whole free blocks along rows 1-2, then the last cell. On portals the blocks start
    # on the sectors' lattice, at row 0, so their middles lie in row 3: a diagonal step off the robot's
    # row at each end of the way; in one sector, with no portal, through the robot's own seed blocks.
    want = {0: 9.0, 2: 9.0 + 2 * (np.sqrt(2.0) - 1.0), 24: 9.0 + 2 * (np.sqrt(2.0) - 1.0)}[sector]
    assert fields[1].value(2, 39) == pytest.approx(want)
    d_exact, d_far = exact.decide(DecisionInput(state, robots, 0.05)), far.decide(DecisionInput(state, robots, 0.05))
    assert d_far.goals_rc.tolist() == d_exact.goals_rc.tolist() == [[2, 1], [2, 39]]
    assert [p.tolist() for p in d_far.paths] == [p.tolist() for p in d_exact.paths]
    assert d_far.paths[1].tolist() == [[2, c] for c in range(30, 40)]


def test_routes_on_threads_give_the_mission_inline_routes_give(small_map, monkeypatch) -> None:
    # Large grids route their robots on the threads; forced on this small one, with two threads and the
    # router's memo shared between them, every record but the timings stays as it is inline.
    import mrexplore.pipeline.base as base

    monkeypatch.setenv("MREXPLORE_THREADS", "2")
    plain, on_threads = base.map_threads, []

    def spied(fn, items):
        on_threads.append(len(items))
        return plain(fn, items)

    monkeypatch.setattr(base, "map_threads", spied)
    runs, calls = [], []
    for cells in (10**12, 0):
        monkeypatch.setattr(base, "_THREADED_ROUTES_CELLS", cells)
        runs.append(
            run_mission(MissionSpec(small_map, make_strategy("hier"), SimConfig(robots=4), seed=3)).measures.to_dict()
        )
        calls.append(len(on_threads))
    assert calls[0] == 0 and calls[1] > 0  # inline first, then every decision's routes on the threads
    inline, threaded = ({k: v for k, v in r.items() if k not in TIMING_KEYS} for r in runs)
    assert threaded == inline


@pytest.mark.parametrize("strategy", ["hier-predict-heuristic", "hier-predict"])
def test_a_prediction_started_ahead_on_the_threads_gives_the_mission_inline_gives(
    small_map, monkeypatch, strategy: str
) -> None:
    # The predictive planners start the map prediction when a decision's grid is known, on the threads where
    # more than one is allowed; every decision takes the one started for its own grid, so every record but
    # the timings is that of one thread.
    from mrexplore.global_planning.predictive import PredictionAhead

    taken: list[bool] = []
    plain = PredictionAhead.take

    def spied(self, predictor, state, resolution_m):
        taken.append(self._state is state and self._future is not None)
        return plain(self, predictor, state, resolution_m)

    monkeypatch.setattr(PredictionAhead, "take", spied)
    runs = []
    for threads in ("1", "2"):
        monkeypatch.setenv("MREXPLORE_THREADS", threads)
        spec = MissionSpec(small_map, make_strategy(strategy), SimConfig(robots=3), seed=4)
        runs.append(run_mission(spec).measures.to_dict())
    assert taken and all(taken)  # each decision took the prediction started for its grid
    one, two = ({k: v for k, v in r.items() if k not in TIMING_KEYS} for r in runs)
    assert two == one


def test_baseline_bytes_counted_on_threads_equal_those_counted_inline(small_map, monkeypatch) -> None:
    # Table II's baseline grids are compressed on the threads where more than one is allowed: the byte
    # counts, and every other record but the timings, are those of one thread.
    import mrexplore.preprocessing.link as link

    batches: list[int] = []
    plain = link.map_threads

    def spied(fn, items):
        batches.append(len(items))
        return plain(fn, items)

    monkeypatch.setattr(link, "map_threads", spied)
    runs = []
    for threads in ("1", "2"):
        monkeypatch.setenv("MREXPLORE_THREADS", threads)
        runs.append(
            run_mission(
                MissionSpec(small_map, make_strategy("utility"), SimConfig(robots=3), seed=2)
            ).measures.to_dict()
        )
    one, two = ({k: v for k, v in r.items() if k not in TIMING_KEYS} for r in runs)
    assert max(batches) == 3  # all three robots' grids in one batch at some round
    assert one["bytes_grid_zlib"] > 0 and two == one


def test_a_mission_without_the_grid_baselines_is_the_same_mission(small_map) -> None:
    # Table II's baselines are accounting only: left out, every record but the timings, the three grid
    # fields and the whole maps' bytes (the mode not sent) is the same, and those read None (empty in a
    # bench's CSV), not 0.
    cfg = MissionConfig()
    runs = [
        run_mission(
            MissionSpec(small_map, make_strategy(s), SimConfig(robots=3), replace(cfg, baseline_bytes=b), seed=1)
        )
        for s in ("utility", "coscan")
        for b in (True, False)
    ]
    grids = ("bytes_grid", "bytes_grid_zlib", "bytes_grid_delta_zlib", "bytes_sparse")
    for counted, left_out in (runs[:2], runs[2:]):
        a, b = (r.measures.to_dict() for r in (counted, left_out))
        assert all(a[k] > 0 for k in grids) and all(b[k] is None for k in grids)
        assert {k: v for k, v in a.items() if k not in TIMING_KEYS | set(grids)} == {
            k: v for k, v in b.items() if k not in TIMING_KEYS | set(grids)
        }
        assert np.array_equal(counted.coverage_curve, left_out.coverage_curve)
        assert np.array_equal(counted.final_state, left_out.final_state)


@pytest.mark.parametrize(("commitment", "goal"), [(1.0, [2, 7]), (0.4, [2, 1])])
def test_commitment_keeps_a_robot_on_its_goal(commitment: float, goal: list[int]) -> None:
    # The robot at (2, 5) heads for the left end (4 cells away); the right end is 2 cells away.
    # Afresh, nearest turns it around; with commitment 0.4 its goal costs 1.6 < 2 and it stays.
    state = state_grid("""
        #########
        ?.......?
        ?.......?
        ?.......?
        #########
    """)
    pipeline = make_strategy("nearest", GlobalPlanningConfig(commitment=commitment))
    current = [np.array([[2, 1]], np.int32)]
    d = pipeline.decide(DecisionInput(state, np.array([[2, 5]], np.int32), 0.05, current=current))
    assert d.goals_rc.tolist() == [goal]


def _as_with_whole_searches(truth, pipeline, steps: int, seed: int) -> dict:
    """A mission's measures with the pipeline's stopped searches, having checked that they, and the coverage
    curve, are those of the same mission with whole searches (``stop_searches=False``), step for step."""
    runs = [
        run_mission(MissionSpec(truth, p, SimConfig(robots=3), MissionConfig(max_steps=steps), seed=seed))
        for p in (pipeline, replace(pipeline, stop_searches=False))
    ]
    a, b = ({k: v for k, v in r.measures.to_dict().items() if k not in TIMING_KEYS} for r in runs)
    assert a == b
    assert np.array_equal(runs[0].coverage_curve, runs[1].coverage_curve)
    return a


def test_nearest_stops_its_searches_at_each_robots_nearest_cluster_and_explores_the_same(small_map) -> None:
    # nearest reads only each robot's nearest cluster and its own goal, so its own decisions search no
    # farther; the mission is the same as with whole searches, step for step, with and without hysteresis.
    for commitment in (None, 1.0):
        stopped = make_strategy("nearest", GlobalPlanningConfig(commitment=commitment))
        assert stopped.nearest_only and stopped.stop_searches
        assert _as_with_whole_searches(small_map, stopped, 400, seed=4)["decisions"] > 10


def test_nearest_poses_every_distance_for_another_planner() -> None:
    state = state_grid("""
        #########
        ?.......?
        ?.......?
        ?.......?
        #########
    """)
    pipeline = make_strategy("nearest")
    robots = np.array([[2, 2]], np.int32)
    for own, right in ((False, 5.0), (True, np.inf)):
        posed = pipeline.pose(DecisionInput(state, robots, 0.05), own_planner=own)
        assert posed.problem is not None
        left = posed.problem.clusters.centers_rc[:, 1].tolist().index(1)
        assert posed.problem.dist_cells[0, left] == 1.0 and posed.problem.dist_cells[0, 1 - left] == right
        assert (posed.problem.robot_dist_cells is None) == own


def test_ncm_searches_only_its_window_and_explores_the_same() -> None:
    # NCM allows a robot only the nodes within its 24 m window (or, with none reachable there, every
    # node), so its own decisions search no farther; on a 64 m floor the mission is the same as with
    # whole searches, step for step.
    occupied = generate_floorplan(FloorplanSpec(seed=2, width_m=64.0, height_m=12.0, corridor_m=2.0), 0.2)
    truth = GroundTruthMap(occupied, GridFrame(occupied.shape[0], occupied.shape[1], 0.2), "long")
    m = _as_with_whole_searches(truth, make_strategy("ncm"), 3000, seed=1)
    assert m["decisions"] > 10 and m["coverage"] > 0.99


def test_oracle_searches_only_to_each_robots_next_viewpoint_and_explores_the_same(small_map) -> None:
    # Each robot owns its route, so its path to the route's first viewpoint is all its search is read for.
    oracle = make_strategy("oracle")
    robots = np.array([[20, 20], [60, 100]], np.int32)
    heads = np.array([[22, 20], [60, 98]], np.int32)
    routes = Clusters(heads, np.ones(2, np.int32), heads, np.arange(2, dtype=np.int32))
    cand = CandidateSet(routes, owners=np.array([1, 0]))  # robot 1 owns the first route
    assert [r.tolist() for r in oracle.own_reads(robots, cand, 0.1)] == [[[60, 98]], [[22, 20]]]
    m = _as_with_whole_searches(small_map, oracle, 2000, seed=2)
    assert m["decisions"] > 3 and m["coverage"] > 0.99


@pytest.mark.parametrize(("col", "far"), [(10, np.inf), (30, 28.0)])
def test_ncm_poses_its_window_for_itself_and_every_distance_for_another_planner(col: int, far: float) -> None:
    # At 1 m a cell: nodes on the left end (column 1) and the right end (column 58). From column 10 the
    # left end is in the 24 m window and the right end, 48 m away, is not: NCM's own search stops at the
    # left end. From column 30 neither end is in the window, so NCM may take any node and reads both.
    state = state_grid("#" * 60 + "\n" + ("?" + "." * 58 + "?\n") * 3 + "#" * 60)
    pipeline = make_strategy("ncm")
    robots = np.array([[2, col]], np.int32)
    whole = {1: col - 1.0, 58: 58.0 - col}  # the middle row's nodes, straight along the corridor
    for own in (False, True):
        posed = pipeline.pose(DecisionInput(state, robots, 1.0), own_planner=own)
        assert posed.problem is not None
        centres = posed.problem.clusters.centers_rc.tolist()
        at = {c: posed.problem.dist_cells[0, centres.index([2, c])] for c in (1, 58)}
        right = far if own else whole[58]
        assert at == {1: whole[1], 58: right}
        assert (posed.problem.robot_dist_cells is None) == own


def test_commitment_defaults() -> None:
    assert make_strategy("utility").commitment == 0.5 and make_strategy("nearest").commitment == 0.5
    assert make_strategy("hier").commitment == 1.0


@pytest.mark.parametrize(
    ("drop", "members"), [(False, [[1, 1], [2, 1], [3, 1], [3, 5], [3, 7]]), (True, [[1, 1], [2, 1], [3, 1]])]
)
def test_frontier_specks_are_dropped_before_clustering(drop: bool, members: list[list[int]]) -> None:
    # F_un: the left column (one 8-connected piece of 3 cells) and two single cells over the gaps in the
    # bottom wall, 2 columns apart (two pieces of 1). The 100th percentile makes one cluster of all F_un.
    state = state_grid("""
        #########
        ?.......#
        ?.......#
        ?.......#
        #####?#?#
    """)
    cfg = PreprocessConfig(bandwidth_percentile=100.0, drop_specks=drop)
    d = make_strategy("utility", preprocess_cfg=cfg).decide(DecisionInput(state, np.array([[2, 4]], np.int32), 0.05))
    assert d.clusters.members_rc.tolist() == members and d.clusters.sizes.tolist() == [len(members)]


def test_no_frontier_ends_the_mission_by_decision() -> None:
    state = state_grid("""
        #####
        #...#
        #####
    """)
    d = make_strategy("nearest").decide(DecisionInput(state, np.array([[1, 1]], np.int32), 0.05))
    assert d.done_reason == "no_frontiers"


def test_centre_plans_the_same_from_deltas_as_from_full_maps(small_map) -> None:
    runs = [
        run_mission(MissionSpec(small_map, make_strategy("hier"), mission_cfg=MissionConfig(transmission=mode), seed=2))
        for mode in ("delta", "full")
    ]
    strip = [{k: v for k, v in r.measures.to_dict().items() if k not in TIMING_KEYS} for r in runs]
    assert strip[0] == strip[1]
    m = runs[0].measures
    assert m.rounds == m.decisions and m.coverage >= 0.99
    assert m.bytes_sparse_delta < m.bytes_sparse < m.bytes_grid / 2
    assert m.reconstruction_iou_min >= 0.98 and m.reconstruction_iou_min <= m.reconstruction_iou_mean <= 1.0


def test_bad_transmission_mode_refused() -> None:
    with pytest.raises(MrExploreError, match=r"^transmission must be 'delta' or 'full', got 'zip'$"):
        MissionConfig(transmission="zip")


@pytest.mark.parametrize("k", [1, 10])
def test_vanished_goals_wait_min_replan_steps(small_map, k: int) -> None:
    # A decision sooner than k steps after the last one is only for a robot at its path's end (or blocked).
    decisions: list[tuple[int, bool]] = []  # (step, some robot was at its path's end or blocked)
    last: list[object] = [None]
    idle = [False]

    def observe(sim, decision, goals, status) -> None:
        if decision is not last[0]:
            decisions.append((sim.steps, idle[0]))
            last[0] = decision
        idle[0] = any(sim.at_path_end(i) or sim.path_ahead_blocked(i) for i in range(sim.n_robots))

    cfg = MissionConfig(min_replan_steps=k, replan_every_steps=1000)
    run_mission(MissionSpec(small_map, make_strategy("nearest"), SimConfig(robots=2), cfg, seed=1), observer=observe)
    gaps = [(b[0] - a[0], b[1]) for a, b in zip(decisions, decisions[1:], strict=False)]
    assert all(gap >= k or idle_then for gap, idle_then in gaps)
    assert any(gap < 10 and not idle_then for gap, idle_then in gaps) == (k == 1)  # k=1 replans for vanished goals


def test_bad_min_replan_steps_refused() -> None:
    with pytest.raises(MrExploreError, match=r"^min_replan_steps must be >= 1, got 0$"):
        MissionConfig(min_replan_steps=0)


@settings(max_examples=60, deadline=None)
@given(st.integers(0, 10**6), st.integers(1, 4), st.booleans())
def test_specks_dropped_sparsely_as_on_the_whole_grid(seed: int, min_size: int, blacklisted: bool) -> None:
    rng = np.random.default_rng(seed)
    un = np.zeros((30, 40), bool)
    un[5:25, 8:30] = rng.random((20, 22)) < 0.3  # pieces of every size inside a box of the grid
    blacklist = rng.random(un.shape) < 0.1 if blacklisted else None
    expected = un & ~blacklist if blacklist is not None else un.copy()
    labels, _ = ndimage.label(expected, structure=np.ones((3, 3)))
    expected &= np.bincount(labels.ravel())[labels] >= min_size
    got = denoised_frontier_cells(Frontiers(un, np.zeros_like(un)), blacklist, min_size)
    assert got.tolist() == np.argwhere(expected).tolist()


def test_the_fault_schedule_hands_out_each_fault_once_in_step_order() -> None:
    from mrexplore.config import FaultConfig
    from mrexplore.mission import FaultSchedule

    schedule = FaultSchedule(FaultConfig(robot_failures=((2, 30), (0, 10)), centre_restarts=(40, 20, 20)), 3)
    assert schedule.failures_due(9) == [] and schedule.failures_due(35) == [0, 2] and schedule.failures_due(99) == []
    assert schedule.restarts_due(19) == 0 and schedule.restarts_due(20) == 2 and schedule.restarts_due(40) == 1
    with pytest.raises(MrExploreError, match=r"^robot failure names robot 3, but the team has robots 0\.\.2; "):
        FaultSchedule(FaultConfig(robot_failures=((3, 5),)), 3)
