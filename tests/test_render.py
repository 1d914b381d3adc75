"""Pictures: frontiers stay visible on a large map, every frame carries its title, counter, legend and scale
bar at one size, a long mission's GIF is capped in frames, and the final picture is one a person reads."""

from __future__ import annotations

import numpy as np
from PIL import Image

from mrexplore.config import MapConfig, MissionConfig, SimConfig
from mrexplore.maps.loaders import load_map
from mrexplore.mission import MissionSpec, run_mission
from mrexplore.mission.render import (
    _ROBOT_COLOURS,
    _TRUTH_WALL,
    _UNKNOWN,
    FRONTIER_COLOURS,
    Caption,
    GifRecorder,
    _legend_items,
    framed,
    render_frame,
)
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


def test_a_picture_a_person_reads(tmp_path) -> None:
    # one legend entry per robot in well-separated colours, 900 px at least, the coverage as the text says it,
    # no clusters once none are left, and a GIF of about ten seconds whatever the mission's length
    truth = load_map("generated:1", MapConfig(resolution_m=0.2))
    recorder = GifRecorder(title="plan")
    spec = MissionSpec(truth, make_strategy("utility"), SimConfig(robots=3), MissionConfig(max_steps=80), seed=0)
    run_mission(spec, observer=recorder, progress=False)
    assert [label for _, label in _legend_items(False, 3)][:4] == ["robot 1", "robot 2", "robot 3", "its path"]
    assert [label for _, label in _legend_items(False, 10)][7:9] == ["robot 8", "robots 9-10"]
    colours = np.array(_ROBOT_COLOURS, float)
    gaps = np.linalg.norm(colours[:, None] - colours[None], axis=-1)[np.triu_indices(len(colours), 1)]
    assert gaps.min() > 60  # no two robots alike (red and magenta were 45 apart)
    final = recorder.final_frame(clusters=False)
    assert max(final.size) >= 900
    px = np.asarray(final)[: final.height * 3 // 4]  # the map, above the legend
    assert not np.all(px == FRONTIER_COLOURS[0], axis=-1).any()  # no frontier drawn
    assert np.all(px == _UNKNOWN, axis=-1).any() or np.all(px == _TRUTH_WALL, axis=-1).any()
    assert np.abs(np.array(_UNKNOWN, int) - np.array(_TRUTH_WALL, int)).min() >= 50  # two greys told apart
    n = recorder.save_gif(tmp_path / "run.gif", progress=False)
    with Image.open(tmp_path / "run.gif") as g:
        total = 0
        for k in range(g.n_frames):
            g.seek(k)
            total += g.info["duration"]
    assert n >= 2 and 8000 <= total - 2000 <= 12000  # about 10 s, then the end held 2 s (equal frames merged)
