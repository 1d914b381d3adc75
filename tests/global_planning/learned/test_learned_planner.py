"""The learned planner as a strategy: the untrained network is exactly utility + Hungarian, the shipped
policy loads and explores, checkpoints round-trip, bad files give one clear error."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import torch
from policy_edit import edited_policy
from random_problems import random_problem as _random_problem

from mrexplore.config import LearnedConfig, MapConfig, SimConfig
from mrexplore.global_planning.classical import UtilityPlanner, utility_cost
from mrexplore.global_planning.learned.features import graph_inputs
from mrexplore.global_planning.learned.policy import LearnedPlanner
from mrexplore.maps.loaders import load_map
from mrexplore.mission import Mission, MissionSpec, run_mission
from mrexplore.pipeline import make_strategy
from mrexplore.training.checkpoint import VALUE_INPUTS, default_policy_path, load_policy, save_policy
from mrexplore.training.hier_net import MultiGraphNet, collate
from mrexplore.types import MrExploreError

TIMING = {"wall_s", "plan_ms_mean", "plan_ms_p95", "peak_mb", "onboard_ms_median", "onboard_ms_p95"}


def _untrained() -> MultiGraphNet:
    torch.manual_seed(0)
    return MultiGraphNet(LearnedConfig(), VALUE_INPUTS).eval()


def test_zero_residual_start_equals_utility_on_random_problems() -> None:
    rng = np.random.default_rng(0)
    planner, utility = LearnedPlanner(_untrained()), UtilityPlanner()
    for _ in range(200):
        p = _random_problem(rng)
        assert planner.assign(p).cluster_of_robot.tolist() == utility.assign(p).cluster_of_robot.tolist()


def test_a_silent_scoring_mlp_is_skipped_with_the_same_costs() -> None:
    """Where the scoring MLP's last layer is zero (the shipped policy), the planner reads the edge path alone
    (in float64) and leaves the attention blocks unrun: the whole network's costs to float32 rounding; any
    weight of that layer brings the whole network back."""
    net = _untrained()
    net.set_edge_weights([-2.3, -2.9, -2.5, -0.14, 1.2])
    planner = LearnedPlanner(net)
    assert net.scores_nothing()
    ran: list[int] = []
    net.robot_in.register_forward_hook(lambda *_: ran.append(1))
    rng = np.random.default_rng(3)
    for _ in range(100):
        p = _random_problem(rng)
        _, affinity = planner.affinity(p)
        with torch.no_grad():
            batch = collate([graph_inputs(p, net.cfg, planner.heuristic)])
            whole = net.residual(*net.encode(batch), batch)[0, : p.n_robots, : len(p.clusters)].double().numpy()
        cost = utility_cost(p, planner.heuristic) - net.cfg.base_scale * whole
        np.testing.assert_allclose(affinity, -cost / net.cfg.base_scale, rtol=1e-6, atol=1e-6)
    assert len(ran) == 100  # the hook: only the 100 whole-network checks above ran the blocks
    with torch.no_grad():
        net.score[-1].bias.fill_(0.5)
    assert not net.scores_nothing()
    planner.affinity(_random_problem(rng))
    assert len(ran) == 101


def test_zero_residual_hier_runs_exactly_as_hier_heuristic(tmp_path: Path) -> None:
    save_policy(tmp_path / "zero.npz", _untrained())
    truth = load_map("generated:5", MapConfig(resolution_m=0.1))
    a = run_mission(
        MissionSpec(truth, make_strategy("hier", policy=str(tmp_path / "zero.npz")), SimConfig(robots=3), seed=2)
    )
    b = run_mission(MissionSpec(truth, make_strategy("hier-heuristic"), SimConfig(robots=3), seed=2))
    da, db = a.measures.to_dict(), b.measures.to_dict()
    assert {k: v for k, v in da.items() if k not in TIMING} == {k: v for k, v in db.items() if k not in TIMING}


def test_shipped_policy_loads_by_default_and_explores() -> None:
    s = make_strategy("hier")
    assert s.policy is not None and s.policy["path"].endswith("pretrained/policy.npz") and len(s.policy["sha256"]) == 64
    assert Path(s.policy["path"]).stat().st_size < 2_000_000
    m = run_mission(
        MissionSpec(load_map("generated:3", MapConfig(resolution_m=0.1)), s, SimConfig(robots=2), seed=1)
    ).measures
    assert m.coverage >= 0.99


def test_checkpoint_round_trip(tmp_path: Path) -> None:
    net = _untrained()
    torch.nn.init.normal_(net.score[-1].weight)
    save_policy(tmp_path / "p.npz", net, {"note": "x"})
    loaded = load_policy(tmp_path / "p.npz")
    for (k, a), (_, b) in zip(net.state_dict().items(), loaded.net.state_dict().items(), strict=True):
        assert torch.equal(a, b), k
    assert loaded.meta["meta"] == {"note": "x"} and loaded.net.cfg == net.cfg


def test_bad_policy_files_give_one_line_errors(tmp_path: Path) -> None:
    with pytest.raises(MrExploreError, match=r"^policy file .*nope.npz not found; pass a file written by"):
        load_policy(tmp_path / "nope.npz")
    (tmp_path / "junk.npz").write_bytes(b"not a checkpoint")
    with pytest.raises(MrExploreError, match=r"^policy file .*junk.npz is not a mrexplore policy \(.*\); retrain it$"):
        load_policy(tmp_path / "junk.npz")
    torch.save({"format": "other"}, tmp_path / "other.pt")  # torch's format, as older versions wrote
    with pytest.raises(MrExploreError, match=r"is not a mrexplore policy \(no format tag\)"):
        load_policy(tmp_path / "other.pt")


def test_snapshot_restore_replays_exactly_and_pose_commit_equals_decide() -> None:
    truth = load_map("generated:2", MapConfig(resolution_m=0.1))

    def finish(m: Mission) -> dict:
        while m.advance():
            m.decide()
        return {k: v for k, v in m.result().measures.to_dict().items() if k not in TIMING}

    m = Mission(MissionSpec(truth, make_strategy("hier-heuristic"), SimConfig(robots=3), seed=4), progress=False)
    for _ in range(5):
        assert m.advance()
        m.decide()
    assert m.advance()
    snap = m.snapshot()
    first = finish(m)
    m.restore(snap)
    assert finish(m) == first
    # the same decisions taken in two halves
    m2 = Mission(MissionSpec(truth, make_strategy("hier-heuristic"), SimConfig(robots=3), seed=4), progress=False)
    while m2.advance():
        if m2.pose() is not None:
            m2.commit()
    assert {k: v for k, v in m2.result().measures.to_dict().items() if k not in TIMING} == first


def test_ncm_policy_round_trip_and_refusals(tmp_path: Path) -> None:
    from mrexplore.training.checkpoint import load_ncm_policy
    from mrexplore.training.ncm_net import NcmConfig, NcmNet

    torch.manual_seed(0)
    net = NcmNet(NcmConfig(hidden=16, blocks=2))
    save_policy(tmp_path / "n.npz", net, {"stage": "ppo3"})
    loaded = load_ncm_policy(tmp_path / "n.npz")
    assert loaded.net.cfg == net.cfg and loaded.meta["meta"] == {"stage": "ppo3"}
    for (k, a), (_, b) in zip(net.state_dict().items(), loaded.net.state_dict().items(), strict=True):
        assert torch.equal(a, b), k
    with pytest.raises(MrExploreError, match=r"is for the hier strategy, not ncm; pass one written by"):
        load_ncm_policy(default_policy_path())

    def huge(h: dict) -> None:
        h["ncm_config"]["hidden"] = 10**6

    def extra(h: dict) -> None:
        h["ncm_config"]["extra"] = 1

    edited_policy(tmp_path / "n.npz", tmp_path / "huge.npz", header=huge)
    with pytest.raises(MrExploreError, match=r"does not fit this network \(network sizes out of range: "):
        load_ncm_policy(tmp_path / "huge.npz")
    edited_policy(tmp_path / "n.npz", tmp_path / "extra.npz", header=extra)
    with pytest.raises(MrExploreError, match=r"does not fit this network \(its network config has other fields\)"):
        load_ncm_policy(tmp_path / "extra.npz")


@pytest.mark.parametrize("name", ["ncm", "ncm-sampled", "ncm-matched"])
def test_shipped_ncm_policy_loads_by_default_and_explores(name: str) -> None:
    s = make_strategy(name)
    assert s.policy is not None and s.policy["path"].endswith("pretrained/ncm.npz")
    assert Path(s.policy["path"]).stat().st_size < 2_000_000
    m = run_mission(
        MissionSpec(load_map("generated:3", MapConfig(resolution_m=0.1)), s, SimConfig(robots=2), seed=1)
    ).measures
    assert m.coverage >= 0.99 and m.done_reason == "no_frontiers"


def test_a_learned_planner_runs_torch_on_one_thread() -> None:
    from random_problems import random_problem

    torch.set_num_threads(2)
    net = MultiGraphNet(LearnedConfig())
    torch.nn.init.normal_(net.score[-1].weight)  # a scoring MLP that adds something: the torch path runs
    LearnedPlanner(net).assign(random_problem(np.random.default_rng(0)))
    assert torch.get_num_threads() == 1


def test_hier_predict_is_hier_over_the_predictive_cost() -> None:
    """``hier-predict``'s cost is hier's less ``gain_weight`` per m^2 of predicted gain; at weight 0 it decides
    as hier does."""
    from dataclasses import replace

    from random_problems import random_problem

    from mrexplore.config import GlobalPlanningConfig
    from mrexplore.global_planning.predictive import predicted_terms
    from mrexplore.pipeline import make_strategy
    from mrexplore.types import CellState

    rng = np.random.default_rng(11)
    hier = make_strategy("hier").planner
    weighted = make_strategy("hier-predict", GlobalPlanningConfig(gain_weight=-0.5), predictor="none").planner
    neutral = make_strategy("hier-predict", GlobalPlanningConfig(gain_weight=0.0), predictor="none").planner
    for _ in range(30):
        states = np.array([CellState.FREE, CellState.UNKNOWN, CellState.OCCUPIED], np.uint8)
        problem = replace(random_problem(rng), state=states[rng.choice(3, size=(50, 50), p=[0.5, 0.4, 0.1])])
        gains = predicted_terms(None, problem, GlobalPlanningConfig()).gain_m2
        _, cost_hier = hier._cost(problem)
        _, cost_pred = weighted._cost(problem)
        reachable = np.isfinite(cost_hier)
        assert np.array_equal(reachable, np.isfinite(cost_pred))
        expected = np.broadcast_to(0.5 * gains, cost_hier.shape)[reachable]
        np.testing.assert_allclose(cost_pred[reachable] - cost_hier[reachable], expected)
        assert neutral.assign(problem).cluster_of_robot.tolist() == hier.assign(problem).cluster_of_robot.tolist()


def test_a_lone_robot_decides_by_the_heuristic_unless_told_otherwise() -> None:
    """Under ``learned_min_robots`` (default 2) hier adds no residual: a lone robot's choice is utility's on
    every problem, though the shipped residual would choose otherwise on some; a team of two keeps it."""
    from dataclasses import replace

    from mrexplore.config import GlobalPlanningConfig

    rng = np.random.default_rng(5)
    gated, always = (
        make_strategy("hier").planner,
        make_strategy("hier", GlobalPlanningConfig(learned_min_robots=1)).planner,
    )
    utility = UtilityPlanner()
    lone_differs = team_differs = 0
    for _ in range(300):
        p = _random_problem(rng)
        lone = replace(p, robots_rc=p.robots_rc[:1], dist_cells=p.dist_cells[:1], current_cluster=p.current_cluster[:1])
        assert gated.assign(lone).cluster_of_robot.tolist() == utility.assign(lone).cluster_of_robot.tolist()
        lone_differs += always.assign(lone).cluster_of_robot.tolist() != utility.assign(lone).cluster_of_robot.tolist()
        if p.n_robots >= 2:
            assert gated.assign(p).cluster_of_robot.tolist() == always.assign(p).cluster_of_robot.tolist()
            team_differs += gated.assign(p).cluster_of_robot.tolist() != utility.assign(p).cluster_of_robot.tolist()
    assert lone_differs > 0 and team_differs > 0


def test_lone_hier_runs_exactly_as_hier_heuristic() -> None:
    truth = load_map("generated:5", MapConfig(resolution_m=0.1))
    a = run_mission(MissionSpec(truth, make_strategy("hier"), SimConfig(robots=1), seed=2))
    b = run_mission(MissionSpec(truth, make_strategy("hier-heuristic"), SimConfig(robots=1), seed=2))
    da, db = a.measures.to_dict(), b.measures.to_dict()
    assert {k: v for k, v in da.items() if k not in TIMING} == {k: v for k, v in db.items() if k not in TIMING}
