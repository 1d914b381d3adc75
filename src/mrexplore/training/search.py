"""Policy search on the residual's linear edge path: the cross-entropy method over one weight per edge
feature, each candidate scored on the same training episodes (numpy): by their mean steps, or by
:func:`relative_score`."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

__all__ = ["search_candidates", "cross_entropy_step", "relative_score"]


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


def relative_score(
    steps: NDArray[np.floating],
    steps_99: NDArray[np.floating],
    ref_steps: NDArray[np.floating],
    ref_steps_99: NDArray[np.floating],
) -> NDArray[np.float64]:
    """Scores of ``(..., episodes)`` results against a reference run of the same episodes (lower is
    better; the reference scores 1): the geometric mean over episodes of each episode's steps to the end
    plus steps to 99% coverage, over the reference's. Every episode weighs the same, as in the paired
    percentages of a bench report, where a mean of raw steps lets the largest maps decide; the steps to
    99% are the issue's "equal coverage", which the end alone does not see. Each ratio's denominator holds
    the reference's whole episode, so an episode that reaches 99% at once (a first scan that sees almost
    all of a small plan: 0 steps) cannot blow the ratio up; the geometric mean makes half as many steps
    and twice as many weigh the same.

    Examples
    --------
    >>> relative_score(np.array([[100, 50], [90, 60]]), np.array([[80, 40], [80, 40]]), np.array([100, 50]),
    ...                np.array([80, 40])).round(4).tolist()  # [1, sqrt(170 / 180 * 100 / 90)]
    [1.0, 1.0244]
    >>> float(relative_score(np.array([40]), np.array([0]), np.array([20]), np.array([0])))  # 99% at step 0
    2.0
    """
    num = np.asarray(steps, dtype=np.float64) + np.asarray(steps_99, dtype=np.float64)
    den = np.asarray(ref_steps, dtype=np.float64) + np.asarray(ref_steps_99, dtype=np.float64)
    return np.asarray(np.exp(np.log(np.maximum(num, 1.0) / np.maximum(den, 1.0)).mean(axis=-1)), dtype=np.float64)
