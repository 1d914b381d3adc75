"""Resampling an obstacle image to the working resolution by min-pooling (any obstacle pixel wins)."""

from __future__ import annotations

import numpy as np

from mrexplore.types import BoolGrid

__all__ = ["resample_obstacles"]


def _block_starts(n_src: int, factor: float) -> tuple[np.ndarray, int]:
    n_dst = max(1, round(n_src / factor))
    starts = np.floor(np.arange(n_dst) * factor + 1e-9).astype(np.int64)
    return np.clip(starts, 0, n_src - 1), n_dst


def resample_obstacles(obstacle: BoolGrid, pixel_size_m: float, resolution_m: float) -> BoolGrid:
    """Resample a ``(H, W) bool`` obstacle image from ``pixel_size_m`` to ``resolution_m`` per cell.

    Downsampling marks a cell occupied if **any** source pixel in it is (min-pooling of free space), so
    one-pixel walls survive; upsampling takes the pixel each cell falls in.

    Examples
    --------
    >>> img = np.zeros((4, 4), bool); img[0, 3] = True
    >>> resample_obstacles(img, 0.01, 0.02).astype(int).tolist()
    [[0, 1], [0, 0]]
    """
    factor = resolution_m / pixel_size_m
    if abs(factor - 1.0) < 1e-9:
        return obstacle.copy()
    rows, _ = _block_starts(obstacle.shape[0], factor)
    cols, _ = _block_starts(obstacle.shape[1], factor)
    # reduceat over block starts: a max over each block when blocks span pixels (downsampling), the
    # pixel at the start when consecutive starts repeat (upsampling).
    out = np.maximum.reduceat(obstacle.astype(np.uint8), rows, axis=0)
    out = np.maximum.reduceat(out, cols, axis=1)
    return out.astype(bool)
