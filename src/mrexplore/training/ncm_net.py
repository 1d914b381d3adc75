"""NeuralCoMapping's network (Ye, Dong et al., CVPR 2022, from its public code), re-implemented for 2D.

Robots and frontier nodes are graph nodes with features (x, y, is_frontier, is_robot), lifted by an MLP;
the robot-to-node edge feature is the geodesic distance alone, lifted by an MLP. Blocks of attentional
propagation follow: self attention within the robots and within the nodes (multi-head dot product), then
cross attention both ways whose weights come from an MLP over [query, key, distance embedding]; each
update is a residual MLP of [features, message]. Robot-node scores (scaled dot products) are masked where a
node lies outside the robot's window or out of its reach, log-softmaxed over the robots, and put through
the log-space Sinkhorn layer with a learned dustbin; each robot's row, sharpened, is its policy's logits
(:mod:`~mrexplore.training.ncm_policy`).

Batches hold decisions padded to the largest team and node count; padding changes no output (tested).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import torch
from numpy.typing import NDArray
from torch import Tensor, nn

from mrexplore.global_planning.learned.ncm_inputs import NcmConfig, NcmInputs, ncm_inputs
from mrexplore.global_planning.learned.policy_file import VALUE_INPUTS
from mrexplore.global_planning.ncm_nodes import POSITION_SCALE_M, WINDOW_M
from mrexplore.global_planning.protocol import UNASSIGNED, AssignmentProblem
from mrexplore.runtime.threads import thread_count
from mrexplore.training.ncm_policy import per_robot_entropy, per_robot_log_prob, per_robot_sample
from mrexplore.training.sinkhorn import log_optimal_transport

__all__ = [
    "NcmConfig", "NcmBatch", "NcmNet", "NcmCritic", "NcmInputs", "NcmStep", "NcmActorCritic", "ncm_batch",
    "ncm_collate", "ncm_inputs", "ncm_log_prob", "WINDOW_M",
]  # fmt: skip

_MASKED = -1e9
"""Attention logit of a masked key: exp() underflows to 0 beside any real key, and stays finite."""


@dataclass(frozen=True)
class NcmStep:
    """One sampled decision, for PPO: the inputs, each robot's node (:data:`UNASSIGNED` for a robot with
    none allowed), the joint log-probability, the critic's value and its scalars."""

    inputs: NcmInputs
    targets: NDArray[np.int64]
    logp: float
    value: float
    extra: NDArray[np.float32]


@dataclass
class NcmBatch:
    """Decisions padded to the largest team (R) and node count (N) of the batch.

    robots_xy ``(B, R, 2)`` and nodes_xy ``(B, N, 2)`` float32, normalised by a map scale; dist ``(B, R, N)``
    float32 geodesic distance, normalised (any finite value where not allowed); allowed ``(B, R, N)`` bool:
    the node is reachable and inside the robot's window; robot_mask ``(B, R)`` and node_mask ``(B, N)`` bool.
    """

    robots_xy: Tensor
    nodes_xy: Tensor
    dist: Tensor
    allowed: Tensor
    robot_mask: Tensor
    node_mask: Tensor


def _mlp(i: int, h: int, o: int) -> nn.Sequential:
    return nn.Sequential(nn.Linear(i, h), nn.ReLU(), nn.Linear(h, o))


class _SelfAttention(nn.Module):
    """Multi-head dot-product attention within one set of nodes, residual MLP update."""

    def __init__(self, d: int, heads: int) -> None:
        super().__init__()
        self.attn = nn.MultiheadAttention(d, heads, batch_first=True)
        self.update = _mlp(2 * d, 2 * d, d)

    def forward(self, x: Tensor, mask: Tensor) -> Tensor:
        msg, _ = self.attn(x, x, x, key_padding_mask=~mask, need_weights=False)
        msg = torch.nan_to_num(msg) * mask[..., None]  # a set with no real member sends nothing
        return x + self.update(torch.cat([x, msg], dim=-1))


class _CrossAttention(nn.Module):
    """Attention from one set to the other whose logits are an MLP over [query, key, edge embedding]."""

    def __init__(self, d: int) -> None:
        super().__init__()
        self.q, self.k, self.v = nn.Linear(d, d), nn.Linear(d, d), nn.Linear(d, d)
        self.score = _mlp(3 * d, d, 1)
        self.update = _mlp(2 * d, 2 * d, d)

    def forward(self, x: Tensor, y: Tensor, edge: Tensor, allowed: Tensor) -> Tensor:
        """x ``(B, A, d)`` attends to y ``(B, C, d)`` over edges ``(B, A, C, d)`` where ``allowed``."""
        q, k, v = self.q(x), self.k(y), self.v(y)
        A, C = x.shape[1], y.shape[1]
        pair = torch.cat([q[:, :, None].expand(-1, -1, C, -1), k[:, None].expand(-1, A, -1, -1), edge], dim=-1)
        logits = self.score(pair)[..., 0].masked_fill(~allowed, _MASKED)
        w = torch.softmax(logits, dim=-1) * allowed.any(dim=-1, keepdim=True)
        return x + self.update(torch.cat([x, w @ v], dim=-1))


class NcmNet(nn.Module):
    """NCM's actor: per-robot logits over the nodes (``(B, R, N)``, ``-inf`` where not allowed or padding)."""

    def __init__(self, cfg: NcmConfig | None = None) -> None:
        super().__init__()
        self.cfg = cfg = cfg or NcmConfig()
        d = cfg.hidden
        self.node_in = _mlp(4, d, d)
        self.edge_in = _mlp(1, d, d)
        self.self_robots = nn.ModuleList(_SelfAttention(d, cfg.heads) for _ in range(cfg.blocks))
        self.self_nodes = nn.ModuleList(_SelfAttention(d, cfg.heads) for _ in range(cfg.blocks))
        self.to_nodes = nn.ModuleList(_CrossAttention(d) for _ in range(cfg.blocks))
        self.to_robots = nn.ModuleList(_CrossAttention(d) for _ in range(cfg.blocks))
        self.dustbin = nn.Parameter(torch.tensor(1.0))

    def logits(self, x: NcmInputs) -> NDArray[np.float32]:
        """``(m, n)`` per-robot logits of one decision, in NumPy, so that NCM's planner decides on this
        network as on the NumPy one (:class:`~mrexplore.global_planning.learned.ncm_planner.NcmScorer`)."""
        if torch.get_num_threads() > thread_count():  # one mission per core in the bench and the trainer
            torch.set_num_threads(thread_count())
        with torch.no_grad():
            out: NDArray[np.float32] = self(ncm_collate([x]))[0].numpy()
        return out

    def draw(self, rows: NDArray[np.float32], seed: int) -> NDArray[np.int64]:
        """One node per robot from its logit row, torch's generator seeded by ``seed``."""
        picks: NDArray[np.int64] = per_robot_sample(torch.from_numpy(rows), torch.Generator().manual_seed(seed)).numpy()
        return picks

    def forward(self, b: NcmBatch) -> Tensor:
        B, R, N = b.dist.shape
        robot_flags = torch.tensor([0.0, 1.0]).expand(B, R, 2)
        node_flags = torch.tensor([1.0, 0.0]).expand(B, N, 2)
        r = self.node_in(torch.cat([b.robots_xy, robot_flags], dim=-1))
        f = self.node_in(torch.cat([b.nodes_xy, node_flags], dim=-1))
        e = self.edge_in(b.dist[..., None])
        pair = b.allowed & b.robot_mask[:, :, None] & b.node_mask[:, None, :]
        for sr, sf, to_r, to_f in zip(self.self_robots, self.self_nodes, self.to_robots, self.to_nodes, strict=True):
            r, f = sr(r, b.robot_mask), sf(f, b.node_mask)
            r, f = to_r(r, f, e, pair), to_f(f, r, e.transpose(1, 2), pair.transpose(1, 2))
        scores = (r @ f.transpose(1, 2)) / math.sqrt(self.cfg.hidden)
        out = torch.full((B, R, N), float("-inf"))
        for i in range(B):
            m, n = int(b.robot_mask[i].sum()), int(b.node_mask[i].sum())
            if m == 0 or n == 0:
                continue
            allowed = pair[i, :m, :n]
            s = torch.log_softmax(scores[i, :m, :n].masked_fill(~allowed, _MASKED), dim=0)  # over robots
            plan = log_optimal_transport(s, self.dustbin, self.cfg.sinkhorn_iters, allowed)
            out[i, :m, :n] = (plan[:m, :n] * self.cfg.sharpen).masked_fill(~allowed, float("-inf"))
        return out


def ncm_collate(decisions: list[NcmInputs]) -> NcmBatch:
    """Decisions padded to the largest team and node count (padding changes no output)."""
    B = len(decisions)
    R = max(d.robots_xy.shape[0] for d in decisions)
    N = max(max(d.nodes_xy.shape[0] for d in decisions), 1)
    robots_xy, nodes_xy = np.zeros((B, R, 2), np.float32), np.zeros((B, N, 2), np.float32)
    dist, allowed = np.zeros((B, R, N), np.float32), np.zeros((B, R, N), bool)
    robot_mask, node_mask = np.zeros((B, R), bool), np.zeros((B, N), bool)
    for i, d in enumerate(decisions):
        m, n = d.dist.shape
        robots_xy[i, :m], nodes_xy[i, :n], dist[i, :m, :n], allowed[i, :m, :n] = (
            d.robots_xy,
            d.nodes_xy,
            d.dist,
            d.allowed,
        )
        robot_mask[i, :m], node_mask[i, :n] = True, True
    t = torch.from_numpy
    return NcmBatch(t(robots_xy), t(nodes_xy), t(dist), t(allowed), t(robot_mask), t(node_mask))


def ncm_batch(problem: AssignmentProblem, window_m: float = WINDOW_M, scale_m: float = POSITION_SCALE_M) -> NcmBatch:
    """:func:`ncm_inputs` of one decision as a batch of one."""
    return ncm_collate([ncm_inputs(problem, window_m, scale_m)])


class NcmCritic(nn.Module):
    """The value of a decision, for PPO only. NCM's critic is a CNN over map channels; ours is smaller:
    node features lifted by an MLP, mean- and max-pooled over robots and over nodes (masked), with the
    node count and the trainer's privileged scalars (``extra`` of them: remaining area,
    coverage, steps, team size), through an MLP."""

    def __init__(self, hidden: int = 32, extra: int = 4) -> None:
        super().__init__()
        self.extra = extra
        self.node_in = _mlp(4, hidden, hidden)
        self.head = _mlp(4 * hidden + 1 + extra, 2 * hidden, 1)

    def forward(self, b: NcmBatch, extra: Tensor) -> Tensor:
        """``(B,)`` values; ``extra`` ``(B, extra)``."""
        B, R, N = b.dist.shape
        r = self.node_in(torch.cat([b.robots_xy, torch.tensor([0.0, 1.0]).expand(B, R, 2)], dim=-1))
        f = self.node_in(torch.cat([b.nodes_xy, torch.tensor([1.0, 0.0]).expand(B, N, 2)], dim=-1))

        def pooled(x: Tensor, mask: Tensor) -> list[Tensor]:
            w = mask[..., None].float()
            mean = (x * w).sum(1) / w.sum(1).clamp(min=1)
            top = x.masked_fill(~mask[..., None], -1e9).max(1).values * mask.any(1, keepdim=True)
            return [mean, top]

        count = b.node_mask.float().sum(1, keepdim=True) / 100.0
        return self.head(torch.cat([*pooled(r, b.robot_mask), *pooled(f, b.node_mask), count, extra], dim=-1))[:, 0]


def ncm_log_prob(net: NcmNet, steps: list[NcmStep]) -> tuple[Tensor, Tensor]:
    """``(B,)`` joint log-probabilities of the recorded targets under ``net`` and ``(B,)`` entropies (robots
    with a target only; those the decision left without one add nothing)."""
    logits = net(ncm_collate([s.inputs for s in steps]))
    logps, ents = [], []
    for i, s in enumerate(steps):
        robots = torch.from_numpy(np.flatnonzero(s.targets != UNASSIGNED))
        rows = logits[i, robots]
        logps.append(per_robot_log_prob(rows, torch.from_numpy(s.targets[robots.numpy()])))
        ents.append(per_robot_entropy(rows))
    return torch.stack(logps), torch.stack(ents)


class NcmActorCritic(torch.nn.Module):
    """NCM's actor and our critic, trained together (one state dict, one optimiser with two learning rates);
    only the actor is a policy file."""

    def __init__(self) -> None:
        super().__init__()
        self.actor = NcmNet()
        self.critic = NcmCritic(extra=VALUE_INPUTS)

    @classmethod
    def around(cls, actor: torch.nn.Module) -> NcmActorCritic:
        """A fresh critic beside the weights of ``actor`` (a loaded policy's)."""
        both = cls()
        both.actor.load_state_dict(actor.state_dict())
        return both
