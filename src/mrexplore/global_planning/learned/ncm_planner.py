"""NeuralCoMapping behind the global-planner protocol, on a NumPy scoring protocol (:class:`NcmScorer`): the
NumPy network (what the strategies run) and training's torch one both answer it; training records what it
needs through :attr:`NcmPlanner.on_sample`. Nothing here imports torch."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Protocol

import numpy as np
from numpy.typing import NDArray

from mrexplore.global_planning.hungarian import match_min_cost
from mrexplore.global_planning.learned.ncm_inputs import NcmInputs, ncm_inputs
from mrexplore.global_planning.protocol import UNASSIGNED, Assignment, AssignmentProblem

__all__ = [
    "NcmPlanner",
    "NcmScorer",
    "NcmSampleHook",
    "matched_targets_np",
    "first_best",
    "TIE_TOL",
]

TIE_TOL = 1e-3
"""Logits this close count as equal when deciding: a robot takes the first of the nodes within ``TIE_TOL`` of
its best, and the matched variant compares logits rounded to this step. The network's float32 arithmetic
rounds differently in NumPy and torch (and between CPUs) by about 1e-6; without a tolerance, nodes whose
logits tie in exact arithmetic (symmetric places) went one way or the other."""


def first_best(rows: NDArray[np.floating]) -> NDArray[np.int64]:
    """``(m,)`` each row's first entry within :data:`TIE_TOL` of its largest.

    Examples
    --------
    >>> first_best(np.array([[1.0, 3.0, 3.0005], [-np.inf, 2.0, 1.0]])).tolist()
    [1, 1]
    """
    best = rows.max(axis=1, keepdims=True)
    return np.argmax(rows >= best - TIE_TOL, axis=1).astype(np.int64)


class NcmScorer(Protocol):
    """What NCM's planner asks of its network, in NumPy: each robot's logits over the nodes, and a draw of one
    node per robot from them (the network's own sampler: NumPy's on the NumPy network, torch's on training's)."""

    def logits(self, x: NcmInputs) -> NDArray[np.float32]:
        """``(m, n)`` per-robot logits, ``-inf`` where a pair is not allowed."""

    def draw(self, rows: NDArray[np.float32], seed: int) -> NDArray[np.int64]:
        """``(m,)`` one node per row, drawn from softmax(row) with generator seed ``seed``."""


NcmSampleHook = Callable[[NcmInputs, NDArray[np.float32], NDArray[np.int64], NDArray[np.int64]], None]
"""Called with a sampled decision's inputs, the allowed robots' logit rows, their picks and every robot's node
(training records it)."""


def matched_targets_np(logits: NDArray[np.floating]) -> NDArray[np.int64]:
    """``(m,)`` the joint choice of largest summed logit with every node used once before any is shared
    (Hungarian, as ``hier`` decodes its affinities); a robot with no allowed node gets -1.

    Examples
    --------
    >>> matched_targets_np(np.array([[2.0, 1.0], [2.0, 1.0]])).tolist()  # argmax would send both to 0
    [0, 1]
    """
    cost = -np.asarray(logits, np.float64)
    return match_min_cost(np.where(np.isfinite(cost), cost, np.inf))


@dataclass
class NcmPlanner:
    """NCM behind the :class:`~mrexplore.global_planning.protocol.GlobalPlanner` protocol: each robot takes
    the node of largest logit (``sample=False``, the deterministic variant; near-ties by :data:`TIE_TOL`),
    draws its own (NCM's evaluation) with the problem's generator, or (``match``, deterministic) the robots
    take the joint choice of largest summed logit with every node used once before any is shared. A robot
    with no allowed node gets none.

    ``net`` answers :class:`NcmScorer`: the NumPy network (what the strategies run) or training's torch one;
    ``on_sample`` is called after each sampled decision. Sampled draws come from the network's own sampler:
    the same distribution on either, not the same draws."""

    net: NcmScorer
    sample: bool = False
    name: str = "ncm"
    match: bool = False
    on_sample: NcmSampleHook | None = None

    def logits(self, problem: AssignmentProblem) -> NDArray[np.float32]:
        """``(R, N)`` per-robot logits (``-inf`` where not allowed)."""
        return self.net.logits(ncm_inputs(problem))

    def assign(self, problem: AssignmentProblem) -> Assignment:
        inputs = ncm_inputs(problem)
        logits = self.net.logits(inputs)
        ok = np.isfinite(logits).any(axis=1)
        out = np.full(problem.n_robots, UNASSIGNED, dtype=np.int64)
        if not ok.any():
            return Assignment(out)
        rows = logits[ok]
        if self.sample:
            seed = int(problem.rng.integers(2**62)) if problem.rng is not None else 0
            picks = self.net.draw(rows, seed)
        elif self.match:
            picks = matched_targets_np(np.round(rows.astype(np.float64) / TIE_TOL) * TIE_TOL)
        else:
            picks = first_best(rows)
        out[ok] = picks
        if self.on_sample is not None and self.sample:
            self.on_sample(inputs, rows, picks, out)
        return Assignment(out)
