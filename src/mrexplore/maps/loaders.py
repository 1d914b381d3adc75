"""Loading real map formats (ROS map_server, grayscale renders, HouseExpo JSON, DungeonMaps) by file type.

Every loader returns a :class:`~mrexplore.maps.ground_truth.GroundTruthMap` at the working resolution with
the outside (free space touching the border) turned into obstacle. Bad files raise
:class:`~mrexplore.types.MrExploreError` with one line naming the file, the problem and the fix.
"""

from __future__ import annotations

import functools
import json
import math
import warnings
from pathlib import Path
from typing import Any

import numpy as np
from PIL import Image, ImageDraw, UnidentifiedImageError

from mrexplore.config import MapConfig
from mrexplore.config.safe_yaml import load_yaml_file
from mrexplore.maps.floorplan import FloorplanSpec, generate_floorplan
from mrexplore.maps.frame import GridFrame
from mrexplore.maps.ground_truth import GroundTruthMap, close_narrow_gaps, mark_outside_as_obstacle
from mrexplore.maps.plan_check import check_plan, check_tones
from mrexplore.maps.resample import resample_obstacles
from mrexplore.runtime.example_maps import DEFAULT_MAP
from mrexplore.types import MrExploreError

__all__ = [
    "load_map",
    "load_map_shared",
    "is_generator_spec",
    "DEFAULT_MAP",
    "GRAYSCALE_PIXEL_M",
    "DUNGEON_PIXEL_M",
    "HOUSEEXPO_RASTER_M",
]

"""The built-in map: a procedural floor plan (license-clean, made here from a seed)."""
GRAYSCALE_PIXEL_M = 0.01
"""Default metres per pixel of a grayscale image with no YAML (HouseExpo renders)."""
DUNGEON_PIXEL_M = 0.1
"""Default metres per pixel of a DungeonMaps PNG (the format has no scale of its own)."""
HOUSEEXPO_RASTER_M = 0.01
"""HouseExpo polygons are rasterised at 1 cm, like the dataset's own renders, then min-pooled."""
_HOUSEEXPO_PAD_M = 0.25
_MAX_COORD_M = 1e7
"""Map origins farther than this from 0 (10,000 km) are refused as nonsense."""
_GRAY_FREE_MIN = 128
_DUNGEON_OBSTACLE = (127, 127, 127)
_DUNGEON_FREE = (195, 195, 194)
_DUNGEON_START = (255, 216, 0)
_IMAGE_SUFFIXES = {".png", ".pgm", ".ppm", ".bmp", ".jpg", ".jpeg", ".tif", ".tiff", ".gif"}


def load_map(spec: str | Path, cfg: MapConfig | None = None) -> GroundTruthMap:
    """Load a ground-truth map from a file path or a generator spec.

    Parameters
    ----------
    spec:
        A ``.yaml`` (ROS map_server), an image (grayscale render or DungeonMaps RGB), a HouseExpo
        ``.json``, ``generated:SEED`` for the built-in procedural floor plan, ``varied:SEED`` for
        one whose size, outline, rooms, corridor and clutter the seed draws too (the training plans), or
        ``example:NAME`` for a map shipped with the package (``mrexplore maps`` lists them).
    cfg:
        Working resolution and pixel size of images without YAML.

    Examples
    --------
    >>> m = load_map("generated:3", MapConfig(resolution_m=0.1))
    >>> m.resolution_m, m.name
    (0.1, 'generated:3')
    """
    cfg = cfg or MapConfig()
    text = str(spec)
    path = Path(text)
    if is_generator_spec(text):
        return _load_generated(text, cfg)
    if text.startswith("example:") and not path.exists():  # a map shipped with the package
        from mrexplore.maps.datasets import example_path

        path = example_path(text.removeprefix("example:"))
    if not path.exists():
        raise MrExploreError(f"map file not found: {path}; pass an existing map file with --map")
    if path.is_dir():
        raise MrExploreError(f"map path is a folder: {path}; pass one map file with --map")
    if not path.is_file():
        raise MrExploreError(f"map path {path} is not a regular file; pass a map file with --map")
    size = path.stat().st_size
    if size > cfg.max_file_bytes:
        raise MrExploreError(
            f"map file {path} is {size} bytes, over the limit of {cfg.max_file_bytes} (map.max_file_bytes); "
            "raise it in --config if the map is real"
        )
    suffix = path.suffix.lower()
    if suffix in (".yaml", ".yml"):
        return _load_ros_yaml(path, cfg)
    if suffix == ".json":
        return _load_houseexpo_json(path, cfg)
    if suffix in _IMAGE_SUFFIXES:
        sibling = path.with_suffix(".yaml")
        if sibling.exists() and _yaml_image_name(sibling) == path.name:
            return _load_ros_yaml(sibling, cfg)
        return _load_image(path, cfg)
    raise MrExploreError(
        f"unsupported map format {suffix!r}: {path}; use a ROS .yaml, a .png/.pgm image or a HouseExpo .json"
    )


@functools.lru_cache(maxsize=2)
def load_map_shared(spec: str, cfg: MapConfig) -> GroundTruthMap:
    """:func:`load_map`, kept for the next episodes of the same map in this process (a bench's or a
    trainer's worker runs them one after another) and read-only, as missions never write the ground truth."""
    truth = load_map(spec, cfg)
    truth.occupied.flags.writeable = False
    return truth


def is_generator_spec(text: str) -> bool:
    """Whether ``text`` names the procedural generator (``generated``, ``generated:SEED`` or ``varied:SEED``)
    rather than a file: an existing file of that name is always read as the file."""
    named = text == "generated" or text.startswith(("generated:", "varied:"))
    return named and not Path(text).exists()


def _check_cells(name: str, extent_px: tuple[int, int], pixel_m: float, cfg: MapConfig) -> None:
    """Refuse, before any work, a map whose working grid would exceed ``cfg.max_cells``."""
    h = math.ceil(extent_px[0] * pixel_m / cfg.resolution_m)
    w = math.ceil(extent_px[1] * pixel_m / cfg.resolution_m)
    if h * w > cfg.max_cells:
        raise MrExploreError(
            f"map {name} at {cfg.resolution_m} m per cell would be {h} x {w} = {h * w} cells, over the limit "
            f"of {cfg.max_cells} (map.max_cells); use a coarser --resolution or raise the limit in --config"
        )


def _check_pixels(name: str, w: int, h: int, cfg: MapConfig) -> None:
    if w * h > cfg.max_image_pixels:
        raise MrExploreError(
            f"map {name} is {w} x {h} = {w * h} pixels, over the limit of {cfg.max_image_pixels} "
            "(map.max_image_pixels); raise it in --config if the map is real"
        )


def _finish(
    obstacle: np.ndarray, frame: GridFrame, name: str, start_rc: tuple[int, int] | None, cfg: MapConfig
) -> GroundTruthMap:
    # A gap of width w is filled by a closing of radius ceil(w / 2) cells.
    radius = math.ceil(cfg.min_passage_m / frame.resolution_m / 2 - 1e-9)
    occupied = close_narrow_gaps(obstacle, radius)
    occupied = mark_outside_as_obstacle(occupied, cfg.outside_opening_m / frame.resolution_m)
    if not (~occupied).any():
        raise MrExploreError(
            f"map {name} has no free space enclosed by walls (no wall outline found); check the file's "
            "free/occupied values"
        )
    check_plan(occupied, frame.resolution_m, name)
    if start_rc is not None and occupied[start_rc]:
        start_rc = None
    return GroundTruthMap(occupied=occupied, frame=frame, name=name, start_hint_rc=start_rc)


def _load_generated(text: str, cfg: MapConfig) -> GroundTruthMap:
    kind, _, seed_text = text.partition(":")
    try:
        seed = int(seed_text) if seed_text else 0
        if seed < 0:
            raise ValueError
    except ValueError:
        raise MrExploreError(f"bad generator spec {text!r}; write {kind}:SEED with an integer SEED >= 0") from None
    spec = FloorplanSpec.varied(seed) if kind == "varied" else FloorplanSpec(seed=seed)
    _check_cells(text, (math.ceil(spec.height_m), math.ceil(spec.width_m)), 1.0, cfg)
    obstacle = generate_floorplan(spec, cfg.resolution_m)
    frame = GridFrame(obstacle.shape[0], obstacle.shape[1], cfg.resolution_m)
    return _finish(obstacle, frame, f"{kind}:{seed}", None, cfg)


def _read_yaml(path: Path) -> dict[str, Any]:
    data = load_yaml_file(path, f"map YAML {path}")
    if not isinstance(data, dict):
        raise MrExploreError(f"malformed map YAML {path}: not a mapping; give a ROS map_server YAML")
    return data


def _yaml_image_name(path: Path) -> str | None:
    try:
        data = _read_yaml(path)
    except MrExploreError:
        return None
    image = data.get("image")
    return Path(str(image)).name if image is not None else None


def _open_image(path: Path, cfg: MapConfig, pixel_m: float | None = None) -> Image.Image:
    """Decode an image once its header passed the pixel limit (and, given ``pixel_m``, the cell limit)."""
    if not path.is_file():
        raise MrExploreError(f"map image {path} not found; fix the path in the map YAML")
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error", Image.DecompressionBombWarning)
            img = Image.open(path)
            size = (img.width, img.height)
    except (OSError, UnidentifiedImageError, ValueError, SyntaxError, Image.DecompressionBombWarning) as exc:
        raise MrExploreError(f"cannot read map image {path}: {exc}; give a PNG/PGM map image") from None
    except Image.DecompressionBombError:
        raise MrExploreError(f"map image {path} is larger than any map should be; give a real map image") from None
    _check_pixels(str(path), size[0], size[1], cfg)
    if pixel_m is not None:
        _check_cells(str(path), (size[1], size[0]), pixel_m, cfg)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error", Image.DecompressionBombWarning)
            img.load()
    except (OSError, ValueError, SyntaxError, Image.DecompressionBombWarning) as exc:
        raise MrExploreError(f"cannot read map image {path}: {exc}; give a PNG/PGM map image") from None
    return img


def _load_ros_yaml(path: Path, cfg: MapConfig) -> GroundTruthMap:
    data = _read_yaml(path)
    for key in ("image", "resolution"):
        if key not in data:
            raise MrExploreError(f"malformed map YAML {path}: missing key {key!r}; give a ROS map_server YAML")
    try:
        resolution = float(data["resolution"])
        origin = [float(v) for v in data.get("origin", [0.0, 0.0, 0.0])]
        negate = int(data.get("negate", 0))
        free_th = float(data.get("free_thresh", 0.196))
    except (TypeError, ValueError, OverflowError) as exc:
        raise MrExploreError(f"malformed map YAML {path}: {exc}; fix the numeric fields") from None
    if not (math.isfinite(resolution) and resolution > 0) or len(origin) < 2:
        raise MrExploreError(
            f"malformed map YAML {path}: resolution must be a finite number > 0 and origin [x, y, yaw]"
        )
    if not all(math.isfinite(v) and abs(v) <= _MAX_COORD_M for v in origin) or not math.isfinite(free_th):
        raise MrExploreError(
            f"malformed map YAML {path}: origin and free_thresh must be finite numbers, origin within "
            f"{_MAX_COORD_M:g} m; fix the numeric fields"
        )
    if not isinstance(data["image"], str):
        raise MrExploreError(f"malformed map YAML {path}: image must be a file name; give a ROS map_server YAML")
    img = _open_image(path.parent / data["image"], cfg, resolution)
    gray = np.asarray(img.convert("L"), dtype=np.float64)
    # map_server: p = (255 - v) / 255 (negate 0); free below free_thresh, occupied above occupied_thresh,
    # unknown between. Only free counts as free: unknown ground truth is obstacle, nothing is known behind it.
    p = gray / 255.0 if negate else (255.0 - gray) / 255.0
    obstacle = ~(p < free_th)
    obstacle = resample_obstacles(obstacle, resolution, cfg.resolution_m)
    frame = GridFrame(obstacle.shape[0], obstacle.shape[1], cfg.resolution_m, (origin[0], origin[1]))
    return _finish(obstacle, frame, path.stem, None, cfg)


def _is_dungeon(rgb: np.ndarray) -> bool:
    colours = np.unique(rgb.reshape(-1, 3), axis=0)
    known = {_DUNGEON_OBSTACLE, _DUNGEON_FREE, _DUNGEON_START}
    return len(colours) <= 3 and all(tuple(int(v) for v in c) in known for c in colours)


def _load_image(path: Path, cfg: MapConfig) -> GroundTruthMap:
    img = _open_image(path, cfg)
    start_rc = None
    if img.mode in ("RGB", "RGBA", "P") and _is_dungeon(rgb := np.asarray(img.convert("RGB"))):
        pixel = cfg.pixel_size_m or DUNGEON_PIXEL_M
        free = np.all(rgb == _DUNGEON_FREE, axis=-1)
        marker = np.all(rgb == _DUNGEON_START, axis=-1)
        obstacle = ~(free | marker)
        if marker.any():
            rr, cc = np.nonzero(marker)
            scale = pixel / cfg.resolution_m
            start_rc = (int(rr.mean() * scale), int(cc.mean() * scale))
    else:
        pixel = cfg.pixel_size_m or GRAYSCALE_PIXEL_M
        gray = np.asarray(img.convert("L"))
        check_tones(gray, path.stem)
        obstacle = gray < _GRAY_FREE_MIN
    _check_cells(str(path), obstacle.shape, pixel, cfg)
    obstacle = resample_obstacles(obstacle, pixel, cfg.resolution_m)
    frame = GridFrame(obstacle.shape[0], obstacle.shape[1], cfg.resolution_m)
    if start_rc is not None:
        start_rc = (min(start_rc[0], frame.height - 1), min(start_rc[1], frame.width - 1))
    return _finish(obstacle, frame, path.stem, start_rc, cfg)


def _load_houseexpo_json(path: Path, cfg: MapConfig) -> GroundTruthMap:
    try:
        data = json.loads(path.read_text())
        verts = np.asarray(data["verts"], dtype=np.float64)
    except RecursionError:
        raise MrExploreError(
            f"malformed HouseExpo JSON {path}: nested too deeply; give a file with a 'verts' polygon"
        ) from None
    except (OSError, UnicodeDecodeError, json.JSONDecodeError, KeyError, TypeError, ValueError) as exc:
        reason = str(exc).splitlines()[0] if str(exc) else ""
        raise MrExploreError(
            f"malformed HouseExpo JSON {path}: {type(exc).__name__} {reason}; give a file with a 'verts' polygon"
        ) from None
    if verts.ndim != 2 or verts.shape[1] != 2 or len(verts) < 3 or not np.isfinite(verts).all():
        raise MrExploreError(f"malformed HouseExpo JSON {path}: 'verts' must be >= 3 [x, y] points in metres")
    lo = verts.min(axis=0) - _HOUSEEXPO_PAD_M
    hi = verts.max(axis=0) + _HOUSEEXPO_PAD_M
    w = math.ceil((hi[0] - lo[0]) / HOUSEEXPO_RASTER_M)
    h = math.ceil((hi[1] - lo[1]) / HOUSEEXPO_RASTER_M)
    _check_pixels(str(path), w, h, cfg)
    _check_cells(str(path), (h, w), HOUSEEXPO_RASTER_M, cfg)
    canvas = Image.new("L", (w, h), 0)
    # Row grows with -y (map frame convention), so flip y when rasterising.
    px = [((x - lo[0]) / HOUSEEXPO_RASTER_M, (hi[1] - y) / HOUSEEXPO_RASTER_M) for x, y in verts]
    ImageDraw.Draw(canvas).polygon(px, fill=255)
    obstacle = np.asarray(canvas) < _GRAY_FREE_MIN
    obstacle = resample_obstacles(obstacle, HOUSEEXPO_RASTER_M, cfg.resolution_m)
    frame = GridFrame(obstacle.shape[0], obstacle.shape[1], cfg.resolution_m, (float(lo[0]), float(lo[1])))
    return _finish(obstacle, frame, path.stem, None, cfg)
