"""Pictures of a mission: frames of the centre's map with robots, trails, clusters and goals; GIF and PNG."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from pathlib import Path

import numpy as np
from numpy.typing import NDArray
from PIL import Image, ImageDraw

from mrexplore.pipeline import Decision
from mrexplore.preprocessing.clustering import Clusters
from mrexplore.preprocessing.transmission import LinkStatus
from mrexplore.sim.belief import merge_beliefs
from mrexplore.sim.world import ExplorationSim
from mrexplore.types import CellState, MrExploreError, StateGrid

__all__ = ["render_frame", "GifRecorder", "save_png"]

_UNKNOWN = (205, 205, 205)
_TRUTH_WALL = (172, 172, 172)
_FREE = (255, 255, 255)
_OCCUPIED = (20, 20, 20)
_FAILED = (128, 128, 128)
_ROBOT_COLOURS = [
    (220, 50, 47),
    (38, 139, 210),
    (133, 153, 0),
    (211, 54, 130),
    (181, 137, 0),
    (42, 161, 152),
    (108, 113, 196),
    (203, 75, 22),
]
_CLUSTER_COLOURS = [
    (255, 127, 14),
    (44, 160, 44),
    (148, 103, 189),
    (23, 190, 207),
    (188, 189, 34),
    (227, 119, 194),
    (140, 86, 75),
    (31, 119, 180),
]


def _robot_colour(i: int) -> tuple[int, int, int]:
    return _ROBOT_COLOURS[i % len(_ROBOT_COLOURS)]


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
    """One RGB picture: ground truth faded under the belief, cluster members, trails, robots, goals.

    ``scale`` is output pixels per cell (below 1 shrinks, box-averaged). Faults: a ``failed`` robot is
    drawn grey and crossed out; one the centre does not assign to (``unheard``: silent too long, out of
    range, or not heard since the centre restarted) as a ring without fill.
    """
    rgb = np.empty((*state.shape, 3), dtype=np.uint8)
    rgb[:] = _UNKNOWN
    rgb[truth_occupied] = _TRUTH_WALL
    rgb[state == CellState.FREE] = _FREE
    rgb[state == CellState.OCCUPIED] = _OCCUPIED
    if clusters is not None and len(clusters):
        colours = np.array(_CLUSTER_COLOURS, dtype=np.uint8)[clusters.labels % len(_CLUSTER_COLOURS)]
        rgb[clusters.members_rc[:, 0], clusters.members_rc[:, 1]] = colours
    img = Image.fromarray(rgb)
    if scale != 1.0:
        size = (max(1, round(img.width * scale)), max(1, round(img.height * scale)))
        img = img.resize(size, Image.Resampling.BOX if scale < 1 else Image.Resampling.NEAREST)
    draw = ImageDraw.Draw(img)
    rad = max(2.0, 3.0 * max(scale, 0.5))
    for i, trail in enumerate(trails):
        if len(trail) > 1:
            light = tuple(int(v + (255 - v) * 0.45) for v in _robot_colour(i))
            xy = [((c + 0.5) * scale, (r + 0.5) * scale) for r, c in np.asarray(trail)]
            draw.line(xy, fill=light, width=max(1, round(scale)))
    for i, (r, c) in enumerate(np.asarray(goals_rc)):
        if r < 0:
            continue
        x, y = (c + 0.5) * scale, (r + 0.5) * scale
        draw.line([(x - rad, y - rad), (x + rad, y + rad)], fill=_robot_colour(i), width=2)
        draw.line([(x - rad, y + rad), (x + rad, y - rad)], fill=_robot_colour(i), width=2)
    for i, (r, c) in enumerate(np.asarray(positions_rc)):
        x, y = (c + 0.5) * scale, (r + 0.5) * scale
        box = [x - rad, y - rad, x + rad, y + rad]
        if failed is not None and failed[i]:
            draw.ellipse(box, fill=_FAILED, outline=(0, 0, 0))
            draw.line([(x - rad, y - rad), (x + rad, y + rad)], fill=(0, 0, 0), width=1)
            draw.line([(x - rad, y + rad), (x + rad, y - rad)], fill=(0, 0, 0), width=1)
        elif unheard is not None and unheard[i]:
            draw.ellipse(box, fill=None, outline=_robot_colour(i), width=2)
        else:
            draw.ellipse(box, fill=_robot_colour(i), outline=(0, 0, 0))
    return img


class GifRecorder:
    """Mission observer that keeps a frame every ``every`` steps (at most ``max_side`` pixels a side)."""

    def __init__(self, every: int = 10, max_side: int = 480) -> None:
        self.every = every
        self.max_side = max_side
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
        if sim.steps % self.every == 0:
            self.frames.append(self._frame(scale=min(1.0, self.max_side / max(sim.truth.shape))))

    def _frame(self, scale: float) -> Image.Image:
        assert self._last is not None
        sim, decision, goals, status = self._last
        state = merge_beliefs(sim.beliefs).state(sim.cfg.sensor)  # the team's raw knowledge
        trails = [np.asarray(t, dtype=np.int32) for t in self._trails]
        clusters = decision.clusters if decision is not None else None
        return render_frame(
            sim.truth.occupied,
            state,
            sim.positions_rc,
            trails,
            clusters,
            goals,
            scale,
            failed=~sim.alive,
            unheard=~status.assignable,
        )

    def final_frame(self, min_side: int = 400) -> Image.Image:
        """The last state at full resolution (enlarged for small maps)."""
        assert self._last is not None
        side = max(self._last[0].truth.shape)
        return self._frame(scale=max(1.0, float(np.ceil(min_side / side))))

    def save_gif(self, path: str | Path, frame_ms: int = 80) -> None:
        """Write the frames (plus the final state, held longer) as a looping GIF."""
        if self._last is None:
            raise MrExploreError("no frames recorded; run a mission with the recorder as observer")
        frames = [*self.frames, self._frame(scale=min(1.0, self.max_side / max(self._last[0].truth.shape)))]
        durations = [frame_ms] * (len(frames) - 1) + [2000]
        _write(
            path,
            lambda p: frames[0].save(
                p, save_all=True, append_images=frames[1:], duration=durations, loop=0, optimize=False
            ),
        )


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
