"""Pictures: frontiers stay visible on a large map, every frame carries its title, counter, legend and scale
bar at one size, and a long mission's GIF is capped in frames."""

from __future__ import annotations

import numpy as np
from PIL import Image

from mrexplore.config import MapConfig, MissionConfig, SimConfig
from mrexplore.maps.loaders import load_map
from mrexplore.mission import MissionSpec, run_mission
from mrexplore.mission.render import FRONTIER_COLOURS, Caption, GifRecorder, framed, render_frame
from mrexplore.pipeline import make_strategy
from mrexplore.preprocessing.clustering import Clusters
from mrexplore.types import CellState


def test_one_frontier_cell_stays_visible_on_a_large_map_shrunk_tenfold() -> None:
    n = 1000
    state = np.full((n, n), CellState.FREE, np.uint8)
    member, centre = np.array([[500, 500]], np.int32), np.array([[100, 100]], np.int32)  # centre drawn apart
    clusters = Clusters(centre, np.array([1], np.int32), member, np.zeros(1, np.int32))
    img = render_frame(np.zeros((n, n), bool), state, np.zeros((0, 2), int), [], clusters, np.zeros((0, 2), int), 0.1)
    px = np.asarray(img)
    green = np.all(px == FRONTIER_COLOURS[0], axis=-1)
    assert img.size == (100, 100) and green.sum() >= 4  # a 2 x 2 square at least, not averaged away


def test_a_framed_picture_has_its_header_and_legend_around_the_map() -> None:
    map_img = Image.new("RGB", (200, 100), (255, 255, 255))
    out = framed(map_img, Caption("plan: hier, 3 robots", 120, 0.5), metres_per_px=0.05)
    assert out.width == 380 and out.height > 100 + 40 + 30  # widened for the legend, header and footer added
    px = np.asarray(out)
    assert (px[:40] < 100).any()  # the title's and counter's ink
    assert (px[-25:] < 100).any()  # the scale bar


def test_a_long_mission_s_gif_is_capped(tmp_path) -> None:
    truth = load_map("generated:1", MapConfig(resolution_m=0.2))
    recorder = GifRecorder(every=1, max_frames=5, title="capped")
    spec = MissionSpec(truth, make_strategy("utility"), SimConfig(robots=2), MissionConfig(max_steps=60), seed=0)
    run_mission(spec, observer=recorder, progress=False)
    assert len(recorder.frames) < 10 and recorder.every > 1  # thinned while recording
    recorder.save_gif(tmp_path / "run.gif", progress=False)
    with Image.open(tmp_path / "run.gif") as g:
        assert g.n_frames <= 6  # at most max_frames, plus the final state
        sizes = set()
        for k in range(g.n_frames):
            g.seek(k)
            sizes.add(g.size)
    assert len(sizes) == 1
