"""ROS map_server export: the saved YAML + PGM loads back cell for cell."""

from __future__ import annotations

import numpy as np
import pytest
import yaml
from conftest import state_grid
from PIL import Image

from mrexplore.config import MapConfig
from mrexplore.maps.frame import GridFrame
from mrexplore.maps.loaders import load_map
from mrexplore.maps.map_saver import save_ros_map
from mrexplore.types import CellState, MrExploreError

CENTRE = """
    ??????????
    ?########?
    ?#......#?
    ?#..#...#?
    ?#......??
    ?########?
    ??????????
"""


def test_roundtrip_through_the_loader(tmp_path) -> None:
    state = state_grid(CENTRE)
    frame = GridFrame(state.shape[0], state.shape[1], 0.1, (1.5, -2.0))
    yaml_path, pgm_path = save_ros_map(state, frame, tmp_path / "centre.yaml")
    assert (yaml_path.name, pgm_path.name) == ("centre.yaml", "centre.pgm")
    meta = yaml.safe_load(yaml_path.read_text())
    assert meta["image"] == "centre.pgm" and meta["resolution"] == 0.1 and meta["origin"] == [1.5, -2.0, 0.0]
    pixels = np.asarray(Image.open(pgm_path))
    assert pixels[2, 2] == 254 and pixels[1, 1] == 0 and pixels[0, 0] == 205  # map_saver's values
    loaded = load_map(yaml_path, MapConfig(resolution_m=0.1, min_passage_m=0))
    assert loaded.frame == frame
    # map_server reads unknown as not free; the loader makes every non-free cell an obstacle.
    assert np.array_equal(~loaded.occupied, state == CellState.FREE)


def test_missing_folder_is_one_line(tmp_path) -> None:
    state = state_grid(CENTRE)
    frame = GridFrame(state.shape[0], state.shape[1], 0.1)
    with pytest.raises(MrExploreError, match=r"^cannot save the map to .*nope/m: folder .*nope does not exist"):
        save_ros_map(state, frame, tmp_path / "nope" / "m")
