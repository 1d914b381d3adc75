"""Pictures of a mission: frames of the centre's map with robots, paths, frontier clusters and goals, under a
title and a step and coverage counter, above a legend and a scale bar; GIF and PNG."""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray
from PIL import Image, ImageDraw, ImageFont

from mrexplore.pipeline import Decision
from mrexplore.preprocessing.clustering import Clusters
from mrexplore.preprocessing.transmission import LinkStatus
from mrexplore.runtime.colours import ROBOT_COLOURS, robot_colour
from mrexplore.runtime.progress import Progress
from mrexplore.sim.belief import merge_beliefs
from mrexplore.sim.world import ExplorationSim
from mrexplore.types import CellState, MrExploreError, StateGrid

__all__ = ["render_frame", "framed", "GifRecorder", "save_png", "scale_bar_m", "FRONTIER_COLOURS"]

_UNKNOWN = (222, 222, 222)
_TRUTH_WALL = (150, 150, 150)
"""Unexplored space light, a wall not yet seen a clearly darker grey, an explored wall near black."""
_FREE = (255, 255, 255)
_OCCUPIED = (20, 20, 20)
_FAILED = (128, 128, 128)
_INK = (30, 30, 30)
_ROBOT_COLOURS = list(ROBOT_COLOURS)
"""Robots (:mod:`~mrexplore.runtime.colours`, as the RViz markers draw them)."""
_LEGEND_ROBOTS = 8
"""A legend names at most this many robots one by one."""
FRONTIER_COLOURS = [(0, 170, 0), (90, 220, 90), (0, 110, 50)]
"""Frontier clusters: three greens, neighbouring clusters told apart by shade."""
_CENTRE = (0, 90, 0)
GIF_SECONDS = 10.0
"""A GIF plays the mission in about this long (its frames' duration adapts), then holds the end 2 s."""


_robot_colour = robot_colour


def _font(size: int) -> ImageFont.FreeTypeFont | ImageFont.ImageFont:
    try:
        return ImageFont.load_default(size=size)
    except (TypeError, OSError):  # Pillow without FreeType: its bitmap font, one size
        return ImageFont.load_default()


def render_frame(
    truth_occupied: NDArray[np.bool_],
    state: StateGrid,
    positions_rc: NDArray[np.integer],
    trails: Sequence[NDArray[np.integer]],
    clusters: Clusters | None,
    goals_rc: NDArray[np.integer],
    scale: float = 1.0,
    failed: NDArray[np.bool_] | None = None,
    unheard: NDArray[np.bool_] | None = None,
) -> Image.Image:
    """The map alone: ground truth faded under the belief, paths, frontier clusters, goals, robots.

    ``scale`` is output pixels per cell (below 1 shrinks, box-averaged). Frontier cells are drawn after
    scaling, at least 2 pixels wide, so that they stay visible on large maps; each cluster's centre is a
    dark green diamond. Faults: a ``failed`` robot is drawn grey and crossed out; one the centre does not
    assign to (``unheard``: silent too long, out of range, or not heard since the centre restarted) as a
    ring without fill.
    """
    rgb = np.empty((*state.shape, 3), dtype=np.uint8)
    rgb[:] = _UNKNOWN
    rgb[truth_occupied] = _TRUTH_WALL
    rgb[state == CellState.FREE] = _FREE
    rgb[state == CellState.OCCUPIED] = _OCCUPIED
    img = Image.fromarray(rgb)
    if scale != 1.0:
        size = (max(1, round(img.width * scale)), max(1, round(img.height * scale)))
        img = img.resize(size, Image.Resampling.BOX if scale < 1 else Image.Resampling.NEAREST)
    # Markers readable on any picture: a hundredth of its long side at least.
    rad = max(2.0, 3.0 * max(scale, 0.5), max(img.size) / 100)
    line = max(1, round(scale), round(max(img.size) / 400))
    if clusters is not None and len(clusters):
        img = _paint_frontiers(img, clusters, scale)
    draw = ImageDraw.Draw(img)
    for i, trail in enumerate(trails):
        if len(trail) > 1:
            xy = [((c + 0.5) * scale, (r + 0.5) * scale) for r, c in np.asarray(trail)]
            draw.line(xy, fill=_light(_robot_colour(i)), width=line)
    if clusters is not None:
        for r, c in np.asarray(clusters.centers_rc):
            x, y = (c + 0.5) * scale, (r + 0.5) * scale
            draw.polygon([(x, y - rad), (x + rad, y), (x, y + rad), (x - rad, y)], fill=_CENTRE, outline=(0, 0, 0))
    for i, (r, c) in enumerate(np.asarray(goals_rc)):
        if r >= 0:
            _cross(draw, (c + 0.5) * scale, (r + 0.5) * scale, rad, _robot_colour(i), max(2, line))
    for i, (r, c) in enumerate(np.asarray(positions_rc)):
        x, y = (c + 0.5) * scale, (r + 0.5) * scale
        box = [x - rad, y - rad, x + rad, y + rad]
        if failed is not None and failed[i]:
            draw.ellipse(box, fill=_FAILED, outline=(0, 0, 0))
            _cross(draw, x, y, rad, (0, 0, 0), 1)
        elif unheard is not None and unheard[i]:
            draw.ellipse(box, fill=None, outline=_robot_colour(i), width=2)
        else:
            draw.ellipse(box, fill=_robot_colour(i), outline=(0, 0, 0))
    return img


def _light(colour: tuple[int, int, int]) -> tuple[int, int, int]:
    r, g, b = (int(v + (255 - v) * 0.45) for v in colour)
    return r, g, b


def _cross(draw: ImageDraw.ImageDraw, x: float, y: float, rad: float, colour: tuple[int, int, int], w: int) -> None:
    draw.line([(x - rad, y - rad), (x + rad, y + rad)], fill=colour, width=w)
    draw.line([(x - rad, y + rad), (x + rad, y - rad)], fill=colour, width=w)


def _paint_frontiers(img: Image.Image, clusters: Clusters, scale: float) -> Image.Image:
    """Frontier cells as squares of at least 2 pixels, in their cluster's green."""
    px = np.array(img)
    side = max(2, round(scale))
    h, w = px.shape[:2]
    top = np.clip(np.round((clusters.members_rc[:, 0] + 0.5) * scale - side / 2).astype(np.int64), 0, h - 1)
    left = np.clip(np.round((clusters.members_rc[:, 1] + 0.5) * scale - side / 2).astype(np.int64), 0, w - 1)
    colours = np.array(FRONTIER_COLOURS, np.uint8)[clusters.labels % len(FRONTIER_COLOURS)]
    for dr in range(side):
        for dc in range(side):
            px[np.minimum(top + dr, h - 1), np.minimum(left + dc, w - 1)] = colours
    return Image.fromarray(px)


def scale_bar_m(metres_per_px: float, target_px: float) -> float:
    """The round length (1, 2 or 5 times a power of ten, metres) whose bar is nearest ``target_px`` wide
    without passing it.

    Examples
    --------
    >>> scale_bar_m(0.05, 100), scale_bar_m(0.5, 100), scale_bar_m(0.01, 120)
    (5.0, 50.0, 1.0)
    """
    most = metres_per_px * target_px
    power = 10.0 ** math.floor(math.log10(most))
    return max(m * power for m in (1, 2, 5) if m * power <= most)


@dataclass(frozen=True)
class Caption:
    """What a frame says around its map: the title, the counter, the legend's fault entries and robots."""

    title: str
    step: int
    coverage: float
    faults: bool = False
    robots: int = 1


_PAD = 6


def _legend_items(faults: bool, robots: int = 1) -> list[tuple[str, str]]:
    items = [(f"robot:{i}", f"robot {i + 1}") for i in range(min(robots, _LEGEND_ROBOTS))]
    if robots > _LEGEND_ROBOTS:
        items.append((f"robot:{_LEGEND_ROBOTS}", f"robots {_LEGEND_ROBOTS + 1}-{robots}"))
    items += [("path", "its path"), ("goal", "its goal"), ("frontier", "frontier cluster")]
    items += [("centre", "cluster centre"), ("unknown", "unexplored"), ("free", "explored"), ("wall", "wall")]
    items += [("truth", "wall not yet seen")]
    if faults:
        items += [("failed", "failed robot"), ("unheard", "not heard")]
    return items


def _swatch(draw: ImageDraw.ImageDraw, kind: str, x: float, y: float, s: float) -> None:
    """A legend symbol in the box ``(x, y)`` to ``(x + s, y + s)``."""
    cx, cy, rad = x + s / 2, y + s / 2, s / 2 - 1
    if kind.startswith("robot:"):
        colour = _robot_colour(int(kind.split(":")[1]))
        draw.ellipse([cx - rad, cy - rad, cx + rad, cy + rad], fill=colour, outline=(0, 0, 0))
    elif kind == "path":
        draw.line([(x, cy), (x + s, cy)], fill=_light(_robot_colour(0)), width=3)
    elif kind == "goal":
        _cross(draw, cx, cy, rad, _robot_colour(0), 2)
    elif kind == "frontier":
        third = s / 3
        for k, colour in enumerate(FRONTIER_COLOURS):
            draw.rectangle([x + k * third, y + 2, x + (k + 1) * third - 1, y + s - 2], fill=colour)
    elif kind == "centre":
        draw.polygon([(cx, y), (x + s, cy), (cx, y + s), (x, cy)], fill=_CENTRE, outline=(0, 0, 0))
    elif kind == "failed":
        draw.ellipse([cx - rad, cy - rad, cx + rad, cy + rad], fill=_FAILED, outline=(0, 0, 0))
        _cross(draw, cx, cy, rad, (0, 0, 0), 1)
    elif kind == "unheard":
        draw.ellipse([cx - rad, cy - rad, cx + rad, cy + rad], outline=_robot_colour(0), width=2)
    else:
        fill = {"unknown": _UNKNOWN, "free": _FREE, "wall": _OCCUPIED, "truth": _TRUTH_WALL}[kind]
        draw.rectangle([x, y, x + s, y + s], fill=fill, outline=(120, 120, 120))


def framed(map_img: Image.Image, caption: Caption, metres_per_px: float) -> Image.Image:
    """``map_img`` with a header (title; step and coverage) above it and a legend and a scale bar below."""
    width = max(map_img.width, 380)
    unit = max(1.0, width / 600)  # text and symbols grow with the picture
    big, small = _font(round(14 * unit)), _font(round(12 * unit))
    probe = ImageDraw.Draw(Image.new("RGB", (1, 1)))

    def text_w(text: str, font: ImageFont.FreeTypeFont | ImageFont.ImageFont) -> float:
        return probe.textlength(text, font=font)

    # legend rows, laid out left to right
    s, gap = round(12 * unit), round(14 * unit)
    rows: list[list[tuple[str, str, float]]] = [[]]
    x: float = _PAD
    for kind, label in _legend_items(caption.faults, caption.robots):
        w = s + 4 + text_w(label, small)
        if x + w > width - _PAD and rows[-1]:
            rows.append([])
            x = _PAD
        rows[-1].append((kind, label, x))
        x += w + gap
    head_h, row_h = round(40 * unit), round(18 * unit)
    foot_h = _PAD + row_h * len(rows) + round(26 * unit)
    out = Image.new("RGB", (width, head_h + map_img.height + foot_h), (255, 255, 255))
    out.paste(map_img, ((width - map_img.width) // 2, head_h))
    draw = ImageDraw.Draw(out)
    draw.text((_PAD, 4), caption.title, fill=_INK, font=big)
    counter = f"step {caption.step}   coverage {100 * caption.coverage:.2f}%"  # as the text summary says it
    draw.text((_PAD, round(22 * unit)), counter, fill=_INK, font=small)
    y = head_h + map_img.height + _PAD
    for row in rows:
        for kind, label, lx in row:
            _swatch(draw, kind, lx, y + 2, s)
            draw.text((lx + s + 4, y), label, fill=_INK, font=small)
        y += row_h
    # the scale bar: a round length near a quarter of the map's width
    metres = scale_bar_m(metres_per_px, max(20.0, map_img.width / 4))
    bar = metres / metres_per_px
    y += round(6 * unit)
    draw.rectangle([_PAD, y, _PAD + bar, y + round(4 * unit)], fill=_INK)
    label = f"{metres:g} m"
    draw.text((_PAD + bar + 6, y - round(5 * unit)), label, fill=_INK, font=small)
    return out


class GifRecorder:
    """Mission observer that keeps frames for a GIF and the last state for a PNG.

    A frame every ``every`` steps at ``max_side`` pixels a side for the map (small maps enlarged by a whole
    factor); where a mission runs long, every other frame is dropped and the interval doubled, so that a
    GIF holds at most ``max_frames`` frames whatever the map (a few MB at most). ``title`` heads every
    frame; ``faults`` adds the failed and not-heard robots to the legend.
    """

    def __init__(
        self, every: int = 10, max_side: int = 480, max_frames: int = 120, title: str = "", faults: bool = False
    ) -> None:
        self.every = every
        self.max_side = max_side
        self.max_frames = max_frames
        self.title = title
        self.faults = faults
        self.frames: list[Image.Image] = []
        self._trails: list[list[NDArray[np.int32]]] = []
        self._last: tuple[ExplorationSim, Decision | None, NDArray[np.int32], LinkStatus] | None = None

    def __call__(
        self, sim: ExplorationSim, decision: Decision | None, goals_rc: NDArray[np.int32], status: LinkStatus
    ) -> None:
        if not self._trails:
            self._trails = [[] for _ in range(sim.n_robots)]
        for i in range(sim.n_robots):
            self._trails[i].append(sim.positions_rc[i].copy())
        self._last = (sim, decision, goals_rc.copy(), status)
        if sim.steps % self.every == 0:  # kept palette-coded: a byte a pixel
            self.frames.append(_coded(self._frame(self._gif_scale())))
            if len(self.frames) >= 2 * self.max_frames:
                self.frames = self.frames[1::2]
                self.every *= 2

    def _gif_scale(self) -> float:
        assert self._last is not None
        side = max(self._last[0].truth.shape)
        return self.max_side / side if side > self.max_side else float(max(1, self.max_side // side))

    def _frame(self, scale: float, clusters: bool = True) -> Image.Image:
        assert self._last is not None
        sim, decision, goals, status = self._last
        if not clusters:
            decision = None
        state = merge_beliefs(sim.beliefs).state(sim.cfg.sensor)  # the team's raw knowledge
        trails = [np.asarray(t, dtype=np.int32) for t in self._trails]
        frontier_clusters = decision.clusters if decision is not None else None
        img = render_frame(
            sim.truth.occupied,
            state,
            sim.positions_rc,
            trails,
            frontier_clusters,
            goals,
            scale,
            failed=~sim.alive,
            unheard=~status.assignable,
        )
        title = self.title or f"{sim.truth.name}, {sim.n_robots} robots"
        caption = Caption(title, sim.steps, sim.coverage, self.faults, sim.n_robots)
        return framed(img, caption, sim.truth.frame.resolution_m / scale)

    def final_frame(self, min_side: int = 900, clusters: bool = True) -> Image.Image:
        """The last state at full resolution, enlarged so that its long side has at least ``min_side`` pixels;
        ``clusters=False`` leaves out the frontier clusters (a mission that ended for want of any)."""
        assert self._last is not None
        side = max(self._last[0].truth.shape)
        return self._frame(scale=max(1.0, min_side / side), clusters=clusters)

    def save_gif(
        self, path: str | Path, seconds: float = GIF_SECONDS, progress: bool | None = None, clusters: bool = True
    ) -> int:
        """Write at most ``max_frames`` frames as a looping GIF of about ``seconds`` whatever the mission's
        length, then the final state held 2 s, with one palette for all, showing progress; returns the
        number of frames."""
        if self._last is None:
            raise MrExploreError("no frames recorded; run a mission with the recorder as observer")
        keep = self.frames
        if len(keep) > self.max_frames:
            picks = np.linspace(0, len(keep) - 1, self.max_frames).round().astype(int)
            keep = [keep[i] for i in picks]
        last = _coded(self._frame(self._gif_scale(), clusters))
        frames = [f for f in keep if f.size == last.size] + [last]
        bar = Progress(len(frames), "writing GIF", "frames", progress)

        def rest() -> Iterator[Image.Image]:  # Pillow takes them one by one as it writes
            for f in frames[1:]:
                bar.update()
                yield f

        frame_ms = int(min(1000, max(40, round(seconds * 1000 / max(1, len(frames) - 1), -1))))
        durations = [frame_ms] * (len(frames) - 1) + [2000]
        _write(path, lambda p: frames[0].save(p, save_all=True, append_images=rest(), duration=durations, loop=0))
        bar.update()
        bar.close()
        return len(frames)


def _coded(frame: Image.Image) -> Image.Image:
    """``frame`` in the GIF's one palette (no dithering: flat colours stay flat)."""
    return frame.quantize(palette=_GIF_PALETTE, dither=Image.Dither.NONE)


def _gif_palette() -> Image.Image:
    """One palette for every frame: the colours drawn (robots and their paths, frontiers, map states), and
    a ramp of greys and of each robot's colour for the edges that scaling and text smooth."""
    colours = [_UNKNOWN, _TRUTH_WALL, _FREE, _OCCUPIED, _FAILED, _INK, _CENTRE, (0, 0, 0), (120, 120, 120)]
    colours += FRONTIER_COLOURS + _ROBOT_COLOURS + [_light(c) for c in _ROBOT_COLOURS]
    colours += [(v, v, v) for v in range(0, 256, 8)]
    for c in _ROBOT_COLOURS + FRONTIER_COLOURS:
        colours += [tuple(int(v + (255 - v) * t) for v in c) for t in (0.2, 0.65, 0.85)]  # type: ignore[misc]
    flat = [v for c in colours[:256] for v in c]
    pal = Image.new("P", (1, 1))
    pal.putpalette(flat + [0] * (768 - len(flat)))
    return pal


_GIF_PALETTE = _gif_palette()


def save_png(img: Image.Image, path: str | Path) -> None:
    """Write a picture as PNG with a one-line error if the path cannot be written."""
    _write(path, lambda p: img.save(p, format="PNG"))


def _write(path: str | Path, save: Callable[[Path], None]) -> None:
    p = Path(path)
    try:
        p.parent.mkdir(parents=True, exist_ok=True)
        save(p)
    except OSError as exc:
        raise MrExploreError(f"cannot write {p}: {exc.strerror or exc}; choose a writable path") from None
