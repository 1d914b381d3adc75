"""Procedural floor plans (rooms, walls, doors) from a seed: the license-clean built-in map and training feed."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mrexplore.types import BoolGrid, MrExploreError

__all__ = ["FloorplanSpec", "generate_floorplan"]


@dataclass(frozen=True)
class FloorplanSpec:
    """Parameters of a procedural floor plan; all lengths in metres."""

    seed: int = 0
    """Seed of the layout."""
    width_m: float = 16.0
    """Outer width of the building, > 4 m."""
    height_m: float = 12.0
    """Outer height of the building, > 4 m."""
    min_room_m: float = 2.5
    """No room side is split below this, > door_m."""
    max_room_m: float = 6.0
    """Rooms with a side above this are always split, >= min_room_m."""
    wall_m: float = 0.15
    """Wall thickness."""
    door_m: float = 0.9
    """Door width."""
    extra_door_prob: float = 0.3
    """Chance that two adjacent rooms not joined by the spanning tree get a door anyway (loops)."""

    def __post_init__(self) -> None:
        if self.width_m <= 4 or self.height_m <= 4:
            raise MrExploreError(f"floor plan must be > 4 m a side, got {self.width_m} x {self.height_m}")
        if not self.door_m < self.min_room_m <= self.max_room_m:
            raise MrExploreError("floor plan needs door_m < min_room_m <= max_room_m")


def _split(
    rng: np.random.Generator,
    rect: tuple[float, float, float, float],
    spec: FloorplanSpec,
    out: list[tuple[float, float, float, float]],
) -> None:
    x0, y0, x1, y1 = rect
    w, h = x1 - x0, y1 - y0
    can_x, can_y = w >= 2 * spec.min_room_m, h >= 2 * spec.min_room_m
    must = max(w, h) > spec.max_room_m
    if not (can_x or can_y) or (not must and rng.random() < 0.35):
        out.append(rect)
        return
    # Split across the longer side, like a corridor of rooms; ties broken by the seed.
    along_x = can_x and (not can_y or w > h or (w == h and rng.random() < 0.5))
    if along_x:
        s = rng.uniform(x0 + spec.min_room_m, x1 - spec.min_room_m)
        _split(rng, (x0, y0, s, y1), spec, out)
        _split(rng, (s, y0, x1, y1), spec, out)
    else:
        s = rng.uniform(y0 + spec.min_room_m, y1 - spec.min_room_m)
        _split(rng, (x0, y0, x1, s), spec, out)
        _split(rng, (x0, s, x1, y1), spec, out)


def _shared_edge(a: tuple[float, ...], b: tuple[float, ...], need: float) -> tuple[str, float, float, float] | None:
    """Wall shared by rooms a and b: (axis, position, lo, hi), if at least ``need`` long."""
    eps = 1e-9
    for axis, (a_lo, a_hi, b_lo, b_hi), (a_s0, a_s1, b_s0, b_s1) in (
        ("x", (a[0], a[2], b[0], b[2]), (a[1], a[3], b[1], b[3])),
        ("y", (a[1], a[3], b[1], b[3]), (a[0], a[2], b[0], b[2])),
    ):
        for pos in (a_hi,) if abs(a_hi - b_lo) < eps else (a_lo,) if abs(a_lo - b_hi) < eps else ():
            lo, hi = max(a_s0, b_s0), min(a_s1, b_s1)
            if hi - lo >= need:
                return axis, pos, lo, hi
    return None


def generate_floorplan(spec: FloorplanSpec, resolution_m: float) -> BoolGrid:
    """Rasterise a seeded floor plan at ``resolution_m``: ``(H, W) bool``, True for walls.

    Rooms come from a recursive split of the building; every pair of rooms sharing a wall long enough
    gets a candidate door; a random spanning tree of doors keeps every room reachable, and extra doors
    add loops.

    Examples
    --------
    >>> occ = generate_floorplan(FloorplanSpec(seed=1), 0.1)
    >>> occ.shape
    (123, 163)
    >>> bool(occ[0].all() and occ[-1].all())  # closed outer wall
    True
    """
    rng = np.random.default_rng(spec.seed)
    rooms: list[tuple[float, float, float, float]] = []
    _split(rng, (0.0, 0.0, spec.width_m, spec.height_m), spec, rooms)
    border = spec.wall_m
    H = int(round((spec.height_m + 2 * border) / resolution_m))
    W = int(round((spec.width_m + 2 * border) / resolution_m))
    occ = np.ones((H, W), dtype=bool)
    half = spec.wall_m / 2

    def cells(v0: float, v1: float, n: int) -> slice:
        a = int(np.ceil((v0 + border) / resolution_m - 1e-9))
        b = int(np.floor((v1 + border) / resolution_m + 1e-9))
        return slice(max(a, 0), min(max(b, a + 1), n))

    for x0, y0, x1, y1 in rooms:
        occ[cells(y0 + half, y1 - half, H), cells(x0 + half, x1 - half, W)] = False
    need = spec.door_m + 2 * spec.wall_m
    edges = [
        (i, j, e)
        for i in range(len(rooms))
        for j in range(i + 1, len(rooms))
        if (e := _shared_edge(rooms[i], rooms[j], need)) is not None
    ]
    order = rng.permutation(len(edges))
    parent = list(range(len(rooms)))

    def find(i: int) -> int:
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    for k in order:
        i, j, (axis, pos, lo, hi) = edges[k]
        joined = find(i) != find(j)
        if not joined and rng.random() >= spec.extra_door_prob:
            continue
        parent[find(i)] = find(j)
        centre = rng.uniform(lo + spec.wall_m + spec.door_m / 2, hi - spec.wall_m - spec.door_m / 2)
        d0, d1 = centre - spec.door_m / 2, centre + spec.door_m / 2
        # Cut through the wall with a cell to spare on each side: rounding may thicken walls by a cell.
        w0, w1 = pos - spec.wall_m - resolution_m, pos + spec.wall_m + resolution_m
        if axis == "x":
            occ[cells(d0, d1, H), cells(w0, w1, W)] = False
        else:
            occ[cells(w0, w1, H), cells(d0, d1, W)] = False
    return occ
