"""Map loading: every format, resampling by min-pooling, outside removal and one-line errors."""

from __future__ import annotations

import json

import numpy as np
import pytest
from conftest import require_shared_maps
from PIL import Image

from mrexplore.config import MapConfig
from mrexplore.maps.ground_truth import free_components
from mrexplore.maps.loaders import load_map
from mrexplore.maps.resample import resample_obstacles
from mrexplore.types import MrExploreError


def _room_pixels(n: int = 20, wall: int = 1) -> np.ndarray:
    """An n x n grayscale image: 0 walls around (and a one-pixel interior wall), 255 inside."""
    img = np.zeros((n, n), np.uint8)
    img[wall:-wall, wall:-wall] = 255
    img[:, n // 2] = 0  # one-pixel wall splitting the room
    img[n // 2 - 2 : n // 2 + 2, n // 2] = 255  # a 4-pixel door in it
    return img


def test_min_pool_keeps_one_pixel_walls() -> None:
    img = np.zeros((10, 10), bool)
    img[:, 5] = True  # one-pixel wall at column 5
    out = resample_obstacles(img, 0.01, 0.05)
    assert out.shape == (2, 2)
    assert out[:, 1].all() and not out[:, 0].any()


def test_upsampling_repeats_pixels() -> None:
    img = np.array([[True, False]])
    assert resample_obstacles(img, 0.1, 0.05).tolist() == [[True, True, False, False]] * 2


def test_grayscale_png_at_pixel_size(tmp_path) -> None:
    p = tmp_path / "room.png"
    Image.fromarray(_room_pixels()).save(p)
    m = load_map(p, MapConfig(resolution_m=0.02, pixel_size_m=0.01, min_passage_m=0))
    assert m.shape == (10, 10)
    assert m.occupied[:, 5].sum() == 8  # wall column survives except the 2-cell door
    assert not m.occupied[5, 3]


def test_ros_yaml_trinary_unknown_is_obstacle_and_origin_kept(tmp_path) -> None:
    img = np.full((6, 8), 254, np.uint8)
    img[0, :] = img[-1, :] = img[:, 0] = img[:, -1] = 0
    img[2, 3] = 205  # unknown
    Image.fromarray(img).save(tmp_path / "m.pgm")
    (tmp_path / "m.yaml").write_text(
        "image: m.pgm\nresolution: 0.1\norigin: [-1.0, 2.0, 0.0]\nnegate: 0\n"
        "occupied_thresh: 0.65\nfree_thresh: 0.196\n"
    )
    cfg = MapConfig(resolution_m=0.1, min_passage_m=0)
    m = load_map(tmp_path / "m.yaml", cfg)
    assert m.occupied[2, 3] and not m.occupied[2, 2]
    assert m.frame.origin_xy == (-1.0, 2.0)
    assert m.frame.rc_to_xy((5, 0)) == (-0.95, 2.05)
    # Loading the image directly finds its YAML beside it.
    assert np.array_equal(load_map(tmp_path / "m.pgm", cfg).occupied, m.occupied)


def test_outside_free_space_touching_border_becomes_obstacle(tmp_path) -> None:
    img = np.full((12, 12), 255, np.uint8)  # free outside, like KTH plans
    img[2:10, 2:10] = 0
    img[3:9, 3:9] = 255  # the building's inside
    Image.fromarray(img).save(tmp_path / "plan.png")
    cfg = MapConfig(resolution_m=0.01, pixel_size_m=0.01, outside_opening_m=0.015, min_passage_m=0)
    m = load_map(tmp_path / "plan.png", cfg)
    assert int((~m.occupied).sum()) == 36


def test_door_in_outer_wall_does_not_make_the_inside_outside(tmp_path) -> None:
    img = np.full((40, 40), 255, np.uint8)  # free outside
    img[8:32, 8:32] = 0
    img[10:30, 10:30] = 255  # a 20 x 20 room ...
    img[18:21, 8:10] = 255  # ... with a 3-pixel door through its 2-pixel wall
    Image.fromarray(img).save(tmp_path / "plan.png")
    cfg = MapConfig(resolution_m=0.01, pixel_size_m=0.01, outside_opening_m=0.03, min_passage_m=0)
    free = ~load_map(tmp_path / "plan.png", cfg).occupied
    assert free[10:30, 10:30].all() and free[18:21, 9].all()  # room and door kept (up to the wall line)
    assert not free[:8].any() and not free[:, :7].any()  # the open land around is outside


def test_slivers_narrower_than_a_robot_are_closed(tmp_path) -> None:
    # Two rooms whose walls meet with a 6 px (6 cm) sliver, as in HouseExpo 4e7034e3..., and a real
    # 60 px door elsewhere: at 0.05 m the sliver would be a one-cell gap; it must not connect the rooms.
    img = np.full((200, 400), 255, np.uint8)
    img[:10], img[-10:], img[:, :10], img[:, -10:] = 0, 0, 0, 0
    img[:, 195:205] = 0  # wall between the rooms
    img[100:106, 195:205] = 255  # the sliver
    img[20:80, 195:205] = 255  # the door
    Image.fromarray(img).save(tmp_path / "two.png")
    occ = load_map(tmp_path / "two.png", MapConfig(resolution_m=0.05)).occupied
    assert occ[20, 39:41].all()  # sliver cells (rows 100-105 px -> cell 20) closed
    assert not occ[8, 39:41].any()  # the door stays open
    loose = load_map(tmp_path / "two.png", MapConfig(resolution_m=0.05, min_passage_m=0)).occupied
    assert not loose[20, 39:41].all()


def test_houseexpo_json_polygon_rasterised(tmp_path) -> None:
    # A 2 m x 1 m rectangle: 200 x 100 free cells at 1 cm, 40 x 20 at 5 cm.
    verts = [[0, 0], [2, 0], [2, 1], [0, 1]]
    (tmp_path / "h.json").write_text(json.dumps({"id": "h", "verts": verts}))
    m = load_map(tmp_path / "h.json", MapConfig(resolution_m=0.05))
    free = ~m.occupied
    rows, cols = np.nonzero(free)
    assert (rows.max() - rows.min() + 1, cols.max() - cols.min() + 1) in {(20, 40), (21, 41), (20, 41), (21, 40)}
    assert m.frame.origin_xy == (-0.25, -0.25)


def test_dungeon_rgb_colours_and_start_marker(tmp_path) -> None:
    img = np.zeros((40, 40, 3), np.uint8)
    img[:] = (127, 127, 127)
    img[5:35, 5:35] = (195, 195, 194)
    img[10:14, 20:24] = (255, 216, 0)
    Image.fromarray(img).save(tmp_path / "d.png")
    m = load_map(tmp_path / "d.png", MapConfig(resolution_m=0.1))  # default 0.1 m per pixel
    assert m.shape == (40, 40)
    assert m.start_hint_rc == (11, 21)
    assert int((~m.occupied).sum()) == 900


@pytest.mark.parametrize(
    ("name", "content", "message"),
    [
        ("bad.yaml", "image: [unclosed", "map YAML .* is not valid YAML at line 1"),
        ("nokey.yaml", "resolution: 0.05\n", "missing key 'image'"),
        ("bad.png", "not an image", "cannot read map image"),
        ("bad.json", "{]", "malformed HouseExpo JSON"),
        ("map.txt", "x", "unsupported map format '.txt'"),
    ],
)
def test_malformed_files_give_one_line_errors(tmp_path, name: str, content: str, message: str) -> None:
    p = tmp_path / name
    p.write_text(content)
    with pytest.raises(MrExploreError, match=message) as err:
        load_map(p)
    assert "\n" not in str(err.value)


def test_missing_file_and_no_free_space(tmp_path) -> None:
    with pytest.raises(MrExploreError, match=r"^map file not found: .*nope.png; pass an existing map file"):
        load_map(tmp_path / "nope.png")
    Image.fromarray(np.zeros((8, 8), np.uint8)).save(tmp_path / "black.png")
    with pytest.raises(MrExploreError, match=r"has no free space enclosed by walls \(no wall outline found\)"):
        load_map(tmp_path / "black.png")


@pytest.mark.parametrize(
    "rel",
    [
        "ros/willow-2010-02-18-0.10.yaml",
        "ros/basement_hallways_5cm.yaml",
        "kth_floorplans/50010535_PLAN1.yaml",
        "houseexpo/json/0004d52d1aeeb8ae6de39d6bd993e992.json",
        "houseexpo/png/06a0e96d04560015cb2062975f94cac4.png",
        "dungeon/easy_img_15.png",
    ],
)
def test_every_shared_format_loads(rel: str) -> None:
    m = load_map(require_shared_maps() / rel, MapConfig(resolution_m=0.1))
    labels, n = free_components(m.occupied)
    largest_m2 = np.bincount(labels.ravel())[1:].max() * 0.01
    assert largest_m2 > 20  # a building's inside survives (doors and leaking rays do not make it outside)


def test_kth_outside_removed_inside_kept() -> None:
    m = load_map(require_shared_maps() / "kth_floorplans/50052748.yaml", MapConfig(resolution_m=0.1))
    free = ~m.occupied
    assert not free[0, 0] and not free[-1, 0]  # the open land around the building
    assert 2000 < free.sum() * 0.01 < 3000  # the floor itself: 2,538 m2 in its largest component
