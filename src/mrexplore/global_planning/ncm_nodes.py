"""NeuralCoMapping's candidates (Ye, Dong et al., CVPR 2022, from its public code): frontier cells kept
clear of obstacles and max-pooled into coarse nodes; every pooled block holding a frontier is one node.

NCM takes as frontier the boundary of the closed explored map minus obstacles dilated by 0.2 m. On the
centre's grid that is F_un (free cells next to unknown space) less the cells within 0.2 m of an obstacle.
Its graph nodes are those cells max-pooled to 0.4 m; a node stands where a robot can go, so each pooled
block is represented by its frontier cell nearest the block's centre.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from mrexplore.maps.boxes import cells_of
from mrexplore.preprocessing.frontiers import Frontiers
from mrexplore.types import BoolGrid, CellState, StateGrid

__all__ = [
    "ncm_frontier",
    "pool_nodes",
    "in_window",
    "scaled_xy",
    "within_window",
    "CLEARANCE_M",
    "POOL_M",
    "WINDOW_M",
    "POSITION_SCALE_M",
]

CLEARANCE_M = 0.2
"""Frontier cells closer than this to an obstacle are dropped (NCM dilates obstacles by 0.2 m)."""
POOL_M = 0.4
"""Side of the pooling blocks (NCM's 0.4 m node grid)."""
WINDOW_M = 24.0
"""Nodes farther than this (straight line) from a robot are outside its window (NCM's local map)."""
POSITION_SCALE_M = 24.0
"""Coordinates and distances enter NCM's network divided by this."""


def ncm_frontier(
    state: StateGrid, frontiers: Frontiers, resolution_m: float, clearance_m: float = CLEARANCE_M
) -> BoolGrid:
    """``(H, W) bool`` NCM's frontier: F_un cells farther than ``clearance_m`` from every occupied cell.

    Examples
    --------
    >>> from mrexplore.preprocessing.frontiers import detect_frontiers
    >>> F, O, U = CellState.FREE, CellState.OCCUPIED, CellState.UNKNOWN
    >>> g = np.array([[O, F, F, F, U]] * 3, np.uint8)
    >>> ncm_frontier(g, detect_frontiers(g), 0.1, 0.2).astype(int).tolist()  # (r, 3): 0.2 m from the wall
    [[0, 0, 0, 1, 0], [0, 0, 0, 1, 0], [0, 0, 0, 1, 0]]
    """
    out = frontiers.un_mask.copy()
    reach = clearance_m / resolution_m + 1e-9
    r = math.floor(reach)
    rc = cells_of(out)
    if r < 1 or len(rc) == 0:
        return out
    # Only the frontier cells are tested: for each offset within the clearance disk, is the cell there an
    # obstacle? (The same cells as a Euclidean distance transform of the whole grid thresholded at the
    # clearance, at a tiny share of its cost on a large grid.)
    H, W = state.shape
    near = np.zeros(len(rc), dtype=bool)
    for dr in range(-r, r + 1):
        for dc in range(-r, r + 1):
            if dr * dr + dc * dc > reach * reach:
                continue
            rr, cc = rc[:, 0] + dr, rc[:, 1] + dc
            inside = (rr >= 0) & (rr < H) & (cc >= 0) & (cc < W)
            hit = np.zeros(len(rc), dtype=bool)
            hit[inside] = state[rr[inside], cc[inside]] == CellState.OCCUPIED
            near |= hit
    out[rc[near, 0], rc[near, 1]] = False
    return out


def pool_nodes(frontier: BoolGrid, resolution_m: float, pool_m: float = POOL_M) -> NDArray[np.int32]:
    """``(n, 2) int32`` one node per ``pool_m`` block that holds a frontier cell: the block's frontier cell
    nearest its centre (ties: the first in row-major order); nodes in row-major order of their blocks.

    Examples
    --------
    >>> f = np.zeros((4, 8), bool); f[0, 0] = f[2, 2] = f[1, 5] = True
    >>> pool_nodes(f, 0.1, 0.4).tolist()  # 4 x 4 blocks centred at 1.5: (2, 2) is nearer than (0, 0)
    [[2, 2], [1, 5]]
    """
    k = max(1, round(pool_m / resolution_m))
    rc = cells_of(frontier)
    if len(rc) == 0:
        return np.zeros((0, 2), dtype=np.int32)
    block = rc // k
    centre = block * k + (k - 1) / 2.0
    d2 = ((rc - centre) ** 2).sum(axis=1)
    width = frontier.shape[1] // k + 1
    block_id = block[:, 0] * width + block[:, 1]
    order = np.lexsort((np.arange(len(rc)), d2, block_id))  # by block, then distance, then row-major
    first = np.ones(len(order), dtype=bool)
    first[1:] = block_id[order][1:] != block_id[order][:-1]
    return rc[order[first]].astype(np.int32)


def scaled_xy(rc: NDArray[np.integer], resolution_m: float, scale_m: float = POSITION_SCALE_M) -> NDArray[np.float32]:
    """Cells as NCM's network takes them: metres over ``scale_m``, float32."""
    return (np.asarray(rc) * resolution_m / scale_m).astype(np.float32)


def within_window(
    robots_xy: NDArray[np.float32],
    nodes_xy: NDArray[np.float32],
    window_m: float = WINDOW_M,
    scale_m: float = POSITION_SCALE_M,
) -> NDArray[np.bool_]:
    """``(m, n) bool`` whether node j lies within ``window_m`` of robot i in a straight line, from
    :func:`scaled_xy` coordinates (the network's input and :func:`in_window` both test this way)."""
    euclid = np.sqrt(((robots_xy[:, None, :] - nodes_xy[None, :, :]) ** 2).sum(-1)) * scale_m
    return euclid <= window_m


def in_window(
    robots_rc: NDArray[np.integer],
    nodes_rc: NDArray[np.integer],
    resolution_m: float,
    window_m: float = WINDOW_M,
    scale_m: float = POSITION_SCALE_M,
) -> NDArray[np.bool_]:
    """:func:`within_window` from cells: the pairs the network's input allows by distance, bit for bit, so
    that a caller deciding which distances NCM reads gets the same pairs.

    Examples
    --------
    >>> in_window(np.array([[0, 0]]), np.array([[0, 240], [0, 241], [240, 1]]), 0.1).tolist()
    [[True, False, False]]
    """
    return within_window(
        scaled_xy(robots_rc, resolution_m, scale_m), scaled_xy(nodes_rc, resolution_m, scale_m), window_m, scale_m
    )
