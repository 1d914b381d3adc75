"""The mGNN: padding leaves outputs unchanged, permuting robots and clusters permutes them, any team size."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from mrexplore.config import LearnedConfig
from mrexplore.global_planning.learned.features import CLUSTER_FEATURES, EDGE_FEATURES, ROBOT_FEATURES, GraphInputs
from mrexplore.training.hier_net import MultiGraphNet, collate


def _random_inputs(rng: np.random.Generator, R: int, C: int) -> GraphInputs:
    reachable = rng.random((R, C)) < 0.8
    return GraphInputs(
        rng.normal(size=(R, ROBOT_FEATURES)).astype(np.float32),
        rng.normal(size=(C, CLUSTER_FEATURES)).astype(np.float32),
        rng.normal(size=(R, C, EDGE_FEATURES)).astype(np.float32),
        reachable,
        rng.normal(size=(R, C)).astype(np.float32),
    )


@pytest.fixture(scope="module")
def net() -> MultiGraphNet:
    torch.manual_seed(0)
    n = MultiGraphNet(LearnedConfig(), value_inputs=4)
    # a trained-looking network: the residual's zero-initialised last layer is randomised too
    torch.nn.init.normal_(n.score[-1].weight, std=0.5)
    n.set_edge_weights([1.0, -2.0, 0.5, 3.0, -1.0])  # and the linear edge path
    return n.eval()


def _aff(net: MultiGraphNet, items: list[GraphInputs]) -> torch.Tensor:
    with torch.no_grad():
        return net(collate(items))[0]


def test_padding_leaves_outputs_unchanged(net: MultiGraphNet) -> None:
    rng = np.random.default_rng(0)
    small, large = _random_inputs(rng, 2, 3), _random_inputs(rng, 7, 11)
    alone = _aff(net, [small])[0]
    padded = _aff(net, [small, large])[0]  # padded to 7 robots x 11 clusters
    assert torch.allclose(padded[:2, :3], alone, atol=1e-5)
    assert torch.isinf(padded[2:]).all() and torch.isinf(padded[:, 3:]).all()


def test_permutation_equivariance(net: MultiGraphNet) -> None:
    rng = np.random.default_rng(1)
    g = _random_inputs(rng, 5, 8)
    pr, pc = rng.permutation(5), rng.permutation(8)
    h = GraphInputs(g.robots[pr], g.clusters[pc], g.edges[pr][:, pc], g.reachable[pr][:, pc], g.base[pr][:, pc])
    a, b = _aff(net, [g])[0], _aff(net, [h])[0]
    assert torch.allclose(a[pr][:, pc], b, atol=1e-5)


@pytest.mark.parametrize(("R", "C"), [(1, 1), (1, 60), (16, 3), (16, 60), (4, 2)])
def test_any_team_and_cluster_count(net: MultiGraphNet, R: int, C: int) -> None:
    g = _random_inputs(np.random.default_rng(R * 100 + C), R, C)
    a = _aff(net, [g])[0]
    assert a.shape == (R, C)
    assert torch.isfinite(a[torch.from_numpy(g.reachable)]).all()
    assert torch.isinf(a[~torch.from_numpy(g.reachable)]).all()


def test_untrained_residual_is_zero_and_gradients_are_finite() -> None:
    torch.manual_seed(3)
    n = MultiGraphNet(LearnedConfig(), value_inputs=4)
    g = _random_inputs(np.random.default_rng(3), 3, 4)
    batch = collate([g])
    aff, vr, vc = n(batch)
    reach = torch.from_numpy(g.reachable)
    assert torch.equal(aff[0][reach], batch.base[0][reach])  # an untrained network is the heuristic
    robot_without_cluster = collate([GraphInputs(g.robots, g.clusters, g.edges, np.zeros_like(g.reachable), g.base)])
    aff2, vr2, vc2 = n(robot_without_cluster)  # no pair allowed anywhere: attention rows with no key
    loss = vr2.sum() + vc2.sum() + n.value_of(vr2, vc2, robot_without_cluster, torch.zeros(1, 4)).sum()
    loss.backward()
    assert all(torch.isfinite(p.grad).all() for p in n.parameters() if p.grad is not None)


def test_edge_path_adds_edge_features_times_its_weights() -> None:
    n = MultiGraphNet(LearnedConfig(), value_inputs=4)
    w = np.array([1.0, -2.0, 0.5, 3.0, -1.0])
    n.set_edge_weights(w)
    assert n.edge_weights.tolist() == w.tolist()
    g = _random_inputs(np.random.default_rng(4), 3, 5)
    aff = _aff(n, [g])[0].numpy()
    reach = g.reachable
    # the scoring MLP's last layer is still zero: the residual is exactly edges . w
    assert np.allclose(aff[reach] - g.base[reach], (g.edges.astype(np.float64) @ w)[reach], atol=1e-5)


def test_gradients_never_move_the_edge_path() -> None:
    n = MultiGraphNet(LearnedConfig(), value_inputs=4)
    n.set_edge_weights([0.0, 0.0, -5.0, 0.0, 5.0])
    g = _random_inputs(np.random.default_rng(5), 2, 3)
    aff, _, _ = n(collate([g]))
    aff[torch.isfinite(aff)].sum().backward()
    assert n.edge_head.weight.grad is None and n.score[-1].weight.grad is not None


def test_a_policy_saved_before_the_edge_path_loads_with_it_at_zero() -> None:
    old = MultiGraphNet(LearnedConfig(), value_inputs=4).state_dict()
    del old["edge_head.weight"]
    n = MultiGraphNet(LearnedConfig(), value_inputs=4)
    n.set_edge_weights([1.0, 1.0, 1.0, 1.0, 1.0])
    n.load_state_dict(old)
    assert n.edge_weights.tolist() == [0.0] * EDGE_FEATURES
    del old["score.0.weight"]  # any other missing weight is still an error
    with pytest.raises(RuntimeError, match="Missing key"):
        n.load_state_dict(old)
