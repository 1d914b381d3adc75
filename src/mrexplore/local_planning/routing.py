"""Route utility (paper eqs. 10-11) and the subsequence-reversal search for the best visiting order.

Reading of eq. 10. Taken literally, ``U = sum_j (G_kj + c * L_kj)`` with ``L_kj`` the distance from the
robot to candidate j and c = +1 does not depend on the order of the route (a sum over the same terms) and
rewards distance. The reading implemented here keeps the paper's terms and makes the order matter:

    U(rho) = sum_{j=1..n} ( G'_{rho_j} - c * L'(A_j(rho)) )

where ``A_j(rho)`` is the travel distance *accumulated along the route* until the j-th candidate is
reached (robot -> rho_1 -> ... -> rho_j), ``G'`` is the gain normalised by eq. 11 (enlarging gain gaps)
and ``L'`` is eq. 11's cost normalisation (``ln``: shrinking distance gaps) applied to accumulated
distances, with the min and max of the direct robot -> candidate distances as its scale. Every leg is
paid again by every candidate after it, so the route goes out from the robot and sweeps instead of
zig-zagging; the concave ``ln`` keeps a far detour from dominating. The gains sum to a constant over all
orders, so they act through the initial order of the search (descending gain, paper IV-C) and through
which sub-clusters exist at all.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np
from numpy.typing import NDArray

from mrexplore.config import LocalPlanningConfig

__all__ = ["normalise_gain", "normalise_cost", "reversal_search", "RouteProblem"]


def normalise_gain(gain: NDArray[np.floating], k_g: float, upper: float, eps: float) -> NDArray[np.float64]:
    """Eq. 11, first line: ``exp(k_g * ((G - min) / (max - min + eps) - 1)) * U_G``.

    Examples
    --------
    >>> normalise_gain(np.array([10.0, 20.0]), 1.0, 5.0, 0.0).round(4).tolist()  # e^-1 * 5 and 5
    [1.8394, 5.0]
    """
    g = np.asarray(gain, dtype=np.float64)
    return np.exp(k_g * ((g - g.min()) / (g.max() - g.min() + eps) - 1.0)) * upper


@nb.njit(cache=True, inline="always")
def _cost(dist: float, lo: float, hi: float, k_l: float, upper: float, eps: float) -> float:  # pragma: no cover
    return math.log(k_l * ((dist - lo) / (hi - lo + eps) + 1.0)) * upper


def normalise_cost(
    dist: NDArray[np.floating], lo: float, hi: float, k_l: float, upper: float, eps: float
) -> NDArray[np.float64]:
    """Eq. 11, second line, on the scale ``[lo, hi]``: ``ln(k_l * ((L - lo) / (hi - lo + eps) + 1)) * U_L``.

    Examples
    --------
    >>> normalise_cost(np.array([2.0, 6.0]), 2.0, 6.0, 1.0, 5.0, 0.0).round(4).tolist()  # 0 and 5 ln 2
    [0.0, 3.4657]
    """
    d = np.asarray(dist, dtype=np.float64)
    return np.log(k_l * ((d - lo) / (hi - lo + eps) + 1.0)) * upper


class RouteProblem:
    """One routing instance: candidates with gains, robot->candidate and candidate<->candidate distances.

    Parameters
    ----------
    gain:
        ``(n,)`` raw gains G_kj (members of each sub-cluster).
    from_robot:
        ``(n,)`` distances robot -> candidate L_kj (any unit, finite).
    between:
        ``(n, n)`` symmetric distances between candidates (same unit).
    """

    def __init__(
        self,
        gain: NDArray[np.floating],
        from_robot: NDArray[np.floating],
        between: NDArray[np.floating],
        cfg: LocalPlanningConfig,
    ) -> None:
        self.cfg = cfg
        self.gain_raw = np.asarray(gain, dtype=np.float64)
        self.gain = normalise_gain(self.gain_raw, cfg.k_g, cfg.upper_gain, cfg.epsilon)
        self.from_robot = np.asarray(from_robot, dtype=np.float64)
        self.between = np.asarray(between, dtype=np.float64)
        self.lo = float(self.from_robot.min())
        self.hi = float(self.from_robot.max())

    def utility(self, order: NDArray[np.integer]) -> float:
        """U(rho) of a visiting order (indices into the candidates)."""
        c = self.cfg
        return float(
            _utility(
                np.asarray(order, dtype=np.int64),
                self.gain,
                self.from_robot,
                self.between,
                self.lo,
                self.hi,
                c.c,
                c.k_l,
                c.upper_cost,
                c.epsilon,
            )
        )

    def initial_order(self) -> NDArray[np.int64]:
        """Descending gain, ties by index (paper IV-C, step 1)."""
        return np.argsort(-self.gain_raw, kind="stable").astype(np.int64)


@nb.njit(cache=True)
def _utility(
    order: np.ndarray,
    gain: np.ndarray,
    from_robot: np.ndarray,
    between: np.ndarray,
    lo: float,
    hi: float,
    c: float,
    k_l: float,
    upper: float,
    eps: float,
) -> float:  # pragma: no cover - numba
    total = 0.0
    acc = 0.0
    prev = -1
    for j in range(order.shape[0]):
        k = order[j]
        acc += from_robot[k] if prev < 0 else between[prev, k]
        total += gain[k] - c * _cost(acc, lo, hi, k_l, upper, eps)
        prev = k
    return total


@nb.njit(cache=True)
def _search(
    order: np.ndarray,
    gain: np.ndarray,
    from_robot: np.ndarray,
    between: np.ndarray,
    lo: float,
    hi: float,
    c: float,
    k_l: float,
    upper: float,
    eps: float,
) -> tuple[np.ndarray, float]:  # pragma: no cover
    n = order.shape[0]
    pre_u = np.zeros(n + 1)  # utility collected before position i
    pre_a = np.zeros(n + 1)  # distance travelled before position i
    while True:
        acc = 0.0
        tot = 0.0
        for i in range(n):
            k = order[i]
            acc += from_robot[k] if i == 0 else between[order[i - 1], k]
            tot += gain[k] - c * _cost(acc, lo, hi, k_l, upper, eps)
            pre_u[i + 1] = tot
            pre_a[i + 1] = acc
        best = tot
        move_x = -1
        move_y = -1
        for x in range(n - 1):
            for y in range(x + 1, n):
                # Only positions from x on change: start from the prefix, read the reversed span in place.
                total = pre_u[x]
                acc = pre_a[x]
                prev = order[x - 1] if x > 0 else -1
                for i in range(x, n):
                    k = order[x + y - i] if i <= y else order[i]
                    acc += from_robot[k] if prev < 0 else between[prev, k]
                    total += gain[k] - c * _cost(acc, lo, hi, k_l, upper, eps)
                    prev = k
                if total > best + 1e-12:
                    best = total
                    move_x = x
                    move_y = y
        if move_x < 0:
            return order, best
        order[move_x : move_y + 1] = order[move_x : move_y + 1][::-1].copy()


def reversal_search(problem: RouteProblem) -> tuple[NDArray[np.int64], float]:
    """The paper's subsequence-reversal search for the order of highest utility.

    Start from descending gain; evaluate the reversal of every subsequence (every pair of candidate
    positions x < y; the robot stays first), move to the best one if it improves the utility, and repeat
    until no reversal improves.

    Returns
    -------
    ``((n,) int64 order, utility)``.

    Examples
    --------
    >>> cfg = LocalPlanningConfig()
    >>> # Three candidates on a line at 1, 2 and 3 m from the robot; the far one has the most gain.
    >>> pos = np.array([1.0, 2.0, 3.0])
    >>> p = RouteProblem(np.array([5.0, 5.0, 9.0]), pos, np.abs(pos[:, None] - pos[None, :]), cfg)
    >>> reversal_search(p)[0].tolist()  # sweep outwards, not far-first
    [0, 1, 2]
    """
    c = problem.cfg
    order, best = _search(
        problem.initial_order(),
        problem.gain,
        problem.from_robot,
        problem.between,
        problem.lo,
        problem.hi,
        c.c,
        c.k_l,
        c.upper_cost,
        c.epsilon,
    )
    return order, float(best)
