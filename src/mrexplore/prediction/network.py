"""The learned map predictor without torch: its NumPy U-Net (:mod:`~mrexplore.prediction.unet`) on the team's
belief pooled onto the predictor's cells (:mod:`~mrexplore.prediction.encoding`), the prediction completed
back onto the planning grid, and its weight file.

The network reads three channels per predictor cell (the share of free, occupied and unknown planning cells
under it) and gives one logit per cell: that the cell is free. Two max-pooling levels and dilated
convolutions at the coarsest one see about 12 m around a cell, which covers the 6 m past a frontier where a
planner's next decisions look.
"""

from __future__ import annotations

import json
import zipfile
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mrexplore.prediction.encoding import POOL_LEVELS, belief_channels, fill_p_free, known_box, pool_factor
from mrexplore.prediction.unet import UNetNp, blas
from mrexplore.runtime.weights_archive import HEADER_MEMBER, WEIGHT_PREFIX, file_sha256, weights_digest
from mrexplore.types import MrExploreError, StateGrid

__all__ = ["PREDICTOR_FORMAT", "REACH_M", "MapPredictor", "load_predictor", "default_predictor_path"]

PREDICTOR_FORMAT = "mrexplore-predictor-1"
"""Format tag of a predictor file."""
MAX_PREDICTOR_BYTES = 64 << 20
"""Largest predictor file read (the shipped one is 137 kB): a bigger one is refused before it is read."""
REACH_M = 8.0
"""The network runs on the box of the known cells grown by this much, metres: farther unknown cells lie
beyond the 6 m band near a frontier that planners read."""


@dataclass(frozen=True)
class MapPredictor:
    """A loaded predictor: its network, the size of its cells, and where it came from."""

    net: UNetNp
    cell_m: float
    path: Path
    sha256: str
    meta: dict[str, Any]

    def p_free(self, state: StateGrid, resolution_m: float) -> NDArray[np.float32]:
        """``(H, W) float32`` the probability that each cell of ``state`` is free: 1 on known free cells,
        0 on known occupied ones, the network's on unknown ones within :data:`REACH_M` of a known cell, 1
        farther out (no planner looks there; the network runs on the known cells' box alone).

        Examples
        --------
        >>> import numpy as np
        >>> from mrexplore.prediction.unet import layer_shapes
        >>> from mrexplore.types import CellState
        >>> F, U = CellState.FREE, CellState.UNKNOWN
        >>> net = UNetNp(1, {f"{n}.{p}": np.zeros(s[:2] + (s[2], s[2]) if p == "weight" else s[:1], np.float32)
        ...                  for n, s in layer_shapes(1).items() for p in ("weight", "bias")})
        >>> pred = MapPredictor(net, 0.2, Path("zero.npz"), "", {})  # every logit 0: p = 0.5 where unknown
        >>> pred.p_free(np.array([[F, U, U]], np.uint8), 0.1).tolist()
        [[1.0, 0.5, 0.5]]
        """
        H, W = state.shape
        factor = pool_factor(resolution_m, self.cell_m)
        state = np.ascontiguousarray(state, np.uint8)
        rmin, rmax, cmin, cmax = known_box(state)
        if rmin > rmax:  # nothing known: no box to run the network on, every cell unknown and far
            return np.ones(state.shape, np.float32)
        step = factor * 2**POOL_LEVELS
        reach = round(REACH_M / resolution_m)
        r0, c0 = max(0, rmin - reach) // step * step, max(0, cmin - reach) // step * step
        r1, c1 = min(H, rmax + 1 + reach), min(W, cmax + 1 + reach)
        # One BLAS thread: the products are small, and a threaded BLAS on cores that other work holds (a
        # bench's workers, the decision's own threads) took ten times as long (16 ms -> 157 ms on 2 cores).
        with blas().limit(limits=1, user_api="blas"):
            logits = self.net(belief_channels(state[r0:r1, c0:c1], factor))
        p = (1.0 / (1.0 + np.exp(-np.clip(logits, -30.0, 30.0)))).astype(np.float32)
        return fill_p_free(state, p, factor, r0, c0, r1, c1)

    def describe(self) -> dict[str, str]:
        """What a mission's record says of the predictor: its path and sha256."""
        return {"path": str(self.path), "sha256": self.sha256}


def default_predictor_path() -> Path:
    """The predictor shipped inside the package."""
    return Path(str(resources.files("mrexplore.prediction") / "pretrained" / "predictor.npz"))


def _not_predictor(path: Path, why: str) -> MrExploreError:
    return MrExploreError(f"predictor file {path} is not a mrexplore map predictor ({why}); retrain it")


def load_predictor(path: Path | str | None = None) -> MapPredictor:
    """A predictor file written by ``mrexplore train --target predictor`` (None: the shipped one); one-line errors
    for every way it can be wrong."""
    path = Path(path) if path is not None else default_predictor_path()
    if not path.is_file():
        raise MrExploreError(
            f"predictor file {path} not found; pass a file written by 'mrexplore train --target predictor' "
            "with --predictor"
        )
    if path.stat().st_size > MAX_PREDICTOR_BYTES:
        raise _not_predictor(path, f"{path.stat().st_size} bytes, over the {MAX_PREDICTOR_BYTES}-byte limit")
    try:
        with zipfile.ZipFile(path) as z:
            unpacked = sum(info.file_size for info in z.infolist())
        if unpacked > MAX_PREDICTOR_BYTES:
            raise _not_predictor(path, f"it unpacks to {unpacked} bytes, over the {MAX_PREDICTOR_BYTES}-byte limit")
        with np.load(path, allow_pickle=False) as z:
            header = json.loads(bytes(z[HEADER_MEMBER]).decode()) if HEADER_MEMBER in z.files else None
            state = {
                k[len(WEIGHT_PREFIX) :]: np.asarray(z[k], np.float32) for k in z.files if k.startswith(WEIGHT_PREFIX)
            }
    except (ValueError, OSError, UnicodeDecodeError, zipfile.BadZipFile, EOFError) as exc:
        raise _not_predictor(path, type(exc).__name__) from None
    if header is None:
        raise _not_predictor(path, "no header")
    if not isinstance(header, dict) or header.get("format") != PREDICTOR_FORMAT:
        raise _not_predictor(path, "no predictor format tag")
    if header.get("weights_sha256") != weights_digest(state):
        raise MrExploreError(
            f"predictor file {path} is corrupted: its weights do not match the digest saved with them; retrain it"
        )
    try:
        width, cell_m = int(header["width"]), float(header["cell_m"])
        if not (0 < width <= 256 and 0 < cell_m <= 10):
            raise ValueError(f"width {width} or cell {cell_m} m out of range")
        net = UNetNp(width, state)
    except (KeyError, TypeError, ValueError) as exc:
        first = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise MrExploreError(f"predictor file {path} does not fit this network ({first}); retrain it") from None
    meta = {k: header.get(k) for k in ("code_version", "meta")}
    return MapPredictor(net, cell_m, path, file_sha256(path), meta)
