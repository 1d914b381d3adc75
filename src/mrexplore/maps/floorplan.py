"""Procedural floor plans (rooms, walls, doors, corridors, clutter) from a seed: the license-clean built-in map
and the training feed.

``generated:SEED`` is the built-in map: a 16 x 12 m building cut into rooms of 2.5-6 m. ``varied:SEED`` draws
the building's size, outline, room sizes, corridor, doors and clutter from the seed as well
(:meth:`FloorplanSpec.varied`), so that training plans spread like HouseExpo's (``benchmarks/plan_stats.py``
compares them)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

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
    stop_prob: float = 0.35
    """Chance that a room which may stay whole (no side over max_room_m) is not split further, in [0, 1]."""
    corridor_m: float = 0.0
    """Width of a corridor along the building's long side, rooms on both sides (0: none), >= 0."""
    corridor_door_prob: float = 0.8
    """Chance that a room beside the corridor gets a door to it beyond the spanning tree's, in [0, 1]."""
    fill: float = 1.0
    """Share of the building's area kept: rooms on the outline are dropped (the rest staying connected)
    until at most this share is left, in (0, 1]; 1 keeps a rectangle."""
    wide_door_prob: float = 0.0
    """Chance that a door is an opening of 1.5-3 m instead (open-plan rooms), in [0, 1]."""
    clutter_prob: float = 0.0
    """Chance that a room holds furniture-like blocks (0.3-0.9 m, at least 1 m from its walls), in [0, 1]."""

    def __post_init__(self) -> None:
        if self.width_m <= 4 or self.height_m <= 4:
            raise MrExploreError(f"floor plan must be > 4 m a side, got {self.width_m} x {self.height_m}")
        if not self.door_m < self.min_room_m <= self.max_room_m:
            raise MrExploreError("floor plan needs door_m < min_room_m <= max_room_m")
        if self.corridor_m < 0 or not 0 < self.fill <= 1:
            raise MrExploreError("floor plan needs corridor_m >= 0 and 0 < fill <= 1")
        for name in ("extra_door_prob", "stop_prob", "corridor_door_prob", "wide_door_prob", "clutter_prob"):
            if not 0 <= getattr(self, name) <= 1:
                raise MrExploreError(f"floor plan needs {name} in [0, 1], got {getattr(self, name)}")

    @classmethod
    def varied(cls, seed: int) -> FloorplanSpec:
        """A plan whose parameters are drawn from ``seed`` too: building 60-500 m² (log-uniform), aspect up
        to 2:1, rooms 2.8-14 m a side, a corridor in about a third of the plans, outlines with up to half of
        the building cut away, doors 0.8-1.2 m and wider openings, clutter in some.

        >>> FloorplanSpec.varied(3) == FloorplanSpec.varied(3), FloorplanSpec.varied(3) == FloorplanSpec.varied(4)
        (True, False)
        """
        r = np.random.default_rng([seed, 7])
        area = float(np.exp(r.uniform(np.log(60.0), np.log(500.0))))
        aspect = float(np.exp(r.uniform(-np.log(2.0), np.log(2.0))))
        width = min(max(np.sqrt(area * aspect), 4.5), 36.0)
        height = min(max(np.sqrt(area / aspect), 4.5), 36.0)
        min_room = r.uniform(2.8, 4.5)
        corridor = r.uniform(1.0, 1.8) if r.random() < 0.35 and max(width, height) >= 10 else 0.0
        return cls(
            seed=seed,
            width_m=round(width, 2),
            height_m=round(height, 2),
            min_room_m=min_room,
            max_room_m=min_room * r.uniform(1.6, 3.2),
            door_m=r.uniform(0.8, 1.2),
            extra_door_prob=r.uniform(0.1, 0.5),
            stop_prob=r.uniform(0.3, 0.7),
            corridor_m=corridor,
            fill=r.uniform(0.5, 0.95) if r.random() < 0.85 else 1.0,
            wide_door_prob=r.uniform(0.0, 0.3),
            clutter_prob=r.uniform(0.1, 0.5) if r.random() < 0.3 else 0.0,
        )


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
    if not (can_x or can_y) or (not must and rng.random() < spec.stop_prob):
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


_Rect = tuple[float, float, float, float]
"""x0, y0, x1, y1 in metres."""


def _corridor(rng: np.random.Generator, spec: FloorplanSpec) -> _Rect | None:
    """The corridor's rectangle along the long side, rooms of at least min_room_m on both sides; or None."""
    if spec.corridor_m <= 0:
        return None
    along_x = spec.width_m >= spec.height_m
    across = spec.height_m if along_x else spec.width_m
    room = spec.min_room_m
    if across < 2 * room + spec.corridor_m:
        return None
    s = rng.uniform(room, across - room - spec.corridor_m)
    if along_x:
        return (0.0, s, spec.width_m, s + spec.corridor_m)
    return (s, 0.0, s + spec.corridor_m, spec.height_m)


def _beside(corridor: _Rect, spec: FloorplanSpec) -> list[_Rect]:
    """The two strips of the building on either side of the corridor."""
    x0, y0, x1, y1 = corridor
    if x0 == 0.0 and x1 == spec.width_m:
        return [(0.0, 0.0, spec.width_m, y0), (0.0, y1, spec.width_m, spec.height_m)]
    return [(0.0, 0.0, x0, spec.height_m), (x1, 0.0, spec.width_m, spec.height_m)]


def _outline(
    rng: np.random.Generator,
    spec: FloorplanSpec,
    rooms: list[_Rect],
    adjacent: list[tuple[int, int]],
    corridor_ix: int,
) -> list[bool]:
    """Which rooms stay: rooms on the outside (on the building's edge, or beside a dropped room) are
    dropped in a random order while the rest stays connected, until at most ``spec.fill`` of the area is
    left; a room whose loss would leave under ``fill - 0.1``, and the last three rooms and the corridor,
    stay."""
    n = len(rooms)
    keep = [True] * n
    if spec.fill >= 1.0 or n < 2:
        return keep
    nbrs: list[list[int]] = [[] for _ in range(n)]
    for i, j in adjacent:
        nbrs[i].append(j)
        nbrs[j].append(i)
    area = [(x1 - x0) * (y1 - y0) for x0, y0, x1, y1 in rooms]
    total, left = spec.width_m * spec.height_m, sum(area)
    eps = 1e-9

    def on_edge(k: int) -> bool:
        x0, y0, x1, y1 = rooms[k]
        return x0 < eps or y0 < eps or x1 > spec.width_m - eps or y1 > spec.height_m - eps

    def connected_without(k: int) -> bool:
        alive = [i for i in range(n) if keep[i] and i != k]
        seen, stack = {alive[0]}, [alive[0]]
        while stack:
            for j in nbrs[stack.pop()]:
                if keep[j] and j != k and j not in seen:
                    seen.add(j)
                    stack.append(j)
        return len(seen) == len(alive)

    changed = True
    while changed and left > spec.fill * total:
        changed = False
        for k in rng.permutation(n):
            if left <= spec.fill * total or sum(keep) <= 3:
                break
            outside = on_edge(k) or any(not keep[j] for j in nbrs[k])
            overshoot = left - area[k] < (spec.fill - 0.1) * total
            if keep[k] and k != corridor_ix and outside and not overshoot and connected_without(k):
                keep[k] = False
                left -= area[k]
                changed = True
    return keep


def generate_floorplan(spec: FloorplanSpec, resolution_m: float) -> BoolGrid:
    """Rasterise a seeded floor plan at ``resolution_m``: ``(H, W) bool``, True for walls.

    Rooms come from a recursive split of the building; every pair of rooms sharing a wall long enough
    gets a candidate door; a random spanning tree of doors keeps every room reachable, and extra doors
    add loops. Where the spec asks for them: a corridor with a strip of rooms on each side, an outline
    cut by dropping outer rooms (:func:`_outline`), blocks of clutter inside rooms.

    Examples
    --------
    >>> occ = generate_floorplan(FloorplanSpec(seed=1), 0.1)
    >>> occ.shape
    (123, 163)
    >>> bool(occ[0].all() and occ[-1].all())  # closed outer wall
    True
    """
    rng = np.random.default_rng(spec.seed)
    side = np.random.default_rng([spec.seed, 1])  # outline and corridor: the built-in plan never draws from it
    rooms: list[tuple[float, float, float, float]] = []
    corridor = _corridor(side, spec)
    if corridor is None:
        _split(rng, (0.0, 0.0, spec.width_m, spec.height_m), spec, rooms)
    else:
        for part in _beside(corridor, spec):
            _split(rng, part, spec, rooms)
        rooms.append(corridor)
    corridor_ix = len(rooms) - 1 if corridor is not None else -1
    border = spec.wall_m
    H = int(round((spec.height_m + 2 * border) / resolution_m))
    W = int(round((spec.width_m + 2 * border) / resolution_m))
    occ = np.ones((H, W), dtype=bool)
    half = spec.wall_m / 2

    def cells(v0: float, v1: float, n: int) -> slice:
        a = int(np.ceil((v0 + border) / resolution_m - 1e-9))
        b = int(np.floor((v1 + border) / resolution_m + 1e-9))
        return slice(max(a, 0), min(max(b, a + 1), n))

    need = spec.door_m + 2 * spec.wall_m
    all_edges = [
        (i, j, e)
        for i in range(len(rooms))
        for j in range(i + 1, len(rooms))
        if (e := _shared_edge(rooms[i], rooms[j], need)) is not None
    ]
    keep = _outline(side, spec, rooms, [(i, j) for i, j, _ in all_edges], corridor_ix)
    for k, (x0, y0, x1, y1) in enumerate(rooms):
        if keep[k]:
            occ[cells(y0 + half, y1 - half, H), cells(x0 + half, x1 - half, W)] = False
    edges = [(i, j, e) for i, j, e in all_edges if keep[i] and keep[j]]
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
        extra = spec.corridor_door_prob if corridor_ix in (i, j) else spec.extra_door_prob
        if not joined and rng.random() >= extra:
            continue
        parent[find(i)] = find(j)
        door = spec.door_m
        if spec.wide_door_prob > 0 and side.random() < spec.wide_door_prob:
            door = max(door, min(side.uniform(1.5, 3.0), hi - lo - 2 * spec.wall_m - 0.01))
        centre = rng.uniform(lo + spec.wall_m + door / 2, hi - spec.wall_m - door / 2)
        d0, d1 = centre - door / 2, centre + door / 2
        # Cut through the wall with a cell to spare on each side: rounding may thicken walls by a cell.
        w0, w1 = pos - spec.wall_m - resolution_m, pos + spec.wall_m + resolution_m
        if axis == "x":
            occ[cells(d0, d1, H), cells(w0, w1, W)] = False
        else:
            occ[cells(w0, w1, H), cells(d0, d1, W)] = False
    _add_clutter(occ, spec, rooms, keep, corridor_ix, lambda y0, y1, x0, x1: (cells(y0, y1, H), cells(x0, x1, W)))
    return occ


Rect = tuple[float, float, float, float]


def _add_clutter(
    occ: BoolGrid,
    spec: FloorplanSpec,
    rooms: list[Rect],
    keep: Any,
    corridor_ix: int,
    box: Callable[[float, float, float, float], tuple[slice, slice]],
) -> None:
    """Blocks of clutter in the kept rooms but the corridor, from the spec's own generator; ``box(y0, y1, x0,
    x1)`` gives a rectangle's cells."""
    clutter = np.random.default_rng([spec.seed, 2])
    gap = spec.wall_m / 2 + 1.0  # a block keeps 1 m from every wall, so doors stay open and the room connected
    for k, (x0, y0, x1, y1) in enumerate(rooms):
        if not keep[k] or k == corridor_ix or spec.clutter_prob <= 0 or clutter.random() >= spec.clutter_prob:
            continue
        for _ in range(int(clutter.integers(1, 3))):
            bw, bh = clutter.uniform(0.3, 0.9, size=2)
            if x1 - x0 - 2 * gap < bw or y1 - y0 - 2 * gap < bh:
                break
            bx = clutter.uniform(x0 + gap, x1 - gap - bw)
            by = clutter.uniform(y0 + gap, y1 - gap - bh)
            occ[box(by, by + bh, bx, bx + bw)] = True
