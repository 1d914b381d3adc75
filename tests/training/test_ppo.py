"""The training maths against hand-computed numbers: GAE over decisions of unequal length, the PPO loss,
the listwise loss."""

from __future__ import annotations

import math

import numpy as np
import pytest
import torch

from mrexplore.training.ppo import gae, listwise_loss, ppo_loss


def test_gae_by_hand() -> None:
    # Three decisions; the second lasted 2 steps (discount 0.9^2 = 0.81), the third ended the episode.
    r = np.array([1.0, 2.0, 3.0])
    v = np.array([0.5, 1.0, 1.5])
    d = np.array([0.9, 0.81, 0.0])
    lam = 0.5
    # deltas: d2 = 3 - 1.5 = 1.5; d1 = 2 + 0.81 * 1.5 - 1.0 = 2.215; d0 = 1 + 0.9 * 1.0 - 0.5 = 1.4
    # advantages: A2 = 1.5; A1 = 2.215 + 0.81 * 0.5 * 1.5 = 2.8225; A0 = 1.4 + 0.9 * 0.5 * 2.8225 = 2.670125
    adv, ret = gae(r, v, d, last_value=7.0, lam=lam)  # last_value unused: the last discount is 0
    assert adv == pytest.approx([2.670125, 2.8225, 1.5])
    assert ret == pytest.approx([3.170125, 3.8225, 3.0])


def test_gae_bootstraps_a_cut_trajectory_and_lambda_one_is_the_discounted_return() -> None:
    r = np.array([1.0, 1.0])
    adv, ret = gae(r, np.zeros(2), np.array([0.5, 0.5]), last_value=4.0, lam=1.0)
    assert ret.tolist() == [1.0 + 0.5 * (1.0 + 0.5 * 4.0), 1.0 + 0.5 * 4.0]


def test_ppo_loss_by_hand() -> None:
    t = torch.tensor
    old = t([0.0, 0.0])
    new = t([math.log(1.5), math.log(0.5)])  # ratios 1.5 and 0.5
    adv = t([1.0, -1.0])
    # sample 0: min(1.5 * 1, clip(1.5) = 1.2 * 1) = 1.2; sample 1: min(0.5 * -1, 0.8 * -1) = -0.8
    # policy = -(1.2 - 0.8) / 2 = -0.2; value = ((1 - 0)^2 + (2 - 4)^2) / 2 = 2.5; entropy = 0.3
    loss, s = ppo_loss(new, old, adv, t([1.0, 2.0]), t([0.0, 4.0]), t([0.2, 0.4]), 0.2, 0.5, 0.1)
    assert float(loss) == pytest.approx(-0.2 + 0.5 * 2.5 - 0.1 * 0.3)
    assert s.policy == pytest.approx(-0.2) and s.value == pytest.approx(2.5)
    assert s.clip_fraction == 1.0  # both ratios left [0.8, 1.2]
    assert s.approx_kl == pytest.approx((0 - math.log(1.5) + 0 - math.log(0.5)) / 2)


def test_ppo_gradient_stops_outside_the_clip() -> None:
    new = torch.tensor([math.log(1.5)], requires_grad=True)
    loss, _ = ppo_loss(new, torch.zeros(1), torch.ones(1), torch.zeros(1), torch.zeros(1), torch.zeros(1), 0.2, 0, 0)
    loss.backward()
    assert new.grad is not None and float(new.grad) == 0.0  # clipped: no push further up


def test_listwise_loss_by_hand() -> None:
    t = torch.tensor
    # target softmax([0, ln 3]) = [1/4, 3/4]; student softmax([0, 0]) = [1/2, 1/2]: loss = ln 2
    loss = listwise_loss(t([[0.0, 0.0, 5.0]]), t([[0.0, math.log(3.0), 9.0]]), t([[True, True, False]]), 1.0)
    assert float(loss) == pytest.approx(math.log(2.0), abs=1e-6)
    # scores that match the target's ranking exactly reach the target's entropy, the minimum
    best = listwise_loss(t([[0.0, math.log(3.0)]]), t([[0.0, math.log(3.0)]]), t([[True, True]]), 1.0)
    entropy = -(0.25 * math.log(0.25) + 0.75 * math.log(0.75))
    assert float(best) == pytest.approx(entropy, abs=1e-6)
