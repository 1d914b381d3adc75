"""The full-knowledge yardstick: viewpoints that cover the explorable region, then a multi-robot tour.

It knows the ground truth, so it is no exploration strategy; it shows how far online exploration is
from a plan made with the whole map. Viewpoints are candidate cells on a lattice; each one's footprint is
what the simulator's LiDAR would mark from it (the same beams, no noise). A greedy set cover picks the
viewpoint that sees most still-unseen cells until none adds any; the chosen viewpoints are ordered in one
open tour from the team's start (nearest neighbour + 2-opt on geodesic distances), and the tour is cut
into one piece per robot minimising the longest (tour splitting).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import linear_sum_assignment

from mrexplore.global_planning.tours import open_tour, split_tour
from mrexplore.maps.boxes import cells_of
from mrexplore.paths.distance_field import distance_fields, distance_matrix, distances_at
from mrexplore.sim.lidar import Beams
from mrexplore.types import BoolGrid

__all__ = ["greedy_cover", "viewpoint_footprints", "plan_oracle_routes", "OraclePlan"]


def viewpoint_footprints(
    occupied: BoolGrid,
    targets: BoolGrid,
    candidates_rc: NDArray[np.integer],
    range_cells: float,
    ray_oversampling: float,
) -> tuple[list[NDArray[np.int32]], int]:
    """For each candidate, the ids of the ``targets`` cells its scan marks (each once); and the number of
    targets."""
    target_id = np.full(targets.shape, -1, dtype=np.int64)
    target_id[targets] = np.arange(int(targets.sum()))
    beams = Beams.of(float(range_cells), ray_oversampling)
    noise = np.zeros(len(beams.dirs))
    mark = np.zeros(occupied.shape, dtype=np.int8)
    occ = np.ascontiguousarray(occupied)
    out = []
    for r, c in candidates_rc:
        r0, r1, c0, c1 = beams.mark(occ, int(r), int(c), noise, mark)
        window = mark[r0:r1, c0:c1]
        ids = target_id[r0:r1, c0:c1][window > 0]
        out.append(ids[ids >= 0].astype(np.int32))
        window[:] = 0
    return out, int(targets.sum())


def greedy_cover(footprints: list[NDArray[np.int32]], n_targets: int) -> list[int]:
    """Candidates picked greedily (most unseen targets first, lowest index on ties) until none adds any.

    ``footprints``: per candidate, the distinct targets it covers.

    Examples
    --------
    >>> greedy_cover([np.array([0, 1]), np.array([1, 2, 3]), np.array([3])], 4)
    [1, 0]
    """
    seen = np.zeros(n_targets, dtype=bool)
    gains = np.array([len(f) for f in footprints], dtype=np.int64)  # a footprint lists each cell once
    picked: list[int] = []
    while len(gains) and gains.max() > 0:
        # Lazy greedy: a stale gain is an upper bound; recompute the best until it stays best.
        k = int(np.argmax(gains))
        fresh = int(np.count_nonzero(~seen[footprints[k]]))
        if fresh < gains[k]:
            gains[k] = fresh
            continue
        if fresh == 0:
            break
        picked.append(k)
        seen[footprints[k]] = True
        gains[k] = 0
    return picked


@dataclass(frozen=True)
class OraclePlan:
    """Viewpoints chosen and each robot's ordered share of them."""

    viewpoints_rc: NDArray[np.int32]
    routes: list[NDArray[np.int32]]


def plan_oracle_routes(
    occupied: BoolGrid,
    explorable: BoolGrid,
    starts_rc: NDArray[np.integer],
    range_cells: float,
    ray_oversampling: float,
    spacing_cells: int,
) -> OraclePlan:
    """Viewpoints on a ``spacing_cells`` lattice of reachable free cells covering ``explorable``, one
    tour, cut into ``len(starts_rc)`` routes (see the module docstring)."""
    free = ~occupied
    starts = np.asarray(starts_rc, dtype=np.int64)
    start_fields = distance_fields(free, starts)
    reach = np.isfinite(np.minimum.reduce([f.full() for f in start_fields]))
    lattice = np.zeros_like(free)
    lattice[:: max(1, spacing_cells), :: max(1, spacing_cells)] = True
    candidates = cells_of(lattice & reach & explorable)
    candidates = np.vstack([starts, candidates])  # the starts themselves see something too
    footprints, n_targets = viewpoint_footprints(occupied, explorable, candidates, range_cells, ray_oversampling)
    chosen = candidates[greedy_cover(footprints, n_targets)].astype(np.int32)
    n = len(starts)
    if len(chosen) == 0:
        return OraclePlan(chosen, [np.zeros((0, 2), np.int32) for _ in range(n)])
    d_start = np.minimum.reduce([distances_at(f, chosen) for f in start_fields])
    d = distance_matrix(free, chosen, chosen)
    d = np.minimum(d, d.T)
    full = np.zeros((len(chosen) + 1, len(chosen) + 1))
    full[0, 1:] = full[1:, 0] = d_start
    full[1:, 1:] = d
    order = open_tour(full) - 1
    legs = d[order[:-1], order[1:]]
    pieces = split_tour(d_start[order], legs, n)
    # Each piece goes to the robot nearest its first viewpoint (Hungarian; pieces <= robots).
    firsts = chosen[order[[i for i, _ in pieces]]]
    cost = np.stack([distances_at(f, firsts) for f in start_fields])
    robots, piece_of = linear_sum_assignment(np.where(np.isfinite(cost), cost, 1e18))
    routes = [np.zeros((0, 2), np.int32) for _ in range(n)]
    for robot, piece_idx in zip(robots, piece_of, strict=True):
        i, j = pieces[piece_idx]
        routes[robot] = chosen[order[i:j]]
    return OraclePlan(chosen, routes)
