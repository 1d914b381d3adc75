"""The ground-truth occupancy grid a simulation runs on, and the outside/explorable-region rules."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import ndimage

from mrexplore.maps.frame import GridFrame
from mrexplore.types import BoolGrid, GridRC, MrExploreError

__all__ = ["GroundTruthMap", "close_narrow_gaps", "mark_outside_as_obstacle", "free_components", "explorable_region"]

_FOUR = ndimage.generate_binary_structure(2, 1)


@dataclass(frozen=True)
class GroundTruthMap:
    """A ground-truth map: which cells are obstacles, and where the grid sits in the map frame.

    Attributes
    ----------
    occupied:
        ``(H, W) bool``; True for walls, unknown source cells and the outside.
    frame:
        Resolution and origin of the grid.
    name:
        Short name for reports (file stem or generator spec).
    start_hint_rc:
        A start cell the format itself gives (DungeonMaps' marker), or None.
    """

    occupied: BoolGrid
    frame: GridFrame
    name: str
    start_hint_rc: GridRC | None = None

    @property
    def shape(self) -> tuple[int, int]:
        return (int(self.occupied.shape[0]), int(self.occupied.shape[1]))

    @property
    def resolution_m(self) -> float:
        return self.frame.resolution_m


def close_narrow_gaps(occupied: BoolGrid, radius_cells: int) -> BoolGrid:
    """Fill free passages up to ``2 * radius_cells`` cells wide: closing of obstacles (dilate, then erode).

    Examples
    --------
    >>> occ = np.zeros((5, 7), bool); occ[:, 3] = True; occ[2, 3] = False  # a one-cell gap in a wall
    >>> bool(close_narrow_gaps(occ, 1)[2, 3]), int(close_narrow_gaps(occ, 1).sum())
    (True, 5)
    """
    if radius_cells < 1:
        return occupied.copy()
    structure = np.ones((2 * radius_cells + 1,) * 2, dtype=bool)
    grown = ndimage.binary_dilation(occupied, structure)
    return ndimage.binary_erosion(grown, structure, border_value=1) | occupied


def mark_outside_as_obstacle(occupied: BoolGrid, opening_cells: float) -> BoolGrid:
    """Turn the outside of a building into obstacle: open free space that reaches the grid border.

    Floor plans (KTH) draw the outside as free space; it is not part of the building and must neither be
    explored nor seen through. Free space merely *touching* the border is not enough to call it outside:
    a door in the outer wall, or a SLAM map's laser rays leaking through a window, connect the inside to
    the border too. So the outside is found as an opening: free cells farther than ``opening_cells`` from
    any obstacle form a core; the core's components that reach the border, grown back by
    ``opening_cells`` within free space, are the outside. Passages narrower than twice the radius
    (doors, gaps, rays) stop it.

    Examples
    --------
    >>> occ = np.zeros((9, 9), bool); occ[2:7, 2:7] = True; occ[3:6, 3:6] = False  # a room in open land
    >>> occ[4, 2] = False  # with a door to the outside
    >>> int((~mark_outside_as_obstacle(occ, 1.5)).sum())  # the room and its door stay free
    10
    """
    free = ~occupied
    # Distances to the nearest obstacle only: the grid's edge is no wall, the outside goes on beyond it.
    core = ndimage.distance_transform_edt(free) > opening_cells
    labels, _ = ndimage.label(core, structure=_FOUR)
    border = np.unique(np.concatenate([labels[0], labels[-1], labels[:, 0], labels[:, -1]]))
    border = border[border > 0]
    if len(border) == 0:
        return occupied.copy()
    outside_core = np.isin(labels, border)
    outside = (ndimage.distance_transform_edt(~outside_core) <= opening_cells) & free
    return occupied | outside


def free_components(occupied: BoolGrid) -> tuple[np.ndarray, int]:
    """Label 4-connected free components: ``((H, W) int32 labels, count)``; 0 marks obstacles.

    4-connectivity matches the motion model: diagonal moves may not cut wall corners.
    """
    labels, n = ndimage.label(~occupied, structure=_FOUR)
    return labels.astype(np.int32), int(n)


def explorable_region(occupied: BoolGrid, starts_rc: np.ndarray) -> BoolGrid:
    """Cells to be explored: the free space reachable from the starts plus the obstacles bounding it.

    Bounding obstacles are those 4-adjacent to reachable free space: a wall cell touching the room only
    diagonally is hidden behind its neighbours and no LiDAR ray can see it.

    Parameters
    ----------
    occupied:
        ``(H, W) bool`` ground truth.
    starts_rc:
        ``(n_robots, 2) int`` start cells, all free.
    """
    labels, _ = free_components(occupied)
    ids = np.unique(labels[starts_rc[:, 0], starts_rc[:, 1]])
    if np.any(ids == 0):
        raise MrExploreError("a start lies inside a wall; pick a start on free space")
    reach = np.isin(labels, ids)
    bound = ndimage.binary_dilation(reach, structure=_FOUR) & occupied
    return reach | bound
