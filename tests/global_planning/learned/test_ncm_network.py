"""NCM's network: padding changes nothing, robots and nodes permute with their outputs, masks hold."""

from __future__ import annotations

import pytest
import torch

from mrexplore.training.ncm_net import NcmBatch, NcmConfig, NcmNet


def _decision(m: int, n: int, seed: int) -> dict[str, torch.Tensor]:
    g = torch.Generator().manual_seed(seed)
    allowed = torch.rand(m, n, generator=g) > 0.25
    allowed[:, 0] = True  # every robot may go somewhere
    return {
        "robots_xy": torch.rand(m, 2, generator=g),
        "nodes_xy": torch.rand(n, 2, generator=g),
        "dist": torch.rand(m, n, generator=g) * 3,
        "allowed": allowed,
    }


def _batch(decisions: list[dict[str, torch.Tensor]]) -> NcmBatch:
    B = len(decisions)
    R = max(d["robots_xy"].shape[0] for d in decisions)
    N = max(d["nodes_xy"].shape[0] for d in decisions)
    out = NcmBatch(
        torch.zeros(B, R, 2),
        torch.zeros(B, N, 2),
        torch.full((B, R, N), 7.0),
        torch.zeros(B, R, N, dtype=torch.bool),
        torch.zeros(B, R, dtype=torch.bool),
        torch.zeros(B, N, dtype=torch.bool),
    )
    for i, d in enumerate(decisions):
        m, n = d["dist"].shape
        out.robots_xy[i, :m], out.nodes_xy[i, :n], out.dist[i, :m, :n] = d["robots_xy"], d["nodes_xy"], d["dist"]
        out.allowed[i, :m, :n], out.robot_mask[i, :m], out.node_mask[i, :n] = d["allowed"], True, True
    return out


def test_padding_changes_no_output() -> None:
    torch.manual_seed(0)
    net = NcmNet(NcmConfig(hidden=16, blocks=2)).eval()
    small, big = _decision(2, 3, 1), _decision(5, 8, 2)
    with torch.no_grad():
        alone = net(_batch([small]))[0]
        padded = net(_batch([small, big]))[0]
    assert torch.allclose(alone, padded[:2, :3], atol=1e-5)
    assert torch.isinf(padded[2:]).all() and torch.isinf(padded[:, 3:]).all()


def test_robots_and_nodes_permute_with_their_outputs() -> None:
    torch.manual_seed(1)
    net = NcmNet(NcmConfig(hidden=16, blocks=2)).eval()
    d = _decision(3, 5, 3)
    pr, pn = torch.tensor([2, 0, 1]), torch.tensor([4, 1, 3, 0, 2])
    perm = {
        "robots_xy": d["robots_xy"][pr],
        "nodes_xy": d["nodes_xy"][pn],
        "dist": d["dist"][pr][:, pn],
        "allowed": d["allowed"][pr][:, pn],
    }
    with torch.no_grad():
        a, b = net(_batch([d]))[0], net(_batch([perm]))[0]
    assert torch.allclose(a[pr][:, pn], b, atol=1e-5)


def test_masked_pairs_are_impossible_and_gradients_reach_every_part() -> None:
    torch.manual_seed(2)
    net = NcmNet(NcmConfig(hidden=16, blocks=1))
    d = _decision(3, 4, 4)
    logits = net(_batch([d]))[0]
    assert torch.isinf(logits[~d["allowed"]]).all() and torch.isfinite(logits[d["allowed"]]).all()
    logp = torch.log_softmax(logits, dim=1)
    logp[torch.arange(3), torch.zeros(3, dtype=torch.long)].sum().backward()
    assert net.dustbin.grad is not None and torch.isfinite(net.dustbin.grad)
    assert all(p.grad is not None for p in net.parameters())


def test_the_ncm_pipeline_decides_on_pooled_nodes_and_explores_a_map() -> None:
    """On the seam: candidates are 0.4 m nodes of the clear frontier, each robot takes its best node
    (deterministic) or draws one (sampled, seeded); a mission with an untrained network still ends."""
    import numpy as np
    from conftest import state_grid

    from mrexplore.config import MapConfig, MissionConfig, SimConfig
    from mrexplore.global_planning.learned.ncm_planner import NcmPlanner
    from mrexplore.maps.loaders import load_map
    from mrexplore.mission import MissionSpec, run_mission
    from mrexplore.pipeline import DecisionInput, NcmPipeline

    torch.manual_seed(3)
    grid = state_grid(
        """
        ############
        #..........?
        #..........?
        #..........?
        #..........?
        #..........?
        ############
        """
    )
    pipeline = NcmPipeline("ncm", NcmPlanner(NcmNet()))
    d = pipeline.decide(DecisionInput(grid, np.array([[3, 2], [3, 4]], np.int32), 0.1))
    # F_un is column 10, rows 1-5; rows 1-2 and 4-5 lie within 0.2 m of a wall, so one clear cell, (3, 10),
    # and one node; both robots may take it (NCM's robots choose independently).
    assert d.clusters.centers_rc.tolist() == [[3, 10]]
    assert d.goals_rc.tolist() == [[3, 10], [3, 10]]
    truth = load_map("generated:3", MapConfig(resolution_m=0.2))
    for sample in (False, True):
        planner = NcmPlanner(NcmNet(), sample=sample)
        m = run_mission(
            MissionSpec(truth, NcmPipeline("ncm", planner), SimConfig(robots=2), MissionConfig(max_steps=3000), seed=1)
        )
        assert m.measures.done_reason == "no_frontiers" and m.measures.coverage >= 0.99


def _problem(robots_rc: list[list[int]], centres_rc: list[list[int]], dist_cells: list[list[float]]):  # noqa: ANN202
    import numpy as np

    from mrexplore.global_planning.protocol import AssignmentProblem
    from mrexplore.preprocessing.clustering import Clusters

    centres = np.array(centres_rc, np.int32)
    k = len(centres)
    clusters = Clusters(centres, np.ones(k, np.int32), centres, np.arange(k, dtype=np.int32))
    state = np.zeros((1, 1), np.uint8)  # the network reads no grid
    return AssignmentProblem(np.array(robots_rc, np.int32), clusters, np.array(dist_cells, np.float64), 0.1, state)


def test_window_masks_far_nodes_unless_a_robot_has_none_near() -> None:
    """At 0.1 m cells: robot 0 has node 0 within its 24 m window (10 m) and nodes 1 and 2 beyond it (30 m,
    60 m): only node 0. Robot 1's nearest node is 30 m away, so none is in its window: it may take any
    reachable one (nodes 0 and 2; node 1 is unreachable)."""
    import math

    from mrexplore.global_planning.learned.ncm_inputs import ncm_inputs

    inf = math.inf
    p = _problem(
        [[0, 0], [0, 900]],
        [[0, 100], [0, 300], [0, 600]],  # 10 m, 30 m, 60 m from robot 0; 80 m, 60 m, 30 m from robot 1
        [[100, 300, 600], [800, inf, 300]],
    )
    x = ncm_inputs(p)
    assert x.allowed.tolist() == [[True, False, False], [True, False, True]]
    assert x.dist[1, 1] == 0.0 and x.dist[0, 0] == pytest.approx(100 * 0.1 / 24.0)
    assert x.robots_xy.tolist() == [[0.0, 0.0], [0.0, 90 / 24]]


def test_critic_ignores_padding_and_log_prob_matches_the_policy() -> None:
    import numpy as np

    from mrexplore.training.ncm_net import (
        NcmCritic,
        NcmInputs,
        NcmStep,
        ncm_collate,
        ncm_log_prob,
    )
    from mrexplore.training.ncm_policy import per_robot_log_prob

    torch.manual_seed(4)

    def inputs(m: int, n: int, seed: int) -> NcmInputs:
        d = _decision(m, n, seed)
        return NcmInputs(*(d[k].numpy() for k in ("robots_xy", "nodes_xy", "dist", "allowed")))

    small, big = inputs(2, 3, 5), inputs(4, 7, 6)
    critic = NcmCritic(hidden=8, extra=2).eval()
    extra = torch.tensor([[0.5, 1.0], [0.0, 2.0]])
    with torch.no_grad():
        alone = critic(ncm_collate([small]), extra[:1])
        both = critic(ncm_collate([small, big]), extra)
    assert torch.allclose(alone, both[:1], atol=1e-6)
    net = NcmNet(NcmConfig(hidden=16, blocks=1)).eval()
    # robot 1 of the big decision got no node (as when it had none allowed): it adds nothing
    targets = [np.array([0, 0]), np.array([0, -1, 0, 0])]
    steps = [NcmStep(x, t, 0.0, 0.0, np.zeros(2, np.float32)) for x, t in zip((small, big), targets, strict=True)]
    with torch.no_grad():
        logp, ent = ncm_log_prob(net, steps)
        logits = net(ncm_collate([big]))[0]
    want = per_robot_log_prob(logits[[0, 2, 3]], torch.tensor([0, 0, 0]))
    assert torch.allclose(logp[1], want, atol=1e-5) and (ent >= 0).all()


def test_matched_decoding_spreads_robots_that_stand_together() -> None:
    """Two robots in one cell have equal rows of the plan: argmax sends both to the same node for ever
    (on Willow Garage two of three robots shared every goal from step 30 on); the matched decoding of the
    same logits gives them different nodes, and a third robot shares once the two nodes are taken."""
    from mrexplore.global_planning.learned.ncm_planner import NcmPlanner

    torch.manual_seed(5)
    net = NcmNet().eval()
    p = _problem([[0, 0], [0, 0]], [[0, 100], [0, 150]], [[100, 150], [100, 150]])
    argmax = NcmPlanner(net).assign(p).cluster_of_robot.tolist()
    assert argmax[0] == argmax[1]
    assert sorted(NcmPlanner(net, match=True).assign(p).cluster_of_robot.tolist()) == [0, 1]
    three = _problem([[0, 0], [0, 0], [0, 0]], [[0, 100], [0, 150]], [[100, 150]] * 3)
    assert sorted(NcmPlanner(net, match=True).assign(three).cluster_of_robot.tolist()) in ([0, 0, 1], [0, 1, 1])
