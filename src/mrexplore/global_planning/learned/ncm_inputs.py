"""NeuralCoMapping's network sizes and one decision's input as plain arrays (no torch)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from mrexplore.global_planning.ncm_nodes import POSITION_SCALE_M, WINDOW_M, scaled_xy, within_window
from mrexplore.global_planning.protocol import AssignmentProblem

__all__ = ["NcmConfig", "NcmInputs", "ncm_inputs"]


@dataclass(frozen=True)
class NcmConfig:
    """Sizes of NCM's network (its public defaults)."""

    hidden: int = 32
    heads: int = 4
    blocks: int = 3
    sinkhorn_iters: int = 5
    sharpen: float = 15.0
    """Logits of the per-robot categoricals are the Sinkhorn plan's log entries times this."""


@dataclass(frozen=True)
class NcmInputs:
    """One decision's input as plain arrays (what a PPO batch stores): robots_xy ``(m, 2)``, nodes_xy
    ``(n, 2)``, dist ``(m, n)`` (0 where unreachable), allowed ``(m, n)`` bool, float32 but ``allowed``."""

    robots_xy: NDArray[np.float32]
    nodes_xy: NDArray[np.float32]
    dist: NDArray[np.float32]
    allowed: NDArray[np.bool_]


def ncm_inputs(problem: AssignmentProblem, window_m: float = WINDOW_M, scale_m: float = POSITION_SCALE_M) -> NcmInputs:
    """The network's input for one decision: robots and candidate nodes (the problem's cluster centres) in
    metres over ``scale_m``, geodesic distances likewise, pairs allowed where reachable and within
    ``window_m`` in a straight line. A robot with no reachable node in its window may take any reachable
    node (NCM's window is its local map; on a large floor the last frontiers can lie beyond every robot's
    window, and a robot told nothing would stand still)."""
    res = problem.resolution_m
    robots = scaled_xy(problem.robots_rc, res, scale_m)
    nodes = scaled_xy(problem.clusters.centers_rc, res, scale_m)
    d = (problem.dist_cells * res / scale_m).astype(np.float32)
    reachable = np.isfinite(d)
    allowed = reachable & within_window(robots, nodes, window_m, scale_m)
    none_near = ~allowed.any(axis=1)
    allowed[none_near] = reachable[none_near]
    return NcmInputs(robots, nodes, np.where(reachable, d, 0.0).astype(np.float32), allowed)
