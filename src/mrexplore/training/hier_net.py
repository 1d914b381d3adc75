"""The multi-graph neural network (paper IV-B, eqs. 4-8): robot graph, cluster graph, cross graph, affinity E_rc."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import torch
from numpy.typing import NDArray
from torch import Tensor, nn

from mrexplore.config import LearnedConfig
from mrexplore.global_planning.learned.features import (
    CLUSTER_FEATURES,
    EDGE_FEATURES,
    ROBOT_FEATURES,
    GraphInputs,
    edge_feature_count,
)

__all__ = ["GraphBatch", "collate", "MultiGraphNet", "NEG_INF"]

NEG_INF = float("-inf")
_MASKED = -1e9
"""Logit of a masked key: exp() underflows to exactly 0 beside any real key, and an all-masked row stays
finite (its weights are then zeroed), so no NaN reaches a gradient."""


@dataclass
class GraphBatch:
    """Decisions padded to the largest team and cluster count of the batch.

    Shapes: robots ``(B, R, 3)``, clusters ``(B, C, 4)``, edges ``(B, R, C, 5)``, reachable and base
    ``(B, R, C)``, robot_mask ``(B, R)``, cluster_mask ``(B, C)``; float32 / bool.
    """

    robots: Tensor
    clusters: Tensor
    edges: Tensor
    reachable: Tensor
    base: Tensor
    robot_mask: Tensor
    cluster_mask: Tensor

    def __len__(self) -> int:
        return int(self.robots.shape[0])


def collate(items: Sequence[GraphInputs]) -> GraphBatch:
    """Pad and stack decisions (any team and cluster counts) into one batch."""
    B = len(items)
    R = max(1, max(g.n_robots for g in items))
    C = max(1, max(g.n_clusters for g in items))
    robots = np.zeros((B, R, ROBOT_FEATURES), np.float32)
    clusters = np.zeros((B, C, CLUSTER_FEATURES), np.float32)
    edges = np.zeros((B, R, C, items[0].edges.shape[-1] if items else EDGE_FEATURES), np.float32)
    reachable = np.zeros((B, R, C), bool)
    base = np.zeros((B, R, C), np.float32)
    rmask = np.zeros((B, R), bool)
    cmask = np.zeros((B, C), bool)
    for b, g in enumerate(items):
        r, c = g.n_robots, g.n_clusters
        robots[b, :r] = g.robots
        clusters[b, :c] = g.clusters
        edges[b, :r, :c] = g.edges
        reachable[b, :r, :c] = g.reachable
        base[b, :r, :c] = g.base
        rmask[b, :r] = True
        cmask[b, :c] = True
    t = torch.from_numpy
    return GraphBatch(t(robots), t(clusters), t(edges), t(reachable), t(base), t(rmask), t(cmask))


def _mlp(n_in: int, hidden: int, n_out: int) -> nn.Sequential:
    return nn.Sequential(nn.Linear(n_in, hidden), nn.ReLU(), nn.Linear(hidden, n_out))


def _attend(logits: Tensor, mask: Tensor, values: Tensor) -> Tensor:
    """Masked softmax attention: ``logits`` and ``mask`` ``(B, Q, K)``, values ``(B, K, H)`` -> ``(B, Q, H)``.
    A query with no key gets zeros."""
    w = torch.softmax(logits.masked_fill(~mask, _MASKED), dim=-1) * mask
    return w @ values


class _SelfGraph(nn.Module):
    """Dot-product attention within one graph (eqs. 4-5) and the residual update by f_V (eq. 6)."""

    def __init__(self, h: int) -> None:
        super().__init__()
        self.q, self.k, self.v = nn.Linear(h, h), nn.Linear(h, h), nn.Linear(h, h)
        self.f_v = _mlp(2 * h, h, h)
        self.scale = 1.0 / math.sqrt(h)  # keeps the softmax from saturating at init (Vaswani et al. 2017)

    def forward(self, x: Tensor, mask: Tensor) -> Tensor:
        logits = self.q(x) @ self.k(x).transpose(1, 2) * self.scale  # (B, N, N): every pair is an edge
        a = _attend(logits, mask[:, None, :] & mask[:, :, None], self.v(x))
        return x + self.f_v(torch.cat([x, a], dim=-1))


class _CrossGraph(nn.Module):
    """Attention from one side of the bipartite cross graph to the other, similarity by the MLP f_edge over
    (query, key, edge features) (eqs. 7-8), then the residual update of eq. 6."""

    def __init__(self, h: int, n_edge: int = EDGE_FEATURES) -> None:
        super().__init__()
        self.q, self.k, self.v = nn.Linear(h, h), nn.Linear(h, h), nn.Linear(h, h)
        self.f_edge = _mlp(2 * h + n_edge, h, 1)
        self.f_v = _mlp(2 * h, h, h)

    def forward(self, x: Tensor, y: Tensor, edges: Tensor, mask: Tensor) -> Tensor:
        """``x (B, N, h)`` attends to ``y (B, M, h)`` over ``edges (B, N, M, F)`` where ``mask (B, N, M)``."""
        q, k = self.q(x), self.k(y)
        N, M = x.shape[1], y.shape[1]
        pair = torch.cat([q[:, :, None, :].expand(-1, -1, M, -1), k[:, None, :, :].expand(-1, N, -1, -1), edges], -1)
        a = _attend(self.f_edge(pair).squeeze(-1), mask, self.v(y))
        return x + self.f_v(torch.cat([x, a], dim=-1))


def _zero_edge_head_if_missing(state: dict[str, Tensor], prefix: str, *args: object) -> None:
    """Policies saved before the linear edge path had none: they load with it at zero (their behaviour)."""
    key = prefix + "edge_head.weight"
    if key not in state and prefix + "score.2.weight" in state:
        state[key] = torch.zeros(1, EDGE_FEATURES)


class MultiGraphNet(nn.Module):
    """mGNN: robot and cluster nodes lifted to ``hidden`` by MLPs, ``blocks`` blocks of [robot self-graph,
    cluster self-graph, robots <- clusters, clusters <- robots], then a score per robot-cluster pair.

    The affinity is ``E_rc = base + residual``: ``base`` is the heuristic's (explore_lite's cost, scaled)
    and the residual's last layer starts at zero, so an untrained network *is* the heuristic. A value head
    reads the pooled nodes plus privileged scalars only the critic sees.
    """

    def __init__(self, cfg: LearnedConfig, value_inputs: int = 0) -> None:
        super().__init__()
        h = cfg.hidden
        n_edge = edge_feature_count(cfg)
        self.cfg = cfg
        self.robot_in = _mlp(ROBOT_FEATURES, h, h)
        self.cluster_in = _mlp(CLUSTER_FEATURES, h, h)
        self.robot_self = nn.ModuleList(_SelfGraph(h) for _ in range(cfg.blocks))
        self.cluster_self = nn.ModuleList(_SelfGraph(h) for _ in range(cfg.blocks))
        self.robot_cross = nn.ModuleList(_CrossGraph(h, n_edge) for _ in range(cfg.blocks))
        self.cluster_cross = nn.ModuleList(_CrossGraph(h, n_edge) for _ in range(cfg.blocks))
        self.score = _mlp(2 * h + n_edge, h, 1)
        last = self.score[-1]
        assert isinstance(last, nn.Linear)
        nn.init.zeros_(last.weight)
        nn.init.zeros_(last.bias)
        # A linear path from the edge features straight to the residual, zero at the start. The trainer's
        # policy search (stage ``search``) sets it; gradients never move it (imitation and PPO train the rest).
        self.edge_head = nn.Linear(n_edge, 1, bias=False)
        nn.init.zeros_(self.edge_head.weight)
        self.edge_head.weight.requires_grad_(False)
        self._register_load_state_dict_pre_hook(_zero_edge_head_if_missing)
        self.value_inputs = value_inputs
        self.value = _mlp(2 * h + value_inputs, h, 1)

    def encode(self, batch: GraphBatch) -> tuple[Tensor, Tensor]:
        """Node features after the blocks: robots ``(B, R, h)``, clusters ``(B, C, h)``."""
        vr = self.robot_in(batch.robots)
        vc = self.cluster_in(batch.clusters)
        cross = batch.reachable & batch.robot_mask[:, :, None] & batch.cluster_mask[:, None, :]
        edges_t = batch.edges.transpose(1, 2)
        for l in range(self.cfg.blocks):  # noqa: E741 - the paper's l
            vr = self.robot_self[l](vr, batch.robot_mask)
            vc = self.cluster_self[l](vc, batch.cluster_mask)
            vr_next = self.robot_cross[l](vr, vc, batch.edges, cross)
            vc = self.cluster_cross[l](vc, vr, edges_t, cross.transpose(1, 2))
            vr = vr_next
        return vr, vc

    def edge_path(self, batch: GraphBatch) -> Tensor:
        """The linear edge path's part of the residual, ``(B, R, C)``."""
        return self.edge_head(batch.edges).squeeze(-1)

    def residual(self, vr: Tensor, vc: Tensor, batch: GraphBatch) -> Tensor:
        """The learned part of the affinity, ``(B, R, C)`` (zero for an untrained network): the scoring
        MLP plus the linear edge path."""
        R, C = vr.shape[1], vc.shape[1]
        pair = torch.cat(
            [vr[:, :, None, :].expand(-1, -1, C, -1), vc[:, None, :, :].expand(-1, R, -1, -1), batch.edges], -1
        )
        return self.score(pair).squeeze(-1) + self.edge_path(batch)

    def residual_of(self, g: GraphInputs) -> NDArray[np.float64]:
        """The learned residual ``(R, C) float64`` at one decision, so that the learned planner decides on this
        network as on the NumPy one (:class:`~mrexplore.global_planning.learned.policy.HierScorer`)."""
        # torch runs on one intra-op thread where it decides: the network's tensors are too small to gain from
        # threads, and its OpenMP workers spin after every call, taking the cores from the distance-field
        # threads of the same decision and from other processes.
        if torch.get_num_threads() != 1:
            torch.set_num_threads(1)
        with torch.no_grad():
            batch = collate([g])
            vr, vc = self.encode(batch)
            learned = self.residual(vr, vc, batch)
        return learned[0, : g.n_robots, : g.n_clusters].double().numpy()

    def value_at(self, g: GraphInputs, extra: NDArray[np.float32]) -> float:
        """The critic's value at one decision, ``extra`` its privileged scalars."""
        with torch.no_grad():
            batch = collate([g])
            vr, vc = self.encode(batch)
            return float(self.value_of(vr, vc, batch, torch.from_numpy(np.asarray(extra, np.float32)[None]))[0])

    def scores_nothing(self) -> bool:
        """True where the scoring MLP's last layer is all zero (weights and bias): its part of the residual is
        then zero whatever the nodes, and the residual is the linear edge path alone. So is an untrained
        network, and a policy whose kept stage is a search generation (the shipped one)."""
        last = self.score[-1]
        assert isinstance(last, nn.Linear)
        with torch.no_grad():
            return not (bool(last.weight.any()) or (last.bias is not None and bool(last.bias.any())))

    @property
    def edge_weights(self) -> NDArray[np.float64]:
        """The linear edge path's weights, one per edge feature: residual += edges . w."""
        return self.edge_head.weight.detach().double().numpy()[0].copy()

    def set_edge_weights(self, w: Sequence[float] | NDArray[np.floating]) -> None:
        """Set the linear edge path (the policy search's candidates)."""
        with torch.no_grad():
            self.edge_head.weight.copy_(torch.as_tensor(np.asarray(w, np.float32)).reshape(1, -1))

    def forward(self, batch: GraphBatch) -> tuple[Tensor, Tensor, Tensor]:
        """Affinities ``(B, R, C)`` (``-inf`` where a pair is not allowed) and the nodes ``(B, R|C, h)``."""
        vr, vc = self.encode(batch)
        affinity = batch.base + self.residual(vr, vc, batch)
        allowed = batch.reachable & batch.robot_mask[:, :, None] & batch.cluster_mask[:, None, :]
        return affinity.masked_fill(~allowed, NEG_INF), vr, vc

    def value_of(self, vr: Tensor, vc: Tensor, batch: GraphBatch, extra: Tensor) -> Tensor:
        """Critic ``(B,)``: masked means of the nodes plus ``extra (B, value_inputs)`` privileged scalars."""
        rm = batch.robot_mask[..., None].float()
        cm = batch.cluster_mask[..., None].float()
        pooled_r = (vr * rm).sum(1) / rm.sum(1).clamp(min=1)
        pooled_c = (vc * cm).sum(1) / cm.sum(1).clamp(min=1)
        return self.value(torch.cat([pooled_r, pooled_c, extra], -1)).squeeze(-1)
