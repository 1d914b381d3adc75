"""Policy search on the residual's linear edge path: the cross-entropy method over one weight per edge
feature, each candidate scored by the mean steps of the same training episodes (numpy)."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

__all__ = ["search_candidates", "cross_entropy_step"]


def search_candidates(
    mean: NDArray[np.floating], sigma: NDArray[np.floating], population: int, rng: np.random.Generator
) -> NDArray[np.float64]:
    """``(population, F)`` weight vectors: the current ``mean`` first, then draws from N(mean, sigma^2)
    per weight. Keeping the mean among them lets a generation whose draws are all worse stay where it is.

    Examples
    --------
    >>> c = search_candidates(np.array([1.0, -2.0]), np.array([0.5, 0.5]), 3, np.random.default_rng(0))
    >>> c.shape, c[0].tolist()
    ((3, 2), [1.0, -2.0])
    """
    mean = np.asarray(mean, dtype=np.float64)
    draws = rng.normal(mean, np.asarray(sigma, dtype=np.float64), size=(population - 1, len(mean)))
    return np.vstack([mean[None, :], draws])


def cross_entropy_step(
    candidates: NDArray[np.floating], steps: NDArray[np.floating], elites: int, sigma_min: float
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The next mean and spread: those of the ``elites`` candidates with the fewest mean ``steps`` (ties
    keep the earlier candidate, so the current mean wins a tie), the spread floored at ``sigma_min``.

    Examples
    --------
    >>> cands = np.array([[0.0, 0.0], [2.0, -4.0], [4.0, 0.0], [-9.0, 9.0]])
    >>> mean, sigma = cross_entropy_step(cands, np.array([100.0, 90.0, 95.0, 130.0]), 2, 0.5)
    >>> mean.tolist(), sigma.tolist()  # the elites are [2, -4] and [4, 0]
    ([3.0, -2.0], [1.0, 2.0])
    """
    cand = np.asarray(candidates, dtype=np.float64)
    best = np.argsort(np.asarray(steps, dtype=np.float64), kind="stable")[:elites]
    elite = cand[best]
    return elite.mean(axis=0), np.maximum(elite.std(axis=0), sigma_min)
