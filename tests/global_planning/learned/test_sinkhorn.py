"""The log-space Sinkhorn layer with a dustbin: a hand-computed 2 x 3 case, a plain reference, masks."""

from __future__ import annotations

import math

import numpy as np
import torch

from mrexplore.training.sinkhorn import log_optimal_transport


def _reference(scores: np.ndarray, dustbin: float, iters: int, mask: np.ndarray | None = None) -> np.ndarray:
    """Plain Sinkhorn on the kernel exp(Z) (no logs), the same marginals, scaled by m + n."""
    m, n = scores.shape
    k = np.exp(np.pad(scores, ((0, 1), (0, 1)), constant_values=dustbin))
    if mask is not None:
        k[:m, :n] *= mask
    mu = np.r_[np.full(m, 1.0), n] / (m + n)
    nu = np.r_[np.full(n, 1.0), m] / (m + n)
    u, v = np.ones(m + 1), np.ones(n + 1)
    for _ in range(iters):
        u = mu / (k @ v)
        v = nu / (k.T @ u)
    return (u[:, None] * k * v[None, :]) * (m + n)


def test_equal_scores_give_the_product_of_the_marginals() -> None:
    # m = 2 robots, n = 3 nodes, all scores and the dustbin 0: the plan is mu nu^T; times m + n = 5, each
    # robot sends 1/5 * 5 = 0.2 to every node and 2/5 to its dustbin (2 robots' worth of spare columns...).
    p = log_optimal_transport(torch.zeros(2, 3), torch.tensor(0.0), iters=5).exp().numpy()
    assert np.allclose(p, [[0.2, 0.2, 0.2, 0.4], [0.2, 0.2, 0.2, 0.4], [0.6, 0.6, 0.6, 1.2]])
    assert np.allclose(p[:2].sum(axis=1), 1.0) and np.allclose(p[:, :3].sum(axis=0), 1.0)


def test_matches_a_plain_reference_and_normalises_at_convergence() -> None:
    rng = np.random.default_rng(0)
    scores = rng.normal(size=(3, 5))
    got = log_optimal_transport(torch.tensor(scores), torch.tensor(0.5), iters=5).exp().numpy()
    assert np.allclose(got, _reference(scores, 0.5, 5), atol=1e-10)
    conv = log_optimal_transport(torch.tensor(scores), torch.tensor(0.5), iters=500).exp().numpy()
    assert np.allclose(conv[:3].sum(axis=1), 1.0) and np.allclose(conv[:, :5].sum(axis=0), 1.0)


def test_masked_pairs_get_nothing_and_gradients_reach_the_dustbin() -> None:
    scores = torch.tensor([[2.0, 0.0, 1.0], [0.0, 3.0, -math.inf]])
    mask = torch.tensor([[True, False, True], [True, True, False]])
    dustbin = torch.tensor(0.3, requires_grad=True)
    log_p = log_optimal_transport(scores, dustbin, iters=5, mask=mask)
    p = log_p.exp()
    assert p[0, 1] == 0 and p[1, 2] == 0
    assert np.allclose(p.detach().numpy(), _reference(np.nan_to_num(scores.numpy(), neginf=0), 0.3, 5, mask.numpy()))
    log_p[0, 0].backward()
    assert dustbin.grad is not None and torch.isfinite(dustbin.grad)
