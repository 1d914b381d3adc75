"""The map predictor's U-Net in NumPy: two max-pooling levels and dilated convolutions at the coarsest one,
run without per-call allocations (its arrays kept per thread), wide layers convolved by shifted products, the
decoder's convolutions of upsampled grids run on the coarse grid by phase. :class:`PredictorUNet` in
:mod:`mrexplore.training.predictor_net` is the same network in torch (the weights' names are shared)."""

from __future__ import annotations

import functools
import math
import threading
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mrexplore.prediction.encoding import IN_CHANNELS

__all__ = ["LAYERS", "DILATION", "layer_shapes", "phase_weights", "UNetNp", "blas"]

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
def blas() -> Any:
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
