"""Is this image a floor plan? Checks that turn a photograph, noise or an image with no enclosed free space
into a one-line error naming the reason, and a borderline image into a warning, before any mission runs.

Measured on every map of the example sets (HouseExpo, DungeonMaps, KTH floors, ROS SLAM maps), none
warned; the thresholds sit several times beyond the worst of them (the noisiest, a SLAM map of Willow
Garage, 0.19 wall pieces per m^2; the most divided, a HouseExpo plan with 71% of its free space in one region).
"""

from __future__ import annotations

import warnings

import numpy as np
from numpy.typing import NDArray
from scipy import ndimage

from mrexplore.types import MrExploreError

__all__ = ["MapWarning", "check_tones", "check_plan", "check_team_size", "ROOM_PER_ROBOT_M2"]

MID_GREY = (40, 215)
"""Grey values read as neither white nor black (exclusive); 205, map_server's unknown, is not counted."""
MID_GREY_ERROR, MID_GREY_WARN = 0.25, 0.05
"""Shares of mid-grey pixels above which an image is refused, or warned about."""
MIN_JUDGED_M2 = 5.0
"""Free space below this is too little to judge by shares and densities (hand-drawn test grids): not checked."""
MAIN_SHARE_ERROR, MAIN_SHARE_WARN = 0.3, 0.6
"""Shares of the free space in its largest region below which a map is refused, or warned about."""
PIECES_ERROR, PIECES_WARN = 0.6, 0.3
"""Separate pieces of wall per m^2 of the main free region above which a map is refused, or warned about."""
_EIGHT = np.ones((3, 3), bool)


class MapWarning(UserWarning):
    """A map that loads but may not be what was meant (the command line prints it as one line)."""


def check_tones(gray: NDArray[np.uint8], name: str) -> None:
    """A grey image whose pixels are largely neither white nor black is a photograph, not a plan.

    Examples
    --------
    >>> check_tones(np.array([[0, 255], [205, 254]], np.uint8), "plan")  # black, white, unknown
    >>> check_tones(np.full((4, 4), 128, np.uint8), "photo")
    Traceback (most recent call last):
    mrexplore.types.MrExploreError: map photo is not a floor plan: 100% of its pixels are mid grey (a photograph?); ...
    """
    g = np.asarray(gray)
    mid = float(((g > MID_GREY[0]) & (g < MID_GREY[1]) & (g != 205)).mean()) if g.size else 0.0
    if mid > MID_GREY_ERROR:
        raise MrExploreError(
            f"map {name} is not a floor plan: {mid:.0%} of its pixels are mid grey (a photograph?); "
            "give a plan with white free space and black walls"
        )
    if mid > MID_GREY_WARN:
        warnings.warn(
            f"map {name}: {mid:.0%} of its pixels are mid grey, read as free above 128 and wall below; "
            "check the result with --png",
            MapWarning,
            stacklevel=2,
        )


def check_plan(occupied: NDArray[np.bool_], resolution_m: float, name: str) -> None:
    """The loaded grid has a room-sized free region holding most of the free space, outlined by walls
    rather than scattered specks; otherwise an error (or, borderline, a warning) saying which.

    Examples
    --------
    >>> room = np.ones((40, 40), bool); room[5:35, 5:35] = False  # 9 m^2
    >>> check_plan(room, 0.1, "room")
    >>> specks = room.copy(); specks[6:34:3, 6:34:3] = True  # a speck every 0.3 m
    >>> check_plan(specks, 0.1, "specks")
    Traceback (most recent call last):
    mrexplore.types.MrExploreError: map specks is not a floor plan: its walls are 101 scattered pieces (12.6 per m^2 ...
    """
    free = ~occupied
    cell_m2 = resolution_m**2
    labels, n = ndimage.label(free)
    if n == 0:
        raise MrExploreError(f"map {name} has no free space enclosed by walls (no wall outline found)")
    sizes = np.bincount(labels.ravel())[1:]
    main = int(sizes.argmax()) + 1
    main_m2 = float(sizes[main - 1]) * cell_m2
    share = float(sizes[main - 1] / sizes.sum())
    if float(sizes.sum()) * cell_m2 < MIN_JUDGED_M2:
        return
    if share < MAIN_SHARE_ERROR:
        raise MrExploreError(
            f"map {name} is not a floor plan: its free space is {n} pieces, the largest {share:.0%} of it, like "
            "noise; give a plan whose rooms connect"
        )
    # pieces of wall that touch the main region (specks elsewhere, e.g. beyond the outer wall, do not count)
    near = ndimage.binary_dilation(labels == main, _EIGHT) & occupied
    wall_labels, _ = ndimage.label(occupied, structure=_EIGHT)
    pieces = len(np.unique(wall_labels[near]))
    density = pieces / main_m2
    if density > PIECES_ERROR:
        raise MrExploreError(
            f"map {name} is not a floor plan: its walls are {pieces} scattered pieces ({density:.1f} per m^2 of "
            f"free space, a plan has under {PIECES_WARN}), like noise; give a plan with connected walls"
        )
    if share < MAIN_SHARE_WARN or density > PIECES_WARN:
        warnings.warn(
            f"map {name} may not be a floor plan: {share:.0%} of its free space in one region, {pieces} pieces of "
            f"wall ({density:.2f} per m^2); check the result with --png",
            MapWarning,
            stacklevel=2,
        )


ROOM_PER_ROBOT_M2 = 4.0
"""Free space below which a team is warned that it is too large for its map, m^2 a robot."""


def check_team_size(free_cells: int, resolution_m: float, robots: int, name: str) -> None:
    """One warning where a team is too large for its map: less than :data:`ROOM_PER_ROBOT_M2` of free space a
    robot, where robots mostly wait in each other's way.

    Examples
    --------
    >>> import warnings
    >>> with warnings.catch_warnings(record=True) as caught:
    ...     warnings.simplefilter("always")
    ...     check_team_size(1500, 0.1, 3, "room")  # 15 m^2: fine for 3
    ...     check_team_size(1500, 0.1, 20, "room")
    >>> [str(w.message)[:60] for w in caught]
    ['map room: 20 robots on 15 m^2 of free space (0.8 m^2 each): ']
    """
    area = free_cells * resolution_m**2
    if robots > 1 and area / robots < ROOM_PER_ROBOT_M2:
        suit = max(1, int(area // ROOM_PER_ROBOT_M2))
        warnings.warn(
            f"map {name}: {robots} robots on {area:.0f} m^2 of free space ({area / robots:.1f} m^2 each): most "
            f"will wait in each other's way; {suit} robot{'s' * (suit != 1)} suit it",
            MapWarning,
            stacklevel=2,
        )
