"""The learned map predictor without torch: the team's belief pooled onto the predictor's cells, a small
U-Net in NumPy, and its weight file.

The network reads three channels per predictor cell (the share of free, occupied and unknown planning cells
under it) and gives one logit per cell: that the cell is free. Two max-pooling levels and dilated
convolutions at the coarsest one see about 12 m around a cell, which covers the 6 m past a frontier where a
planner's next decisions look. :class:`PredictorUNet` in :mod:`mrexplore.training.predictor` is the same
network in torch (trained there; the names of the weights are shared).
"""

from __future__ import annotations

import functools
import json
import math
import zipfile
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import Any

import numba as nb
import numpy as np
from numpy.typing import NDArray

from mrexplore.prediction.baselines import known_p_free
from mrexplore.types import CellState, MrExploreError, StateGrid
from mrexplore.weights_archive import HEADER_MEMBER, WEIGHT_PREFIX, file_sha256, weights_digest

__all__ = [
    "PREDICTOR_FORMAT",
    "POOL_LEVELS",
    "IN_CHANNELS",
    "LAYERS",
    "DILATION",
    "layer_shapes",
    "pool_factor",
    "belief_channels",
    "UNetNp",
    "MapPredictor",
    "load_predictor",
    "default_predictor_path",
]

PREDICTOR_FORMAT = "mrexplore-predictor-1"
"""Format tag of a predictor file."""
MAX_PREDICTOR_BYTES = 64 << 20
"""Largest predictor file read (the shipped one is 137 kB): a bigger one is refused before it is read."""
POOL_LEVELS = 2
"""Max-pooling levels of the U-Net: the predictor's grid is padded to a multiple of ``2 ** POOL_LEVELS``."""
REACH_M = 8.0
"""The network runs on the box of the known cells grown by this much, metres: farther unknown cells lie
beyond the 6 m band near a frontier that planners read."""
IN_CHANNELS = 3
"""Share of free, occupied and unknown planning cells under each predictor cell."""
LAYERS = ("enc1", "enc2", "mid1", "mid2", "mid3", "dec2", "dec1", "head")
"""The convolutions in order, by the names their weights carry (``enc1.weight``, ``enc1.bias``, ...)."""
DILATION = {"mid2": 2, "mid3": 4}
"""Dilation of the convolutions that have one (the others: 1)."""


def layer_shapes(width: int) -> dict[str, tuple[int, int, int]]:
    """``name -> (out channels, in channels, kernel)`` of every convolution for a finest width ``width``
    (doubled at each pooling level)."""
    w = width
    return {
        "enc1": (w, IN_CHANNELS, 3),
        "enc2": (2 * w, w, 3),
        "mid1": (4 * w, 2 * w, 3),
        "mid2": (4 * w, 4 * w, 3),
        "mid3": (4 * w, 4 * w, 3),
        "dec2": (2 * w, 4 * w + 2 * w, 3),
        "dec1": (w, 2 * w + w, 3),
        "head": (1, w, 1),
    }


def pool_factor(resolution_m: float, cell_m: float) -> int:
    """Planning cells per predictor cell along a side: ``cell_m / resolution_m`` rounded, at least 1.

    Examples
    --------
    >>> pool_factor(0.1, 0.2), pool_factor(0.05, 0.2), pool_factor(0.25, 0.2)
    (2, 4, 1)
    """
    return max(1, round(cell_m / resolution_m))


def belief_channels(state: StateGrid, factor: int) -> NDArray[np.float32]:
    """``(3, h, w) float32``: the share of free, occupied and unknown cells of ``state`` in each
    ``factor x factor`` block; the grid is padded with unknown cells at its bottom and right to a multiple of
    ``factor * 2 ** POOL_LEVELS``.

    Examples
    --------
    >>> F, O, U = CellState.FREE, CellState.OCCUPIED, CellState.UNKNOWN
    >>> x = belief_channels(np.array([[F, O], [F, U]], np.uint8), 2)
    >>> x.shape, x[:, 0, 0].tolist(), x[:, 0, 1].tolist()  # one block of 2 x 2, then padding
    ((3, 4, 4), [0.5, 0.25, 0.25], [0.0, 0.0, 1.0])
    """
    H, W = state.shape
    step = factor * 2**POOL_LEVELS
    Hp, Wp = math.ceil(H / step) * step, math.ceil(W / step) * step
    counts = _block_counts(np.ascontiguousarray(state, np.uint8), factor, Hp // factor, Wp // factor)
    return (counts / float(factor * factor)).astype(np.float32)


_UNKNOWN = int(CellState.UNKNOWN)


@nb.njit(cache=True, nogil=True)
def _block_counts(state: np.ndarray, factor: int, h: int, w: int) -> np.ndarray:  # pragma: no cover - numba
    """``(3, h, w) float64``: free, occupied and unknown cells of each ``factor x factor`` block, the cells
    beyond ``state`` counted unknown, in one pass over the grid."""
    out = np.zeros((3, h, w))
    out[2] = factor * factor
    for r in range(state.shape[0]):
        for c in range(state.shape[1]):
            s = state[r, c]  # the channel is the state's value: free 0, occupied 1, unknown 2
            if s != _UNKNOWN:
                out[s, r // factor, c // factor] += 1.0
                out[2, r // factor, c // factor] -= 1.0
    return out


def _conv(x: NDArray[np.float32], w: NDArray[np.float32], b: NDArray[np.float32], dilation: int) -> np.ndarray:
    """``(O, H, W)``: the same-size convolution of ``x (C, H, W)`` with ``w (O, C, k, k)``, zero padding (as
    torch's ``Conv2d(padding=dilation * (k // 2))``), as one matrix product over the shifted copies."""
    C, H, W = x.shape
    n_out, _, k, _ = w.shape
    p = dilation * (k // 2)
    xp = np.pad(x, ((0, 0), (p, p), (p, p))) if p else x
    cols = np.empty((C, k * k, H, W), np.float32)
    for i in range(k):
        for j in range(k):
            cols[:, i * k + j] = xp[:, i * dilation : i * dilation + H, j * dilation : j * dilation + W]
    out = w.reshape(n_out, C * k * k) @ cols.reshape(C * k * k, H * W)
    out += b[:, None]
    return out.reshape(n_out, H, W)


@functools.cache
def _blas() -> Any:
    """The process's BLAS thread pools (threadpoolctl), looked up once."""
    from threadpoolctl import ThreadpoolController

    return ThreadpoolController()


def _pool(x: np.ndarray) -> np.ndarray:
    C, H, W = x.shape
    return x.reshape(C, H // 2, 2, W // 2, 2).max(axis=(2, 4))


def _up(x: np.ndarray) -> np.ndarray:
    return x.repeat(2, axis=1).repeat(2, axis=2)


class UNetNp:
    """The predictor's U-Net on NumPy arrays (float32), weights by the torch module's names."""

    def __init__(self, width: int, state: dict[str, NDArray[np.float32]]) -> None:
        shapes = layer_shapes(width)
        self.width = width
        self.w: dict[str, NDArray[np.float32]] = {}
        self.b: dict[str, NDArray[np.float32]] = {}
        for name, (o, i, k) in shapes.items():
            w, b = state[f"{name}.weight"], state[f"{name}.bias"]
            if w.shape != (o, i, k, k) or b.shape != (o,):
                raise ValueError(f"{name} has shape {w.shape}, this network {(o, i, k, k)}")
            self.w[name], self.b[name] = np.ascontiguousarray(w, np.float32), np.ascontiguousarray(b, np.float32)
        extra = set(state) - {f"{n}.{p}" for n in shapes for p in ("weight", "bias")}
        if extra:
            raise ValueError(f"weights {sorted(extra)[0]} belong to no layer")

    def _layer(self, name: str, x: np.ndarray, relu: bool = True) -> np.ndarray:
        y = _conv(x, self.w[name], self.b[name], DILATION.get(name, 1))
        return np.maximum(y, 0.0, out=y) if relu else y

    def __call__(self, x: NDArray[np.float32]) -> NDArray[np.float32]:
        """Logits ``(h, w) float32`` that each cell is free, from ``belief_channels``' ``(3, h, w)``."""
        e1 = self._layer("enc1", x)
        e2 = self._layer("enc2", _pool(e1))
        m = self._layer("mid1", _pool(e2))
        m = self._layer("mid2", m)
        m = self._layer("mid3", m)
        d2 = self._layer("dec2", np.concatenate([_up(m), e2]))
        d1 = self._layer("dec1", np.concatenate([_up(d2), e1]))
        return self._layer("head", d1, relu=False)[0]


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
        >>> F, U = CellState.FREE, CellState.UNKNOWN
        >>> net = UNetNp(1, {f"{n}.{p}": np.zeros(s[:2] + (s[2], s[2]) if p == "weight" else s[:1], np.float32)
        ...                  for n, s in layer_shapes(1).items() for p in ("weight", "bias")})
        >>> pred = MapPredictor(net, 0.2, Path("zero.npz"), "", {})  # every logit 0: p = 0.5 where unknown
        >>> pred.p_free(np.array([[F, U, U]], np.uint8), 0.1).tolist()
        [[1.0, 0.5, 0.5]]
        """
        H, W = state.shape
        factor = pool_factor(resolution_m, self.cell_m)
        out = known_p_free(state)
        unknown = np.isnan(out)
        out[unknown] = 1.0
        rows, cols = np.nonzero(~unknown.all(axis=1))[0], np.nonzero(~unknown.all(axis=0))[0]
        if not len(rows):
            return out
        step = factor * 2**POOL_LEVELS
        reach = round(REACH_M / resolution_m)
        r0, c0 = max(0, rows[0] - reach) // step * step, max(0, cols[0] - reach) // step * step
        r1, c1 = min(H, rows[-1] + 1 + reach), min(W, cols[-1] + 1 + reach)
        box = state[r0:r1, c0:c1]
        # One BLAS thread: the products are small, and a threaded BLAS on cores that other work holds (a
        # bench's workers, the decision's own threads) took ten times as long (16 ms -> 157 ms on 2 cores).
        with _blas().limit(limits=1, user_api="blas"):
            logits = self.net(belief_channels(box, factor))
        p = (1.0 / (1.0 + np.exp(-np.clip(logits, -30.0, 30.0)))).astype(np.float32)
        full = p.repeat(factor, axis=0).repeat(factor, axis=1)[: r1 - r0, : c1 - c0]
        sub = out[r0:r1, c0:c1]
        sub[unknown[r0:r1, c0:c1]] = full[unknown[r0:r1, c0:c1]]
        return out

    def describe(self) -> dict[str, str]:
        """What a mission's record says of the predictor: its path and sha256."""
        return {"path": str(self.path), "sha256": self.sha256}


def default_predictor_path() -> Path:
    """The predictor shipped inside the package."""
    return Path(str(resources.files("mrexplore.prediction") / "pretrained" / "predictor.npz"))


def _not_predictor(path: Path, why: str) -> MrExploreError:
    return MrExploreError(f"predictor file {path} is not a mrexplore map predictor ({why}); retrain it")


def load_predictor(path: Path | str | None = None) -> MapPredictor:
    """A predictor file written by ``mrexplore train --predictor`` (None: the shipped one); one-line errors
    for every way it can be wrong."""
    path = Path(path) if path is not None else default_predictor_path()
    if not path.is_file():
        raise MrExploreError(
            f"predictor file {path} not found; pass a file written by 'mrexplore train --predictor' with --predictor"
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
