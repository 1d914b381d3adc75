"""The maths of training, as pure functions: GAE over decisions of unequal length, the PPO loss, the
listwise loss that ranks an expert's candidates."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import torch
from numpy.typing import NDArray
from torch import Tensor

__all__ = ["gae", "ppo_loss", "PPOStats", "listwise_loss"]


def gae(
    rewards: NDArray[np.floating],
    values: NDArray[np.floating],
    discounts: NDArray[np.floating],
    last_value: float,
    lam: float,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Generalised advantage estimation (Schulman et al. 2016) for one trajectory of decisions.

    ``discounts[t]`` is the factor from decision t to t+1: gamma^k for a decision whose interval lasted
    k simulation steps (a semi-MDP), 0 after the last decision of a finished episode. ``last_value`` is
    the critic's value after the trajectory (0 when it ended). Returns advantages and returns (advantage
    + value), ``(T,) float64`` each.

    Examples
    --------
    >>> adv, ret = gae(np.array([1.0, 1.0]), np.array([0.0, 0.0]), np.array([0.5, 0.0]), 0.0, 1.0)
    >>> adv.tolist(), ret.tolist()
    ([1.5, 1.0], [1.5, 1.0])
    """
    T = len(rewards)
    adv = np.zeros(T, dtype=np.float64)
    running = 0.0
    for t in reversed(range(T)):
        next_value = last_value if t == T - 1 else float(values[t + 1])
        delta = float(rewards[t]) + float(discounts[t]) * next_value - float(values[t])
        running = delta + float(discounts[t]) * lam * running
        adv[t] = running
    return adv, adv + np.asarray(values, dtype=np.float64)


@dataclass(frozen=True)
class PPOStats:
    """Parts of one PPO loss, for the log."""

    policy: float
    value: float
    entropy: float
    approx_kl: float
    clip_fraction: float


def ppo_loss(
    new_logp: Tensor,
    old_logp: Tensor,
    advantages: Tensor,
    new_values: Tensor,
    returns: Tensor,
    entropy: Tensor,
    clip: float,
    value_coef: float,
    entropy_coef: float,
) -> tuple[Tensor, PPOStats]:
    """Clipped surrogate (Schulman et al. 2017) + value_coef * MSE - entropy_coef * entropy, averaged.

    Examples
    --------
    >>> t = torch.tensor
    >>> loss, s = ppo_loss(t([0.0]), t([0.0]), t([2.0]), t([1.0]), t([3.0]), t([0.5]), 0.2, 0.5, 0.1)
    >>> round(float(loss), 4)  # -(1 * 2) + 0.5 * (1 - 3)^2 - 0.1 * 0.5
    -0.05
    """
    ratio = torch.exp(new_logp - old_logp)
    surrogate = torch.minimum(ratio * advantages, torch.clamp(ratio, 1 - clip, 1 + clip) * advantages)
    policy = -surrogate.mean()
    value = ((new_values - returns) ** 2).mean()
    ent = entropy.mean()
    loss = policy + value_coef * value - entropy_coef * ent
    with torch.no_grad():
        kl = float((old_logp - new_logp).mean())
        clipped = float(((ratio - 1).abs() > clip).float().mean())
    return loss, PPOStats(float(policy.detach()), float(value.detach()), float(ent.detach()), kl, clipped)


def listwise_loss(scores: Tensor, returns: Tensor, valid: Tensor, temperature: float) -> Tensor:
    """ListNet (Cao et al. 2007): cross-entropy between softmax(candidate returns / temperature), the
    expert's ranking, and softmax(scores), the student's; candidates with equal returns share the target
    mass, so ties teach nothing. ``scores``, ``returns``, ``valid`` ``(B, M)``; mean over the batch.

    Examples
    --------
    >>> t = torch.tensor
    >>> round(float(listwise_loss(t([[0.0, 0.0]]), t([[1.0, 1.0]]), t([[True, True]]), 1.0)), 4)  # ln 2
    0.6931
    """
    neg = torch.full_like(scores, -1e9)
    target = torch.softmax(torch.where(valid, returns / temperature, neg), dim=-1) * valid
    logq = torch.log_softmax(torch.where(valid, scores, neg), dim=-1)
    return -(target * torch.where(valid, logq, torch.zeros_like(logq))).sum(-1).mean()
