"""The sequential policy's maths in torch, for PPO and imitation: the exact log-probability and entropy of
robots choosing one after another, the summed affinity of candidate assignments, and the record of one
sampled decision (:class:`PolicyStep`)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import torch
from numpy.typing import NDArray
from torch import Tensor

from mrexplore.global_planning.learned.features import GraphInputs

__all__ = ["PolicyStep", "sequential_log_prob", "assignment_score"]


@dataclass
class PolicyStep:
    """What the sampling planner did at one decision (for PPO)."""

    inputs: GraphInputs
    order: NDArray[np.int64]
    choices: NDArray[np.int64]
    logp: float
    value: float
    extra: NDArray[np.float32]
    """The critic's privileged scalars at this decision."""


def sequential_log_prob(affinity: Tensor, order: Tensor, choices: Tensor) -> tuple[Tensor, Tensor]:
    """Log-probability and entropy ``(B,)`` of ``choices`` under the sequential policy, batched.

    ``affinity (B, R, C)`` with ``-inf`` for forbidden pairs; ``order (B, R)`` robot indices (-1 for
    padding); ``choices (B, R)`` cluster per robot (-1 for none). The entropy is that of each robot's
    choice given those before it, summed (the joint entropy given the order, in expectation).
    """
    B, R, C = affinity.shape
    taken = torch.zeros(B, C, dtype=torch.bool)
    logp = affinity.new_zeros(B)
    entropy = affinity.new_zeros(B)
    rows = torch.arange(B)
    for t in range(R):
        i = order[:, t]
        valid = i >= 0
        logits = affinity[rows, i.clamp(min=0)]
        allowed = torch.isfinite(logits) & valid[:, None]
        free = allowed & ~taken
        avail = torch.where(free.any(-1, keepdim=True), free, allowed)
        has = avail.any(-1)
        lp = torch.log_softmax(torch.where(avail, logits, torch.full_like(logits, -1e9)), dim=-1)
        c = choices[rows, i.clamp(min=0)]
        pick = has & (c >= 0)
        logp = logp + torch.where(pick, lp[rows, c.clamp(min=0)], torch.zeros_like(logp))
        p = torch.exp(lp) * avail
        entropy = entropy - torch.where(has, (p * torch.where(avail, lp, torch.zeros_like(lp))).sum(-1), 0.0)
        taken = taken | (torch.nn.functional.one_hot(c.clamp(min=0), C).bool() & pick[:, None])
    return logp, entropy


def assignment_score(affinity: Tensor, candidates: Tensor) -> Tensor:
    """Summed affinity (paper eq. 2) of candidate assignments: ``affinity (B, R, C)``, ``candidates
    (B, M, R)`` cluster per robot (-1: none, or padding) -> ``(B, M)``. Forbidden pairs count 0."""
    B, M, R = candidates.shape
    safe = torch.where(torch.isfinite(affinity), affinity, torch.zeros_like(affinity))
    idx = candidates.clamp(min=0)
    picked = torch.gather(safe[:, None].expand(-1, M, -1, -1), 3, idx[..., None]).squeeze(-1)  # (B, M, R)
    return (picked * (candidates >= 0)).sum(-1)
