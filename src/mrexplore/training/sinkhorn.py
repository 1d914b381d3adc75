"""Differentiable optimal transport in log space with a dustbin (Sinkhorn iterations), NCM's assignment layer.

As in SuperGlue (Sarlin et al. 2020), which NeuralCoMapping follows: the ``m x n`` score matrix is augmented
with a dustbin row and column holding one learned score; row marginals are 1 for each of the ``m`` rows and
``n`` for the dustbin row, column marginals 1 for each column and ``m`` for the dustbin column, all divided
by ``m + n``; a few Sinkhorn iterations in log space approach the transport plan, which is returned
multiplied back by ``m + n`` so that each real row and column sums to 1.
"""

from __future__ import annotations

import math

import torch

__all__ = ["log_optimal_transport"]


def log_optimal_transport(
    scores: torch.Tensor, dustbin: torch.Tensor, iters: int, mask: torch.Tensor | None = None
) -> torch.Tensor:
    """``(m + 1, n + 1)`` log transport plan of ``(m, n)`` scores with a dustbin; ``mask`` ``(m, n) bool``
    marks pairs that may not be matched (their plan is 0; a row or column always keeps its dustbin).

    Examples
    --------
    With equal scores the plan is the product of the marginals: each real row sends 1/5 to every column
    and 2/5 to the dustbin (times ``m + n`` = 5: 0.2 and 0.4); the dustbin row 0.6 to each column.

    >>> p = log_optimal_transport(torch.zeros(2, 3), torch.tensor(0.0), iters=3).exp()
    >>> [round(v, 4) for v in p[0].tolist()], [round(v, 4) for v in p[2].tolist()]
    ([0.2, 0.2, 0.2, 0.4], [0.6, 0.6, 0.6, 1.2])
    """
    m, n = scores.shape
    z = torch.empty(m + 1, n + 1, dtype=scores.dtype)
    z[:m, :n] = scores if mask is None else scores.masked_fill(~mask, -math.inf)
    z[:m, n] = dustbin
    z[m, :] = dustbin
    norm = -math.log(m + n)
    log_mu = torch.full((m + 1,), norm, dtype=scores.dtype)
    log_mu[m] = math.log(n) + norm
    log_nu = torch.full((n + 1,), norm, dtype=scores.dtype)
    log_nu[n] = math.log(m) + norm
    u, v = torch.zeros_like(log_mu), torch.zeros_like(log_nu)
    for _ in range(iters):
        u = log_mu - torch.logsumexp(z + v[None, :], dim=1)
        v = log_nu - torch.logsumexp(z + u[:, None], dim=0)
    return z + u[:, None] + v[None, :] - norm
