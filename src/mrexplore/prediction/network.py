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
import threading
import zipfile
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import Any

import numba as nb
import numpy as np
from numpy.typing import NDArray

from mrexplore.runtime.weights_archive import HEADER_MEMBER, WEIGHT_PREFIX, file_sha256, weights_digest
from mrexplore.types import CellState, MrExploreError, StateGrid

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
_OCCUPIED = int(CellState.OCCUPIED)


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


SHIFTED_FROM_CHANNELS = 16
"""Inputs of at least this many channels are convolved by shifted products (:func:`_conv_shifted`), thinner
ones by a product over their stacked shifted copies (:func:`_conv_stacked`), whichever was faster on one core."""


class _Scratch(threading.local):
    """The forward pass's arrays, one per role, kept from one call to the next in each thread.

    Fresh arrays of megabytes cost their pages' first touch on every call: with them the forward pass took
    twice as long. An array grows when a larger grid needs it, so what is kept is the largest grid's.
    """

    def __init__(self) -> None:
        self.arrays: dict[str, NDArray[np.float32]] = {}

    def take(self, role: str, shape: tuple[int, ...]) -> NDArray[np.float32]:
        """A float32 array of ``shape`` for ``role``, its contents left from before (the caller fills it)."""
        n = math.prod(shape)
        a = self.arrays.get(role)
        if a is None or a.size < n:
            a = self.arrays[role] = np.empty(n + n // 4, np.float32)  # room for a grid that grows a little
        return a[:n].reshape(shape)


def _padded(x: np.ndarray, p: int, spare_rows: int, scratch: _Scratch, role: str) -> NDArray[np.float32]:
    """``x (C, H, W)`` with ``p`` zeros around it and ``spare_rows`` more zero rows at the bottom."""
    C, H, W = x.shape
    xp = scratch.take(role, (C, H + 2 * p + spare_rows, W + 2 * p))
    xp[:, :p] = 0.0
    xp[:, p + H :] = 0.0
    xp[:, p : p + H, :p] = 0.0
    xp[:, p : p + H, p + W :] = 0.0
    xp[:, p : p + H, p : p + W] = x
    return xp


@nb.njit(cache=True, nogil=True)
def _known_box(state: np.ndarray) -> tuple[int, int, int, int]:  # pragma: no cover - numba
    """First and last row, first and last column holding a known cell (``(H, -1, W, -1)`` when none does)."""
    H, W = state.shape
    rmin, rmax, cmin, cmax = H, -1, W, -1
    for r in range(H):
        for c in range(W):
            if state[r, c] != _UNKNOWN:
                rmin, rmax = min(rmin, r), max(rmax, r)
                cmin, cmax = min(cmin, c), max(cmax, c)
    return rmin, rmax, cmin, cmax


@nb.njit(cache=True, nogil=True)
def _fill_p_free(
    state: np.ndarray, p: np.ndarray, factor: int, r0: int, c0: int, r1: int, c1: int
) -> np.ndarray:  # pragma: no cover - numba
    """``(H, W) float32``: 1 on free cells, 0 on occupied ones, on unknown cells inside rows ``r0:r1`` and
    columns ``c0:c1`` the probability ``p`` of the predictor cell over them (``p[0, 0]`` over ``(r0, c0)``),
    1 on unknown cells outside."""
    H, W = state.shape
    out = np.empty((H, W), np.float32)
    for r in range(H):  # known cells, and unknown ones outside the box (1)
        for c in range(W):
            out[r, c] = 0.0 if state[r, c] == _OCCUPIED else 1.0
    row = np.empty(c1 - c0, np.float32)
    for r in range(r0, r1):
        if (r - r0) % factor == 0:  # the box's row of p, each cell repeated ``factor`` times
            pr = (r - r0) // factor
            for c in range(c1 - c0):
                row[c] = p[pr, c // factor]
        srow, orow = state[r, c0:c1], out[r, c0:c1]
        for c in range(c1 - c0):
            if srow[c] == _UNKNOWN:
                orow[c] = row[c]
    return out


def _conv(
    x: NDArray[np.float32],
    w: NDArray[np.float32],
    b: NDArray[np.float32],
    dilation: int,
    scratch: _Scratch | None = None,
    role: str = "conv",
) -> NDArray[np.float32]:
    """``(O, H, W)``: the same-size convolution of ``x (C, H, W)`` with ``w (O, C, k, k)``, zero padding (as
    torch's ``Conv2d(padding=dilation * (k // 2))``). The result lives in ``scratch`` under ``role`` (a fresh
    scratch when none is given): the next call with the same role overwrites it.

    Examples
    --------
    >>> x = np.arange(9, dtype=np.float32).reshape(1, 3, 3)
    >>> _conv(x, np.ones((1, 1, 3, 3), np.float32), np.zeros(1, np.float32), 1)[0].tolist()  # 3 x 3 box sums
    [[8.0, 15.0, 12.0], [21.0, 36.0, 27.0], [20.0, 33.0, 24.0]]
    """
    scratch = scratch if scratch is not None else _Scratch()
    C, H, W = x.shape
    n_out, _, k, _ = w.shape
    if k == 1:
        out = scratch.take(role + ".out", (n_out, H * W))
        np.matmul(w.reshape(n_out, C), x.reshape(C, H * W), out=out)
        out += b[:, None]
        return out.reshape(n_out, H, W)
    if C >= SHIFTED_FROM_CHANNELS:
        return _conv_shifted(x, w, b, dilation, scratch, role)
    return _conv_stacked(x, w, b, dilation, scratch, role)


def _conv_stacked(
    x: NDArray[np.float32], w: NDArray[np.float32], b: NDArray[np.float32], dilation: int, scratch: _Scratch, role: str
) -> NDArray[np.float32]:
    """:func:`_conv` as one matrix product over the input's ``k * k`` shifted copies, stacked."""
    C, H, W = x.shape
    n_out, _, k, _ = w.shape
    xp = _padded(x, dilation * (k // 2), 0, scratch, role + ".in")
    cols = scratch.take(role + ".cols", (C, k * k, H, W))
    for i in range(k):
        for j in range(k):
            cols[:, i * k + j] = xp[:, i * dilation : i * dilation + H, j * dilation : j * dilation + W]
    out = scratch.take(role + ".out", (n_out, H * W))
    np.matmul(w.reshape(n_out, C * k * k), cols.reshape(C * k * k, H * W), out=out)
    out += b[:, None]
    return out.reshape(n_out, H, W)


def _conv_shifted(
    x: NDArray[np.float32], w: NDArray[np.float32], b: NDArray[np.float32], dilation: int, scratch: _Scratch, role: str
) -> NDArray[np.float32]:
    """:func:`_conv` with no copy of the input per tap: one product of every tap's weights with the zero-padded
    input laid out row after row, then each tap's output shifted into place and summed (a tap's window of the
    padded input is one contiguous run of it). The sum runs across the padded width; the padding columns are
    dropped at the end."""
    C, H, W = x.shape
    n_out, _, k, _ = w.shape
    p = dilation * (k // 2)
    Wp = W + 2 * p
    xp = _padded(x, p, 1, scratch, role + ".in")  # the spare row: the last tap's run ends past the grid
    flat = xp.reshape(C, -1)
    prod = scratch.take(role + ".prod", (k * k * n_out, flat.shape[1]))
    np.matmul(w.transpose(2, 3, 0, 1).reshape(k * k * n_out, C), flat, out=prod)
    n = H * Wp
    acc = scratch.take(role + ".acc", (n_out, n))
    np.copyto(acc, prod[:n_out, :n])
    for t in range(1, k * k):
        at = (t // k) * dilation * Wp + (t % k) * dilation
        acc += prod[t * n_out : (t + 1) * n_out, at : at + n]
    out = scratch.take(role + ".out", (n_out, H, W))
    np.copyto(out, acc.reshape(n_out, H, Wp)[:, :, :W])
    out += b[:, None, None]
    return out


@functools.cache
def _blas() -> Any:
    """The process's BLAS thread pools (threadpoolctl), looked up once."""
    from threadpoolctl import ThreadpoolController

    return ThreadpoolController()


def _pool(x: np.ndarray, scratch: _Scratch, role: str) -> NDArray[np.float32]:
    """2 x 2 max pooling of ``(C, H, W)`` (``H`` and ``W`` even), as the maximum of the four strided views."""
    C, H, W = x.shape
    out = scratch.take(role, (C, H // 2, W // 2))
    np.maximum(x[:, ::2, ::2], x[:, ::2, 1::2], out=out)
    np.maximum(out, x[:, 1::2, ::2], out=out)
    np.maximum(out, x[:, 1::2, 1::2], out=out)
    return out


def phase_weights(w_up: NDArray[np.float32]) -> NDArray[np.float32]:
    """``(16 * O, C)``: a 3 x 3 convolution ``w_up (O, C, 3, 3)`` of a grid upsampled 2x by repeating each
    cell, as four 2 x 2 convolutions of the grid itself, one per parity of the output's row and column.

    A fine row ``2r + a`` reads, through its three taps, coarse rows ``r + (a + i - 1) // 2`` for tap
    ``i``: two of the taps read the same coarse row, so their weights add. Row ``((a * 2 + b) * 2 + u) * 2 +
    v`` (times ``O``, plus the output channel) holds the weights of phase ``(a, b)`` on coarse offset
    ``(u - 1 + a, v - 1 + b)``.
    """
    n_out, n_in = w_up.shape[:2]
    k = np.zeros((2, 2, 2, 2, n_out, n_in), np.float32)
    for a in range(2):
        for i in range(3):
            u = (a + i - 1) // 2 - a + 1
            for b in range(2):
                for j in range(3):
                    k[a, b, u, (b + j - 1) // 2 - b + 1] += w_up[:, :, i, j]
    return k.reshape(16 * n_out, n_in)


def _conv_up_and_skip(
    coarse: np.ndarray,
    skip: np.ndarray,
    w_phase: NDArray[np.float32],
    w_skip: NDArray[np.float32],
    b: NDArray[np.float32],
    scratch: _Scratch,
    role: str,
) -> NDArray[np.float32]:
    """``(O, H, W)``: the 3 x 3 convolution of ``coarse (Cu, H/2, W/2)`` upsampled 2x by repeating each cell,
    stacked on ``skip (Cs, H, W)``, with zero padding, without building the upsampled grid: the coarse part
    runs on the coarse grid by :func:`phase_weights` (4 taps per output cell instead of 9), in the manner of
    :func:`_conv_shifted`."""
    Cu, Hc, Wc = coarse.shape
    n_out = w_skip.shape[0]
    out = _conv(skip, w_skip, b, 1, scratch, role + ".skip")
    Wp = Wc + 2
    xp = _padded(coarse, 1, 1, scratch, role + ".in")
    flat = xp.reshape(Cu, -1)
    prod = scratch.take(role + ".prod", (16 * n_out, flat.shape[1]))
    np.matmul(w_phase, flat, out=prod)
    n = Hc * Wp
    acc = scratch.take(role + ".acc", (n_out, n))
    for a in range(2):
        for b_ in range(2):
            t = (a * 2 + b_) * 4
            np.copyto(acc, prod[t * n_out : (t + 1) * n_out, a * Wp + b_ : a * Wp + b_ + n])
            for u, v in ((0, 1), (1, 0), (1, 1)):
                at = (u + a) * Wp + v + b_
                acc += prod[(t + u * 2 + v) * n_out : (t + u * 2 + v + 1) * n_out, at : at + n]
            out[:, a::2, b_::2] += acc.reshape(n_out, Hc, Wp)[:, :, :Wc]
    return out


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
        self._scratch = _Scratch()
        self._split = {  # the decoders' weights on the upsampled input (by phase) and on the skip input
            name: (phase_weights(self.w[name][:, : 2 * n_in]), np.ascontiguousarray(self.w[name][:, 2 * n_in :]))
            for name, n_in in (("dec2", 2 * width), ("dec1", width))
        }

    def _layer(self, name: str, x: np.ndarray, relu: bool = True) -> NDArray[np.float32]:
        y = _conv(x, self.w[name], self.b[name], DILATION.get(name, 1), self._scratch, name)
        return np.maximum(y, 0.0, out=y) if relu else y

    def _up_layer(self, name: str, coarse: np.ndarray, skip: np.ndarray) -> NDArray[np.float32]:
        """The decoder's convolution of ``coarse`` upsampled, stacked on ``skip``, then ReLU."""
        w_phase, w_skip = self._split[name]
        y = _conv_up_and_skip(coarse, skip, w_phase, w_skip, self.b[name], self._scratch, name)
        return np.maximum(y, 0.0, out=y)

    def __call__(self, x: NDArray[np.float32]) -> NDArray[np.float32]:
        """Logits ``(h, w) float32`` that each cell is free, from ``belief_channels``' ``(3, h, w)``."""
        s = self._scratch
        e1 = self._layer("enc1", x)
        e2 = self._layer("enc2", _pool(e1, s, "pool1"))
        m = self._layer("mid1", _pool(e2, s, "pool2"))
        m = self._layer("mid2", m)
        m = self._layer("mid3", m)
        d2 = self._up_layer("dec2", m, e2)
        d1 = self._up_layer("dec1", d2, e1)
        return self._layer("head", d1, relu=False)[0].copy()


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
        state = np.ascontiguousarray(state, np.uint8)
        rmin, rmax, cmin, cmax = _known_box(state)
        if rmin > rmax:  # nothing known: no box to run the network on, every cell unknown and far
            return np.ones(state.shape, np.float32)
        step = factor * 2**POOL_LEVELS
        reach = round(REACH_M / resolution_m)
        r0, c0 = max(0, rmin - reach) // step * step, max(0, cmin - reach) // step * step
        r1, c1 = min(H, rmax + 1 + reach), min(W, cmax + 1 + reach)
        # One BLAS thread: the products are small, and a threaded BLAS on cores that other work holds (a
        # bench's workers, the decision's own threads) took ten times as long (16 ms -> 157 ms on 2 cores).
        with _blas().limit(limits=1, user_api="blas"):
            logits = self.net(belief_channels(state[r0:r1, c0:c1], factor))
        p = (1.0 / (1.0 + np.exp(-np.clip(logits, -30.0, 30.0)))).astype(np.float32)
        return _fill_p_free(state, p, factor, r0, c0, r1, c1)

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
