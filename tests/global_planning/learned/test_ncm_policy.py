"""NCM's per-robot distribution: log-probabilities against enumeration, entropy, sampling, masks."""

from __future__ import annotations

import itertools
import math

import torch

from mrexplore.global_planning.learned.ncm_planner import first_best
from mrexplore.training.ncm_policy import (
    per_robot_entropy,
    per_robot_log_prob,
    per_robot_sample,
    robot_logits,
)
from mrexplore.training.sinkhorn import log_optimal_transport


def test_log_prob_sums_to_one_over_every_joint_action_and_factorises() -> None:
    g = torch.Generator().manual_seed(0)
    scores = torch.randn(2, 3, generator=g, dtype=torch.float64)
    logits = robot_logits(log_optimal_transport(scores, torch.tensor(0.2, dtype=torch.float64), iters=5))
    joint = {
        (a, b): per_robot_log_prob(logits, torch.tensor([a, b])).exp().item()
        for a, b in itertools.product(range(3), repeat=2)
    }
    assert math.isclose(sum(joint.values()), 1.0, rel_tol=1e-12)
    rows = torch.softmax(logits, dim=1)
    assert all(math.isclose(p, rows[0, a].item() * rows[1, b].item(), rel_tol=1e-12) for (a, b), p in joint.items())
    # two robots may take the same node: the pair (1, 1) has positive probability
    assert joint[(1, 1)] > 0
    h = -sum(p * math.log(p) for p in joint.values())
    assert math.isclose(per_robot_entropy(logits).item(), h, rel_tol=1e-10)


def test_masked_nodes_are_never_drawn_and_argmax_is_per_robot() -> None:
    logits = torch.tensor([[0.0, 5.0, 1.0], [3.0, 0.0, 2.0]])
    mask = torch.tensor([[True, False, True], [True, True, True]])
    masked = robot_logits(torch.nn.functional.pad(logits, (0, 1, 0, 1)), mask)
    assert first_best(masked.numpy()).tolist() == [2, 0]
    g = torch.Generator().manual_seed(1)
    draws = torch.stack([per_robot_sample(masked, g) for _ in range(300)])
    assert not (draws[:, 0] == 1).any() and set(draws[:, 1].tolist()) == {0, 1, 2}
    assert per_robot_log_prob(masked, torch.tensor([1, 0])).item() == -math.inf
