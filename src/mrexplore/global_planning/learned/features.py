"""The mGNN's inputs from an AssignmentProblem: robot and cluster nodes, robot->cluster edge features (numpy)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from mrexplore.config import GlobalPlanningConfig, LearnedConfig
from mrexplore.global_planning.classical import utility_cost
from mrexplore.global_planning.protocol import AssignmentProblem

__all__ = [
    "GraphInputs",
    "graph_inputs",
    "edge_feature_count",
    "route_positions",
    "EDGE_FEATURES",
    "ROBOT_FEATURES",
    "CLUSTER_FEATURES",
]

ROBOT_FEATURES = 3
"""x, y (metres from the team's centroid / distance scale), label 1 (paper: s_ri = (x, y, label))."""
CLUSTER_FEATURES = 4
"""x, y, label 0, |C_k| x resolution / size scale (paper: c_k and g_ik)."""
EDGE_FEATURES = 5
"""d_ik, g_ik (paper eq. 7's f_edge inputs), advantage, current goal, isolation (switchable, see
:class:`~mrexplore.config.LearnedConfig`); a switched-off feature is zero. A policy trained with
``use_predicted_gain`` reads the predicted gain next, one trained with ``use_predicted_path`` the predicted
shortcut after it, then the team plan's regret and route position where trained with them
(:func:`edge_feature_count`)."""
_FAR = 10.0
"""Normalised distances are clipped to [-_FAR, _FAR] (unreachable pairs are masked anyway)."""


@dataclass(frozen=True)
class GraphInputs:
    """One decision as the network sees it.

    Attributes
    ----------
    robots:
        ``(R, 3) float32`` robot node features.
    clusters:
        ``(C, 4) float32`` cluster node features.
    edges:
        ``(R, C, 5) float32`` robot->cluster edge features.
    reachable:
        ``(R, C) bool`` pairs with a finite geodesic distance; the only pairs a robot may be assigned.
    base:
        ``(R, C) float32`` the heuristic affinity, -(explore_lite's cost) / base_scale (0 where unreachable).
    """

    robots: NDArray[np.float32]
    clusters: NDArray[np.float32]
    edges: NDArray[np.float32]
    reachable: NDArray[np.bool_]
    base: NDArray[np.float32]

    @property
    def n_robots(self) -> int:
        return len(self.robots)

    @property
    def n_clusters(self) -> int:
        return len(self.clusters)


def edge_feature_count(cfg: LearnedConfig) -> int:
    """Edge features of a network with ``cfg``: :data:`EDGE_FEATURES`, then the predicted gain, the
    predicted shortcut, the plan's regret and the plan's route position where used."""
    return (
        EDGE_FEATURES
        + int(cfg.use_predicted_gain)
        + int(cfg.use_predicted_path)
        + int(cfg.use_plan_regret)
        + int(cfg.use_plan_position)
    )


def route_positions(routes: list[NDArray[np.int64]], n_clusters: int) -> NDArray[np.float64]:
    """``(R, C)`` 1 / (1 + p) where cluster k is the p-th (from 0) on robot i's route, 0 elsewhere.

    Examples
    --------
    >>> route_positions([np.array([2, 0]), np.array([], np.int64)], 3).tolist()
    [[0.5, 0.0, 1.0], [0.0, 0.0, 0.0]]
    """
    out = np.zeros((len(routes), n_clusters))
    for i, route in enumerate(routes):
        out[i, np.asarray(route, dtype=np.int64)] = 1.0 / (1.0 + np.arange(len(route)))
    return out


def _per_pair(value: NDArray[np.float64] | None, what: str, R: int, C: int) -> NDArray[np.float64]:
    """The plan's ``what`` as a ``(R, C)`` array; a one-line error where it is missing or of another shape."""
    if value is None or np.shape(value) != (R, C):
        raise ValueError(f"a network that reads the plan's {what} needs one per robot and cluster ({R}, {C})")
    return np.asarray(value, dtype=np.float64)


def graph_inputs(
    problem: AssignmentProblem,
    cfg: LearnedConfig,
    heuristic: GlobalPlanningConfig,
    gain_m2: NDArray[np.float64] | None = None,
    shortcut_m: NDArray[np.float64] | None = None,
    plan_regret_m: NDArray[np.float64] | None = None,
    plan_position: NDArray[np.float64] | None = None,
) -> GraphInputs:
    """Nodes, edges and masks of one decision, every distance in metres divided by ``cfg.distance_scale_m``;
    ``gain_m2`` ``(n_clusters,)``: the predicted gain of each cluster, ``shortcut_m`` ``(n_robots,
    n_clusters)``: each robot's predicted shortcut to each cluster, ``plan_regret_m`` and ``plan_position``
    ``(n_robots, n_clusters)``: the team plan's regret and :func:`route_positions` (each needed where ``cfg``
    uses it).

    Examples
    --------
    >>> from mrexplore.preprocessing.clustering import Clusters
    >>> c = Clusters(np.array([[0, 10]], np.int32), np.array([4], np.int32), np.zeros((4, 2), np.int32),
    ...              np.zeros(4, np.int32))
    >>> p = AssignmentProblem(np.array([[0, 0]], np.int32), c, np.array([[10.0]]), 1.0, np.zeros((1, 11), np.uint8))
    >>> g = graph_inputs(p, LearnedConfig(), GlobalPlanningConfig())
    >>> g.edges[0, 0].tolist()  # 10 m away, 4 m of frontier, alone, not the current goal, no other cluster
    [1.0, 0.800000011920929, 0.0, 0.0, 10.0]
    >>> float(g.base[0, 0])  # -(3 * 10 - 4) / 3
    -8.666666984558105
    """
    res = problem.resolution_m
    robots_xy = problem.robots_rc.astype(np.float64) * res
    centres_xy = problem.clusters.centers_rc.astype(np.float64) * res
    origin = robots_xy.mean(axis=0) if len(robots_xy) else np.zeros(2)
    R, C = problem.n_robots, problem.n_clusters
    ds = cfg.distance_scale_m
    size_m = problem.clusters.sizes.astype(np.float64) * res

    robots = np.zeros((R, ROBOT_FEATURES), np.float32)
    robots[:, :2] = (robots_xy - origin) / ds
    robots[:, 2] = 1.0
    clusters = np.zeros((C, CLUSTER_FEATURES), np.float32)
    clusters[:, :2] = (centres_xy - origin) / ds
    clusters[:, 3] = size_m / cfg.size_scale_m

    d_m = problem.dist_m
    reachable = np.isfinite(d_m)
    d = np.clip(np.where(reachable, d_m / ds, _FAR), -_FAR, _FAR)
    edges = np.zeros((R, C, edge_feature_count(cfg)), np.float32)
    edges[..., 0] = d
    edges[..., 1] = (size_m / cfg.size_scale_m)[None, :]
    if cfg.use_advantage and R > 1:
        # min over the other robots: the smallest distance unless it is robot i's own, then the second
        order = np.sort(d, axis=0)
        best_other = np.where(d <= order[0:1], order[1:2], order[0:1])
        edges[..., 2] = np.clip(d - best_other, -_FAR, _FAR)
    if cfg.use_current_goal and problem.current_cluster is not None:
        cur = problem.current_cluster
        has = cur >= 0
        edges[np.flatnonzero(has), cur[has], 3] = 1.0
    if cfg.use_isolation:
        if C > 1:
            gap = np.sqrt(((centres_xy[:, None, :] - centres_xy[None, :, :]) ** 2).sum(-1))
            np.fill_diagonal(gap, np.inf)
            edges[..., 4] = np.minimum(gap.min(axis=1) / ds, _FAR)[None, :]
        else:
            edges[..., 4] = _FAR
    if cfg.use_predicted_gain:
        if gain_m2 is None or len(gain_m2) != C:
            raise ValueError(f"a network that reads the predicted gain needs one per cluster ({C}), got {gain_m2!r}")
        edges[..., EDGE_FEATURES] = np.minimum(np.asarray(gain_m2) / cfg.gain_scale_m2, _FAR)[None, :]
    if cfg.use_predicted_path:
        if shortcut_m is None or np.shape(shortcut_m) != (R, C):
            need = f"one per robot and cluster ({R}, {C})"
            raise ValueError(f"a network that reads the predicted shortcut needs {need}, got {shortcut_m!r}")
        at = EDGE_FEATURES + int(cfg.use_predicted_gain)
        edges[..., at] = np.minimum(np.asarray(shortcut_m) / ds, _FAR)
    at = EDGE_FEATURES + int(cfg.use_predicted_gain) + int(cfg.use_predicted_path)
    if cfg.use_plan_regret:
        regret = _per_pair(plan_regret_m, "regret", R, C)
        edges[..., at] = np.where(np.isfinite(regret), np.minimum(regret / ds, _FAR), _FAR)
        at += 1
    if cfg.use_plan_position:
        edges[..., at] = _per_pair(plan_position, "position", R, C)
    cost = utility_cost(problem, heuristic)
    base = np.where(reachable, -cost / cfg.base_scale, 0.0).astype(np.float32)
    return GraphInputs(robots, clusters, edges, reachable, base)
