"""The floor-plan check: photographs, noise and images with no enclosed free space are refused in one line
naming the reason; a borderline image warns; no example map warns."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from conftest import SHARED_MAPS, require_shared_maps
from PIL import Image
from scipy import ndimage

from mrexplore.cli import main
from mrexplore.config import MapConfig
from mrexplore.maps.loaders import load_map
from mrexplore.maps.plan_check import MapWarning, check_plan
from mrexplore.types import MrExploreError


def _save(tmp_path, name: str, gray: np.ndarray) -> str:
    path = tmp_path / f"{name}.png"
    Image.fromarray(gray.astype(np.uint8)).save(path)
    return str(path)


def _blocks(rng: np.random.Generator, grain: int, black: float) -> np.ndarray:
    """A 12 m x 12 m image (0.01 m pixels) of random black and white squares of ``grain`` pixels."""
    b = rng.random((1200 // grain, 1200 // grain)) >= black
    return np.kron(b, np.ones((grain, grain), bool)) * 255


def _refusal(path: str) -> str:
    with pytest.raises(MrExploreError) as err:
        load_map(path, MapConfig(resolution_m=0.1))
    return str(err.value)


def test_a_photograph_noise_and_an_open_image_are_refused(tmp_path) -> None:
    rng = np.random.default_rng(1)
    photo = ndimage.gaussian_filter(rng.random((300, 400)), 8)
    photo = (photo - photo.min()) / (photo.max() - photo.min()) * 255
    got = _refusal(_save(tmp_path, "photo", photo))
    assert got.startswith("map photo is not a floor plan: ") and "of its pixels are mid grey (a photograph?)" in got
    assert _refusal(_save(tmp_path, "pieces", _blocks(rng, 20, 0.5))).startswith(
        "map pieces is not a floor plan: its free space is "
    )
    assert "scattered pieces" in _refusal(_save(tmp_path, "specks", _blocks(rng, 30, 0.3)))
    assert _refusal(_save(tmp_path, "white", np.full((200, 200), 255))) == (
        "map white has no free space enclosed by walls (no wall outline found); check the file's free/occupied values"
    )
    grains = _refusal(_save(tmp_path, "grains", _blocks(np.random.default_rng(0), 8, 0.5)))
    assert grains.startswith(("map grains is not a floor plan: ", "map grains has no free space enclosed by walls"))
    room = np.zeros((20, 20), bool)  # 2 m x 2 m: too little to judge, loads
    check_plan(np.pad(room, 1, constant_values=True), 0.1, "small")


def test_a_borderline_plan_warns_in_one_line(tmp_path, capsys) -> None:
    """A 10 m x 10 m room with 40 pillars (0.4 pieces of wall per m^2): loads, with a warning."""
    room = np.ones((100, 100), bool)
    room[1:99, 1:99] = False
    room[10:90:12, 10:90:12] = True  # 7 x 7 pillars, 0.1 m each
    with pytest.warns(MapWarning, match=r"^map pillars may not be a floor plan: 100% of its free space in one region"):
        check_plan(room, 0.1, "pillars")
    grey = np.where(room, 0, 255)
    grey[:, :10] = 150  # a tenth of the image mid grey
    path = _save(tmp_path, "greyish", np.kron(grey, np.ones((10, 10))))
    assert main(["explore", "--map", path, "--robots", "1", "--max-steps", "5", "--no-progress"]) == 0
    err = capsys.readouterr().err.splitlines()
    assert err[0] == (
        "mrexplore: warning: map greyish: 10% of its pixels are mid grey, read as free above 128 and wall below; "
        "check the result with --png"
    )


@pytest.mark.slow
def test_no_example_map_warns() -> None:
    require_shared_maps()
    files = sorted(SHARED_MAPS.glob("dungeon/*.png")) + sorted(SHARED_MAPS.glob("houseexpo/png/*.png"))
    files += sorted(SHARED_MAPS.glob("kth_floorplans/*.yaml")) + sorted(SHARED_MAPS.glob("ros/*.yaml"))
    with warnings.catch_warnings():
        warnings.simplefilter("error", MapWarning)
        for f in files:
            load_map(f, MapConfig(resolution_m=0.1))
