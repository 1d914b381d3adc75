"""NeuralCoMapping behind the global-planner protocol, on its NumPy network (no torch) or its torch one
(training, which records log-probabilities and values)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from mrexplore.global_planning.hungarian import match_min_cost
from mrexplore.global_planning.learned.ncm_inputs import NcmInputs, ncm_inputs
from mrexplore.global_planning.learned.numpy_nets import NcmNetNp
from mrexplore.global_planning.protocol import UNASSIGNED, Assignment, AssignmentProblem
from mrexplore.runtime.threads import thread_count

if TYPE_CHECKING:
    from mrexplore.global_planning.learned.ncm_network import NcmCritic, NcmNet

__all__ = ["NcmPlanner", "NcmStep", "matched_targets_np", "first_best", "TIE_TOL"]

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


@dataclass(frozen=True)
class NcmStep:
    """One sampled decision, for PPO: the inputs, each robot's node (:data:`UNASSIGNED` for a robot with
    none allowed), the joint log-probability, the critic's value and its scalars."""

    inputs: NcmInputs
    targets: NDArray[np.int64]
    logp: float
    value: float
    extra: NDArray[np.float32]


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

    ``net`` is the NumPy network (what the strategies run) or the torch one (training). With ``record``
    (a list) and a ``critic``, each sampled decision is appended as an :class:`NcmStep` (torch only);
    ``value_extra`` holds the critic's scalars for the next decision. Sampled draws come from NumPy on the
    NumPy network and from torch on the torch one: the same distribution, not the same draws."""

    net: NcmNetNp | NcmNet
    sample: bool = False
    name: str = "ncm"
    match: bool = False
    critic: NcmCritic | None = None
    record: list[NcmStep] | None = None
    value_extra: NDArray[np.float32] | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.net, NcmNetNp):
            import torch

            if torch.get_num_threads() > thread_count():  # as LearnedPlanner: one mission per core in the bench
                torch.set_num_threads(thread_count())
        elif self.record is not None:
            raise ValueError("recording NCM decisions needs the torch network")

    def logits(self, problem: AssignmentProblem) -> NDArray[np.float32]:
        """``(R, N)`` per-robot logits (``-inf`` where not allowed)."""
        return self._logits(ncm_inputs(problem))[0]

    def _logits(self, inputs: NcmInputs) -> tuple[NDArray[np.float32], Any]:
        if isinstance(self.net, NcmNetNp):
            return self.net.logits(inputs), None
        import torch

        from mrexplore.global_planning.learned.ncm_network import ncm_collate

        batch = ncm_collate([inputs])
        with torch.no_grad():
            return self.net(batch)[0].numpy(), batch

    def assign(self, problem: AssignmentProblem) -> Assignment:
        inputs = ncm_inputs(problem)
        logits, batch = self._logits(inputs)
        ok = np.isfinite(logits).any(axis=1)
        out = np.full(problem.n_robots, UNASSIGNED, dtype=np.int64)
        if not ok.any():
            return Assignment(out)
        rows = logits[ok]
        if self.sample:
            seed = int(problem.rng.integers(2**62)) if problem.rng is not None else 0
            picks = self._draw(rows, seed)
        elif self.match:
            picks = matched_targets_np(np.round(rows.astype(np.float64) / TIE_TOL) * TIE_TOL)
        else:
            picks = first_best(rows)
        out[ok] = picks
        if self.record is not None:
            self._record(inputs, batch, rows, picks, out)
        return Assignment(out)

    def _draw(self, rows: NDArray[np.float32], seed: int) -> NDArray[np.int64]:
        if isinstance(self.net, NcmNetNp):
            z = rows.astype(np.float64)
            p = np.exp(z - z.max(axis=1, keepdims=True))
            p /= p.sum(axis=1, keepdims=True)
            rng = np.random.default_rng(seed)
            return np.array([rng.choice(len(q), p=q) for q in p], dtype=np.int64)
        import torch

        from mrexplore.global_planning.learned.ncm_policy import per_robot_sample

        return per_robot_sample(torch.from_numpy(rows), torch.Generator().manual_seed(seed)).numpy()

    def _record(
        self, inputs: NcmInputs, batch: Any, rows: NDArray[np.float32], picks: NDArray[np.int64], out: NDArray[np.int64]
    ) -> None:
        import torch

        from mrexplore.global_planning.learned.ncm_policy import per_robot_log_prob

        if self.critic is None or self.value_extra is None or self.record is None:
            raise ValueError("recording NCM decisions needs a critic and value_extra")
        extra = np.asarray(self.value_extra, np.float32)
        with torch.no_grad():
            value = float(self.critic(batch, torch.from_numpy(extra)[None])[0])
        logp = float(per_robot_log_prob(torch.from_numpy(rows), torch.from_numpy(np.asarray(picks, np.int64))))
        self.record.append(NcmStep(inputs, out.copy(), logp, value, extra))
