"""Local routing of one robot inside its assigned cluster: sub-clusters, distances, best visiting order."""

from __future__ import annotations

import hashlib
import threading
from collections import OrderedDict
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, TypeVar

import numpy as np
from numpy.typing import NDArray

from mrexplore.config import LocalPlanningConfig, PreprocessConfig
from mrexplore.local_planning.routing import RouteProblem, reversal_search
from mrexplore.paths.distance_field import Distances, distances_at, pairwise_distances
from mrexplore.preprocessing.clustering import cluster_frontiers
from mrexplore.types import BoolGrid, GridRC

__all__ = ["Route", "LocalRouter"]

_V = TypeVar("_V")


@dataclass(frozen=True)
class Route:
    """Where a robot goes inside its cluster, in order.

    Attributes
    ----------
    targets_rc:
        ``(m, 2) int32`` local candidates f_kj (snapped sub-cluster centres) in visiting order.
    gains:
        ``(m,) int32`` members of each sub-cluster (G_kj), same order.
    utility:
        U of the route (eq. 10 as read in :mod:`mrexplore.local_planning.routing`).
    """

    targets_rc: NDArray[np.int32]
    gains: NDArray[np.int32]
    utility: float


@dataclass
class LocalRouter:
    """Paper IV-C: sub-cluster a large assigned cluster and order the sub-clusters by utility."""

    cfg: LocalPlanningConfig = field(default_factory=LocalPlanningConfig)
    preprocess: PreprocessConfig = field(default_factory=PreprocessConfig)
    _memo: _Memo = field(default_factory=lambda: _Memo(), init=False, repr=False, compare=False)
    """Sub-clusters and candidate distances already computed for the same inputs: on a large floor most
    clusters routed at a decision were routed unchanged at the one before (57-71% of the sub-clusterings,
    14-41% of the distance searches late in a 16-robot mission on a KTH floor at 0.05 m)."""

    def applies(self, members: int) -> bool:
        """Routing is used for clusters with more than theta members; smaller ones: go to the centre."""
        return members > self.cfg.theta_members

    def route(
        self,
        passable: BoolGrid,
        robot_rc: GridRC,
        robot_field: Distances,
        members_rc: NDArray[np.int32],
        resolution_m: float,
    ) -> Route | None:
        """Best route through the sub-clusters of ``members_rc``; None when no candidate is reachable.

        Parameters
        ----------
        passable:
            ``(H, W) bool`` cells a robot may drive on.
        robot_field:
            the robot's distance field on ``passable`` (cells): a :class:`~mrexplore.paths.distance_field.Field`
            or a whole-grid ``(H, W) float32`` array.
        members_rc:
            ``(n, 2) int32`` members of the assigned cluster.
        """
        cfg = self.cfg
        bw = None if cfg.sub_bandwidth_m is None else cfg.sub_bandwidth_m / resolution_m
        sub = self._memo.get(
            ("sub", bw, _digest(np.ascontiguousarray(members_rc, dtype=np.int32))),
            lambda: cluster_frontiers(
                members_rc,
                PreprocessConfig(
                    min_cluster_size=1,
                    bandwidth_percentile=self.preprocess.bandwidth_percentile,
                    bandwidth_sample=self.preprocess.bandwidth_sample,
                ),
                bw,
            ),
        )
        cand = sub.centers_rc
        gains = sub.sizes
        from_robot = distances_at(robot_field, cand)
        keep = np.flatnonzero(np.isfinite(from_robot))
        if len(keep) == 0:
            return None
        # The largest sub-clusters, at most max_candidates of them.
        keep = keep[np.argsort(-gains[keep], kind="stable")[: cfg.max_candidates]]
        cand, gains, from_robot = cand[keep], gains[keep], from_robot[keep]
        between = self._between(passable, robot_rc, members_rc, cand, from_robot, resolution_m)
        problem = RouteProblem(gains.astype(np.float64), from_robot, between, cfg)
        order, utility = reversal_search(problem)
        return Route(cand[order].astype(np.int32), gains[order].astype(np.int32), utility)

    def _between(
        self,
        passable: BoolGrid,
        robot_rc: GridRC,
        members_rc: NDArray[np.int32],
        cand: NDArray[np.int32],
        from_robot: NDArray[np.float64],
        resolution_m: float,
    ) -> NDArray[np.float64]:
        """Geodesic distances between candidates: one field per candidate on the box around robot and
        cluster grown by ``margin_m`` (paths leaving the box are not seen: the via-robot bound is used)."""
        margin = int(np.ceil(self.cfg.margin_m / resolution_m))
        pts = np.vstack([members_rc, np.asarray(robot_rc, dtype=np.int32)[None]])
        r0, c0 = np.maximum(pts.min(axis=0) - margin, 0)
        r1, c1 = np.minimum(pts.max(axis=0) + margin + 1, passable.shape)
        local = cand - np.array([r0, c0])
        crop = passable[r0:r1, c0:c1]

        def searched() -> NDArray[np.float64]:
            return pairwise_distances(crop, local)

        box = (int(r0), int(r1), int(c0), int(c1))
        key = ("between", box, _digest(np.ascontiguousarray(local)), _digest(np.packbits(crop, axis=1)))
        between = self._memo.get(key, searched)
        via_robot = from_robot[:, None] + from_robot[None, :]
        between = np.where(np.isfinite(between), between, via_robot)
        return np.minimum(between, between.T)


def _digest(a: NDArray[np.generic]) -> tuple[tuple[int, ...], str, bytes]:
    """A key for an array's shape, type and contents."""
    return a.shape, a.dtype.str, hashlib.blake2b(a.tobytes(), digest_size=16).digest()


class _Memo:
    """The last ``size`` results of pure computations, by key (least recently used dropped first).
    Values are shared between hits: callers never change them."""

    def __init__(self, size: int = 64) -> None:
        self.size = size
        self._items: OrderedDict[object, Any] = OrderedDict()
        self._lock = threading.Lock()
        """Robots' routes are searched on several threads; the values are pure, so a key computed twice
        at once only costs time."""

    def get(self, key: object, compute: Callable[[], _V]) -> _V:
        with self._lock:
            if key in self._items:
                self._items.move_to_end(key)
                return self._items[key]
        value = compute()
        with self._lock:
            self._items[key] = value
            if len(self._items) > self.size:
                self._items.popitem(last=False)
        return value

    def __getstate__(self) -> dict[str, Any]:  # a lock neither pickles nor deep-copies
        return {"size": self.size, "_items": self._items}

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__dict__.update(state)
        self._lock = threading.Lock()
