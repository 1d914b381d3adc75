"""Learning works: on toy assignments whose optimum is known and differs from the heuristic's, the listwise
imitation and PPO both move the network to it."""

from __future__ import annotations

import itertools

import numpy as np
import torch

from mrexplore.config import LearnedConfig, TrainConfig
from mrexplore.global_planning.learned.features import CLUSTER_FEATURES, EDGE_FEATURES, ROBOT_FEATURES, GraphInputs
from mrexplore.global_planning.learned.policy import hungarian_decode, sample_sequential
from mrexplore.training.expert import ExpertLabel
from mrexplore.training.hier_net import MultiGraphNet, collate
from mrexplore.training.ppo import ppo_loss
from mrexplore.training.sequential import sequential_log_prob
from mrexplore.training.updates import fit_imitation

R, C = 2, 3
MATCHINGS = np.array(list(itertools.permutations(range(C), R)), dtype=np.int64)  # 6 candidates


def _toy(rng: np.random.Generator) -> tuple[GraphInputs, np.ndarray]:
    """Random decision; the true return is 4 x the summed isolation of the chosen clusters (a feature the
    heuristic ignores) plus the heuristic's own affinity."""
    isolation = rng.uniform(0, 2, size=C).astype(np.float32)
    edges = rng.normal(size=(R, C, EDGE_FEATURES)).astype(np.float32)
    edges[..., 4] = isolation[None, :]
    base = rng.normal(size=(R, C)).astype(np.float32)
    g = GraphInputs(
        rng.normal(size=(R, ROBOT_FEATURES)).astype(np.float32),
        rng.normal(size=(C, CLUSTER_FEATURES)).astype(np.float32),
        edges,
        np.ones((R, C), bool),
        base,
    )
    returns = np.array([4 * isolation[m].sum() + base[np.arange(R), m].sum() for m in MATCHINGS])
    return g, returns


def _hit_rate(net: MultiGraphNet, problems: list[tuple[GraphInputs, np.ndarray]]) -> float:
    with torch.no_grad():
        aff = net(collate([g for g, _ in problems]))[0].double().numpy()
    hits = 0
    for a, (_, ret) in zip(aff, problems, strict=True):
        best = MATCHINGS[int(np.argmax(ret))]
        hits += hungarian_decode(a).tolist() == best.tolist()
    return hits / len(problems)


def test_listwise_imitation_learns_the_known_optimum() -> None:
    rng = np.random.default_rng(0)
    torch.manual_seed(0)
    train = [_toy(rng) for _ in range(256)]
    test = [_toy(rng) for _ in range(100)]
    net = MultiGraphNet(LearnedConfig(), value_inputs=4)
    before = _hit_rate(net, test)  # the heuristic alone
    data = [ExpertLabel(g, MATCHINGS, r) for g, r in train]
    opt = torch.optim.Adam(net.parameters(), lr=3e-3)
    fit_imitation(net, opt, data, TrainConfig(imitation_epochs=40, return_temperature=0.5, residual_l2=0.0), rng)
    after = _hit_rate(net, test)
    assert before < 0.5
    assert after >= 0.85, (before, after)


def test_ppo_learns_a_one_robot_bandit() -> None:
    # One robot, two clusters; the heuristic prefers cluster 0, only cluster 1 pays.
    torch.manual_seed(1)
    rng = np.random.default_rng(1)
    net = MultiGraphNet(LearnedConfig(), value_inputs=0)
    g = GraphInputs(
        np.zeros((1, ROBOT_FEATURES), np.float32),
        np.eye(2, CLUSTER_FEATURES, dtype=np.float32),
        np.zeros((1, 2, EDGE_FEATURES), np.float32),
        np.ones((1, 2), bool),
        np.array([[0.0, -1.0]], np.float32),
    )
    batch = collate([g] * 32)
    opt = torch.optim.Adam(net.parameters(), lr=3e-3)

    def p_cluster_1() -> float:
        with torch.no_grad():
            return float(torch.softmax(net(collate([g]))[0][0, 0], -1)[1])

    start = p_cluster_1()
    for _ in range(40):
        with torch.no_grad():
            aff = net(batch)[0].double().numpy()
        draws = [sample_sequential(a, rng) for a in aff]
        order = torch.tensor(np.stack([d[0] for d in draws]))
        choices = torch.tensor(np.stack([d[1] for d in draws]))
        old = torch.tensor([d[2] for d in draws], dtype=torch.float32)
        reward = (choices[:, 0] == 1).float()
        adv = reward - reward.mean()
        for _ in range(4):
            logp, ent = sequential_log_prob(net(batch)[0], order, choices)
            loss, _ = ppo_loss(logp, old, adv, torch.zeros(32), torch.zeros(32), ent, 0.2, 0.0, 0.0)
            opt.zero_grad()
            loss.backward()
            opt.step()
    assert start < 0.3 and p_cluster_1() > 0.9
