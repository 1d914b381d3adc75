"""NeuralCoMapping's action distribution: every robot draws its own target node from its row of the
transport plan (independent categoricals; two robots may draw the same node), or takes the row's argmax
for the deterministic variant (:mod:`~mrexplore.global_planning.learned.ncm_planner`, in NumPy). The joint
log-probability is the sum of the robots' own."""

from __future__ import annotations

import torch

__all__ = [
    "robot_logits",
    "per_robot_log_prob",
    "per_robot_entropy",
    "per_robot_sample",
]


def robot_logits(log_plan: torch.Tensor, mask: torch.Tensor | None = None) -> torch.Tensor:
    """``(m, n)`` logits of each robot over the real nodes: the plan's rows without the dustbin column and
    row, ``-inf`` where ``mask`` (``(m, n) bool``) forbids the pair."""
    logits = log_plan[:-1, :-1]
    return logits if mask is None else logits.masked_fill(~mask, float("-inf"))


def per_robot_log_prob(logits: torch.Tensor, targets: torch.Tensor) -> torch.Tensor:
    """Log-probability of the joint action ``targets`` (``(m,) int64``, a node per robot): the sum over
    robots of log softmax of their own row.

    Examples
    --------
    >>> logits = torch.log(torch.tensor([[0.5, 0.5], [0.9, 0.1]]))
    >>> round(per_robot_log_prob(logits, torch.tensor([1, 0])).exp().item(), 4)  # 0.5 * 0.9
    0.45
    """
    logp = torch.log_softmax(logits, dim=1)
    return logp.gather(1, targets[:, None]).sum()


def per_robot_entropy(logits: torch.Tensor) -> torch.Tensor:
    """Entropy of the joint distribution: the sum of the robots' (independent) entropies."""
    logp = torch.log_softmax(logits, dim=1)
    p = logp.exp()
    return -(p * torch.where(p > 0, logp, torch.zeros_like(logp))).sum()


def per_robot_sample(logits: torch.Tensor, generator: torch.Generator | None = None) -> torch.Tensor:
    """``(m,) int64`` a node drawn for each robot from its own row."""
    probs = torch.softmax(logits, dim=1)
    return torch.multinomial(probs, 1, generator=generator)[:, 0]
