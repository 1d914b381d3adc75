"""The shipped networks' forward passes in NumPy float32, so that every strategy runs without torch.

The same weights and the same operations as the torch modules (:class:`~mrexplore.training.hier_net.MultiGraphNet`,
:class:`~mrexplore.training.ncm_net.NcmNet`), for one decision at a time (no padding). Torch is needed to train only.
A forward pass here is a few dozen small matrix products; NumPy's per-call cost is below torch's, so
inference is no slower (``python benchmarks/policy_inference.py`` measures both side by side). Float32
sums may round in another order than torch's; the decisions of the dev set are compared row for row by
``python benchmarks/inference_parity.py``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mrexplore.config import LearnedConfig
from mrexplore.global_planning.learned.features import GraphInputs, edge_feature_count
from mrexplore.global_planning.learned.ncm_inputs import NcmConfig, NcmInputs

__all__ = ["GraphNetNp", "NcmNetNp", "draw_np", "log_optimal_transport_np"]

F32 = NDArray[np.float32]
_MASKED = np.float32(-1e9)
"""Logit of a masked key, as in the torch modules."""


def _relu(x: F32) -> F32:
    return np.maximum(x, np.float32(0))


def _softmax(z: NDArray[Any], axis: int = -1) -> NDArray[Any]:
    e = np.exp(z - z.max(axis=axis, keepdims=True))
    return e / e.sum(axis=axis, keepdims=True)


def _logsumexp(z: F32, axis: int) -> F32:
    """log(sum(exp(z))) along ``axis``; ``-inf`` where every entry is ``-inf`` (as torch's)."""
    top = z.max(axis=axis, keepdims=True)
    safe = np.where(np.isfinite(top), top, np.float32(0))
    with np.errstate(divide="ignore"):
        out = np.log(np.exp(z - safe).sum(axis=axis, keepdims=True)) + safe
    return np.squeeze(out, axis=axis)


class _Weights:
    """Named float32 weights, with the torch modules' names; a missing one is a ValueError naming it."""

    def __init__(self, state: Mapping[str, NDArray[np.floating]]) -> None:
        self.state = {k: np.ascontiguousarray(v, dtype=np.float32) for k, v in state.items()}
        self.used: set[str] = set()

    def get(self, name: str) -> F32:
        if name not in self.state:
            raise ValueError(f"missing weights {name}")
        self.used.add(name)
        return self.state[name]

    def linear(self, name: str, bias: bool = True) -> tuple[F32, F32 | None]:
        w = self.get(name + ".weight")
        return np.ascontiguousarray(w.T), (self.get(name + ".bias") if bias else None)

    def check_all_used(self) -> None:
        extra = sorted(set(self.state) - self.used)
        if extra:
            raise ValueError(f"unexpected weights {extra[0]}")


class _Linear:
    def __init__(self, w: _Weights, name: str, bias: bool = True) -> None:
        self.wt, self.b = w.linear(name, bias)

    def __call__(self, x: F32) -> F32:
        y = x @ self.wt
        return y + self.b if self.b is not None else y


class _Mlp:
    """Linear, ReLU, Linear (the torch modules' ``nn.Sequential`` at indices 0 and 2)."""

    def __init__(self, w: _Weights, name: str) -> None:
        self.first, self.last = _Linear(w, name + ".0"), _Linear(w, name + ".2")

    def __call__(self, x: F32) -> F32:
        return self.last(_relu(self.first(x)))


def _attend(logits: F32, mask: NDArray[np.bool_], values: F32) -> F32:
    """Masked softmax attention, a query with no key getting zeros (``network._attend``)."""
    w = _softmax(np.where(mask, logits, _MASKED)) * mask
    return w @ values


def _pairs(q: F32, k: F32, edges: F32) -> F32:
    """``(N, M, 2h + F)``: [q_i, k_j, edges_ij] for every pair."""
    N, M = q.shape[0], k.shape[0]
    return np.concatenate(
        [np.broadcast_to(q[:, None, :], (N, M, q.shape[1])), np.broadcast_to(k[None, :, :], (N, M, k.shape[1])), edges],
        axis=-1,
    )


class _SelfGraph:
    def __init__(self, w: _Weights, name: str, h: int) -> None:
        self.q, self.k, self.v = (_Linear(w, f"{name}.{p}") for p in "qkv")
        self.f_v = _Mlp(w, name + ".f_v")
        self.scale = np.float32(1.0 / math.sqrt(h))

    def __call__(self, x: F32) -> F32:
        logits = self.q(x) @ self.k(x).T * self.scale
        a = _attend(logits, np.ones(logits.shape, bool), self.v(x))
        return x + self.f_v(np.concatenate([x, a], axis=-1))


class _CrossGraph:
    def __init__(self, w: _Weights, name: str) -> None:
        self.q, self.k, self.v = (_Linear(w, f"{name}.{p}") for p in "qkv")
        self.f_edge = _Mlp(w, name + ".f_edge")
        self.f_v = _Mlp(w, name + ".f_v")

    def __call__(self, x: F32, y: F32, edges: F32, mask: NDArray[np.bool_]) -> F32:
        logits = self.f_edge(_pairs(self.q(x), self.k(y), edges))[..., 0]
        a = _attend(logits, mask, self.v(y))
        return x + self.f_v(np.concatenate([x, a], axis=-1))


class GraphNetNp:
    """The mGNN's actor (:class:`~mrexplore.training.hier_net.MultiGraphNet` without its critic) from a policy's
    weights."""

    def __init__(self, cfg: LearnedConfig, state: Mapping[str, NDArray[np.floating]]) -> None:
        self.cfg = cfg
        w = _Weights(state)
        self.robot_in, self.cluster_in = _Mlp(w, "robot_in"), _Mlp(w, "cluster_in")
        blocks = range(cfg.blocks)
        self.robot_self = [_SelfGraph(w, f"robot_self.{i}", cfg.hidden) for i in blocks]
        self.cluster_self = [_SelfGraph(w, f"cluster_self.{i}", cfg.hidden) for i in blocks]
        self.robot_cross = [_CrossGraph(w, f"robot_cross.{i}") for i in blocks]
        self.cluster_cross = [_CrossGraph(w, f"cluster_cross.{i}") for i in blocks]
        self.score = _Mlp(w, "score")
        # policies saved before the linear edge path had none: it is zero for them (their behaviour)
        head = state.get("edge_head.weight")
        self.edge_w = np.zeros(0, np.float32) if head is None else w.get("edge_head.weight")[0]
        for name in state:  # the critic is not needed to decide
            if name.startswith("value."):
                w.used.add(name)
        w.check_all_used()

    def scores_nothing(self) -> bool:
        """True where the scoring MLP's last layer is all zero: its part of the residual is then zero."""
        last = self.score.last
        return not (last.wt.any() or (last.b is not None and last.b.any()))

    @property
    def edge_weights(self) -> NDArray[np.float64]:
        """The linear edge path's weights, one per edge feature (zero for a policy saved without one)."""
        return self.edge_w.astype(np.float64) if len(self.edge_w) else np.zeros(edge_feature_count(self.cfg))

    def edge_path(self, g: GraphInputs) -> F32:
        """The linear edge path's part of the residual, ``(R, C)``."""
        return g.edges @ self.edge_weights.astype(np.float32)

    def residual_of(self, g: GraphInputs) -> NDArray[np.float64]:
        """The learned residual ``(R, C) float64`` (the :class:`~mrexplore.global_planning.learned.policy.HierScorer`
        protocol)."""
        return self.residual(g).astype(np.float64)

    def residual(self, g: GraphInputs) -> F32:
        """The learned part of the affinity, ``(R, C)``: the scoring MLP over the encoded nodes plus the
        linear edge path (the edge path alone where the MLP scores nothing)."""
        if self.scores_nothing() or g.n_robots == 0 or g.n_clusters == 0:
            return self.edge_path(g)
        vr, vc = self.robot_in(g.robots), self.cluster_in(g.clusters)
        cross = g.reachable
        edges_t = np.ascontiguousarray(g.edges.transpose(1, 0, 2))
        for l in range(self.cfg.blocks):  # noqa: E741 - the paper's l
            vr = self.robot_self[l](vr)
            vc = self.cluster_self[l](vc)
            vr_next = self.robot_cross[l](vr, vc, g.edges, cross)
            vc = self.cluster_cross[l](vc, vr, edges_t, cross.T)
            vr = vr_next
        return self.score(_pairs(vr, vc, g.edges))[..., 0] + self.edge_path(g)


class _MultiHead:
    """``nn.MultiheadAttention`` (batch first, every key present) from its packed projection weights."""

    def __init__(self, w: _Weights, name: str, d: int, heads: int) -> None:
        wi, bi = w.get(name + ".in_proj_weight"), w.get(name + ".in_proj_bias")
        self.wq, self.wk, self.wv = (np.ascontiguousarray(wi[i * d : (i + 1) * d].T) for i in range(3))
        self.bq, self.bk, self.bv = (bi[i * d : (i + 1) * d] for i in range(3))
        self.out = _Linear(w, name + ".out_proj")
        self.heads, self.dh = heads, d // heads

    def __call__(self, x: F32) -> F32:
        n = x.shape[0]
        q = (x @ self.wq + self.bq).reshape(n, self.heads, self.dh).transpose(1, 0, 2)
        k = (x @ self.wk + self.bk).reshape(n, self.heads, self.dh).transpose(1, 0, 2)
        v = (x @ self.wv + self.bv).reshape(n, self.heads, self.dh).transpose(1, 0, 2)
        a = _softmax(q @ k.transpose(0, 2, 1) / np.float32(math.sqrt(self.dh))) @ v  # (H, n, dh)
        return self.out(a.transpose(1, 0, 2).reshape(n, self.heads * self.dh))


class _NcmSelf:
    def __init__(self, w: _Weights, name: str, d: int, heads: int) -> None:
        self.attn = _MultiHead(w, name + ".attn", d, heads)
        self.update = _Mlp(w, name + ".update")

    def __call__(self, x: F32) -> F32:
        return x + self.update(np.concatenate([x, self.attn(x)], axis=-1))


class _NcmCross:
    def __init__(self, w: _Weights, name: str) -> None:
        self.q, self.k, self.v = (_Linear(w, f"{name}.{p}") for p in "qkv")
        self.score = _Mlp(w, name + ".score")
        self.update = _Mlp(w, name + ".update")

    def __call__(self, x: F32, y: F32, edge: F32, allowed: NDArray[np.bool_]) -> F32:
        logits = np.where(allowed, self.score(_pairs(self.q(x), self.k(y), edge))[..., 0], _MASKED)
        wts = _softmax(logits) * allowed.any(axis=-1, keepdims=True)
        return x + self.update(np.concatenate([x, wts @ self.v(y)], axis=-1))


def draw_np(rows: NDArray[np.float32], seed: int) -> NDArray[np.int64]:
    """``(m,)`` one node per row from softmax(row), NumPy's generator seeded by ``seed``.

    Examples
    --------
    >>> draw_np(np.array([[0.0, -np.inf], [-np.inf, 5.0]], np.float32), 0).tolist()
    [0, 1]
    """
    z = rows.astype(np.float64)
    p = np.exp(z - z.max(axis=1, keepdims=True))
    p /= p.sum(axis=1, keepdims=True)
    rng = np.random.default_rng(seed)
    return np.array([rng.choice(len(q), p=q) for q in p], dtype=np.int64)


def log_optimal_transport_np(scores: F32, dustbin: float, iters: int, mask: NDArray[np.bool_] | None = None) -> F32:
    """:func:`~mrexplore.training.sinkhorn.log_optimal_transport` in NumPy: the ``(m + 1, n + 1)`` log plan with
    a dustbin.

    Examples
    --------
    >>> p = np.exp(log_optimal_transport_np(np.zeros((2, 3), np.float32), 0.0, iters=3))
    >>> p[0].astype(float).round(4).tolist(), p[2].astype(float).round(4).tolist()
    ([0.2, 0.2, 0.2, 0.4], [0.6, 0.6, 0.6, 1.2])
    """
    m, n = scores.shape
    z = np.empty((m + 1, n + 1), np.float32)
    z[:m, :n] = scores if mask is None else np.where(mask, scores, -np.inf)
    z[:m, n] = dustbin
    z[m, :] = dustbin
    norm = np.float32(-math.log(m + n))
    log_mu = np.full(m + 1, norm, np.float32)
    log_mu[m] = np.float32(math.log(n)) + norm
    log_nu = np.full(n + 1, norm, np.float32)
    log_nu[n] = np.float32(math.log(m)) + norm
    u, v = np.zeros_like(log_mu), np.zeros_like(log_nu)
    for _ in range(iters):
        u = log_mu - _logsumexp(z + v[None, :], axis=1)
        v = log_nu - _logsumexp(z + u[:, None], axis=0)
    return z + u[:, None] + v[None, :] - norm


class NcmNetNp:
    """NCM's actor (:class:`~mrexplore.training.ncm_net.NcmNet`) from a policy's weights: per-robot logits over
    the nodes."""

    def __init__(self, cfg: NcmConfig, state: Mapping[str, NDArray[np.floating]]) -> None:
        self.cfg = cfg
        d, w = cfg.hidden, _Weights(state)
        self.node_in, self.edge_in = _Mlp(w, "node_in"), _Mlp(w, "edge_in")
        blocks = range(cfg.blocks)
        self.self_robots = [_NcmSelf(w, f"self_robots.{i}", d, cfg.heads) for i in blocks]
        self.self_nodes = [_NcmSelf(w, f"self_nodes.{i}", d, cfg.heads) for i in blocks]
        self.to_nodes = [_NcmCross(w, f"to_nodes.{i}") for i in blocks]
        self.to_robots = [_NcmCross(w, f"to_robots.{i}") for i in blocks]
        self.dustbin = float(w.get("dustbin").reshape(()))
        w.check_all_used()

    def draw(self, rows: F32, seed: int) -> NDArray[np.int64]:
        """One node per robot from its logit row, NumPy's generator seeded by ``seed``."""
        return draw_np(rows, seed)

    def logits(self, x: NcmInputs) -> F32:
        """``(m, n)`` per-robot logits, ``-inf`` where a pair is not allowed."""
        m, n = x.dist.shape
        out = np.full((m, n), -np.inf, np.float32)
        if m == 0 or n == 0:
            return out
        flags = np.array([[0.0, 1.0], [1.0, 0.0]], np.float32)
        r = self.node_in(np.concatenate([x.robots_xy, np.broadcast_to(flags[0], (m, 2))], axis=-1))
        f = self.node_in(np.concatenate([x.nodes_xy, np.broadcast_to(flags[1], (n, 2))], axis=-1))
        e = self.edge_in(x.dist[..., None].astype(np.float32))
        e_t = np.ascontiguousarray(e.transpose(1, 0, 2))
        allowed = x.allowed
        for sr, sf, to_r, to_f in zip(self.self_robots, self.self_nodes, self.to_robots, self.to_nodes, strict=True):
            r, f = sr(r), sf(f)
            r, f = to_r(r, f, e, allowed), to_f(f, r, e_t, allowed.T)
        scores = (r @ f.T) / np.float32(math.sqrt(self.cfg.hidden))
        s = np.where(allowed, scores, _MASKED)
        s = s - _logsumexp(s, axis=0)[None, :]  # log softmax over the robots
        plan = log_optimal_transport_np(s, self.dustbin, self.cfg.sinkhorn_iters, allowed)
        out[allowed] = (plan[:m, :n] * np.float32(self.cfg.sharpen))[allowed]
        return out
