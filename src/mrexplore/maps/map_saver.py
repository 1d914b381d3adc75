"""Writing a three-state grid as a ROS map_server map (YAML + PGM), like ``map_saver`` does."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import yaml
from PIL import Image

from mrexplore.maps.frame import GridFrame
from mrexplore.types import CellState, MrExploreError, StateGrid

__all__ = ["save_ros_map", "PGM_VALUES"]

PGM_VALUES = {CellState.FREE: 254, CellState.OCCUPIED: 0, CellState.UNKNOWN: 205}
"""Pixel value per state, map_saver's trinary convention."""
_OCCUPIED_THRESH = 0.65
_FREE_THRESH = 0.196


def save_ros_map(state: StateGrid, frame: GridFrame, path: str | Path) -> tuple[Path, Path]:
    """Write ``path``.yaml and ``path``.pgm (a ``.yaml`` suffix on ``path`` is dropped first).

    The YAML gives the resolution, the origin of the lower-left cell and map_server's thresholds; the PGM
    holds free as 254, occupied as 0 and unknown as 205, row 0 at the top. Returns both paths.
    """
    base = Path(path)
    if base.suffix.lower() in (".yaml", ".yml", ".pgm"):
        base = base.with_suffix("")
    if not base.parent.is_dir():
        raise MrExploreError(f"cannot save the map to {base}: folder {base.parent} does not exist; create it first")
    if state.shape != (frame.height, frame.width):
        raise MrExploreError(f"grid {state.shape} does not match its frame {(frame.height, frame.width)}")
    lut = np.zeros(len(CellState), dtype=np.uint8)
    for s, v in PGM_VALUES.items():
        lut[s] = v
    yaml_path, pgm_path = base.with_suffix(".yaml"), base.with_suffix(".pgm")
    Image.fromarray(lut[state], mode="L").save(pgm_path)
    meta = {
        "image": pgm_path.name,
        "mode": "trinary",
        "resolution": float(frame.resolution_m),
        "origin": [float(frame.origin_xy[0]), float(frame.origin_xy[1]), 0.0],
        "negate": 0,
        "occupied_thresh": _OCCUPIED_THRESH,
        "free_thresh": _FREE_THRESH,
    }
    yaml_path.write_text(yaml.safe_dump(meta, sort_keys=False))
    return yaml_path, pgm_path
