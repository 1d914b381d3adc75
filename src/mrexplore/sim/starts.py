"""Robot start cells: given explicitly (validated) or drawn close together from the seeded generator."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from mrexplore.maps.ground_truth import GroundTruthMap, free_components
from mrexplore.paths.distance_field import distance_field
from mrexplore.types import MrExploreError, WorldXY

__all__ = ["draw_starts", "starts_from_xy", "team_starts"]


def starts_from_xy(truth: GroundTruthMap, starts_xy: Sequence[WorldXY]) -> NDArray[np.int32]:
    """Convert given start points (metres, map frame) to cells, refusing ones off the map or in walls."""
    cells = []
    for x, y in starts_xy:
        rc = truth.frame.xy_to_rc((x, y))
        if not truth.frame.contains(rc):
            raise MrExploreError(f"start ({x}, {y}) lies outside the map; give --start X,Y inside it")
        if truth.occupied[rc]:
            raise MrExploreError(f"start ({x}, {y}) lies inside a wall; give --start X,Y on free space")
        cells.append(rc)
    return np.asarray(cells, dtype=np.int32).reshape(-1, 2)


def draw_starts(
    truth: GroundTruthMap,
    n_robots: int,
    spread_m: float,
    rng: np.random.Generator,
    first_rc: tuple[int, int] | None = None,
) -> NDArray[np.int32]:
    """Draw ``n_robots`` distinct start cells close together.

    The first robot starts at ``first_rc`` (or the map's own start hint), else at a random cell of the
    largest free component; the others at random cells within ``spread_m`` geodesic metres of it (the
    radius grows until there is room for everyone).

    Returns
    -------
    ``(n_robots, 2) int32`` start cells.
    """
    free = ~truth.occupied
    first = first_rc if first_rc is not None else truth.start_hint_rc
    if first is None:
        labels, n = free_components(truth.occupied)
        sizes = np.bincount(labels.ravel(), minlength=n + 1)
        sizes[0] = 0
        cells = np.argwhere(labels == int(np.argmax(sizes)))
        pick = cells[rng.integers(len(cells))]
        first = (int(pick[0]), int(pick[1]))
    field = distance_field(free, first)
    radius = max(spread_m / truth.resolution_m, 1.0)
    while True:
        near = np.argwhere((field > 0) & (field <= radius))
        if len(near) >= n_robots - 1:
            break
        if np.isfinite(field).sum() - 1 < n_robots - 1:
            raise MrExploreError(
                f"robots must fit on the start's free component ({int(np.isfinite(field).sum())} cells), "
                f"got {n_robots}; use fewer robots or another start"
            )
        radius *= 2
    others = near[rng.choice(len(near), size=n_robots - 1, replace=False)] if n_robots > 1 else near[:0]
    return np.vstack([np.asarray([first], dtype=np.int32), others.astype(np.int32)])


def team_starts(
    truth: GroundTruthMap, starts_xy: Sequence[WorldXY], robots: int, spread_m: float, seed: int
) -> NDArray[np.int32] | None:
    """A team's starts from the points a user gave: one per robot as given, or one that the team is drawn
    near (within ``spread_m``, from ``seed``); None where none was given (the mission draws them). Two
    points alike, two robots in one cell, or a count that is neither 1 nor ``robots`` is one line.

    Examples
    --------
    >>> from mrexplore.maps.frame import GridFrame
    >>> occupied = np.ones((5, 5), bool); occupied[1:4, 1:4] = False
    >>> truth = GroundTruthMap(occupied=occupied, frame=GridFrame(5, 5, 1.0, (0.0, 0.0)), name="room")
    >>> team_starts(truth, [(1.5, 3.5), (3.5, 1.5)], 2, 1.0, 0).tolist()
    [[1, 1], [3, 3]]
    """
    if not starts_xy:
        return None
    if len(set(starts_xy)) != len(starts_xy):
        raise MrExploreError("--start gives the same point twice; give each robot its own start")
    given = starts_from_xy(truth, starts_xy)
    if len({tuple(rc) for rc in given.tolist()}) != len(given):
        raise MrExploreError("--start puts two robots in one cell; give starts at least one cell apart")
    if len(given) == robots:
        return given
    if len(given) == 1:
        return draw_starts(truth, robots, spread_m, np.random.default_rng(seed), tuple(given[0]))
    raise MrExploreError(f"--start must be given once or once per robot ({robots}), got {len(given)}")
