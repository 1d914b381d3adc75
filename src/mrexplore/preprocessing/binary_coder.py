"""Adaptive binary arithmetic coding (numba): the entropy coder under the frontier message's context model.

A carry-less binary arithmetic coder with 32-bit bounds and 16-bit probabilities, the design of Mahoney's
lpaq1 coder, with a one-byte flush that lands the decoder inside the final interval. Each context keeps two
counts in half units; the probability of a 1 is ``(n1 + 1) / (n0 + n1 + 2)`` (a Krichevsky-Trofimov estimate
started from the counts of a prior table), both counts halved past a limit so that a context follows the
message it codes. Integer arithmetic only: encoder and decoder compute the same probabilities on any CPU.

The state of a coder is a small ``int64`` array (``_STATE`` fields) and a byte buffer, so that the functions
inline into the caller's numba loop.
"""

from __future__ import annotations

import numba as nb
import numpy as np

__all__ = [
    "new_encoder",
    "new_decoder",
    "encode_bit",
    "decode_bit",
    "finish",
    "bytes_read",
    "COUNT_LIMIT",
    "PROB_ONE",
]

PROB_ONE = 1 << 16
"""Probabilities are integers in 1..``PROB_ONE - 1``."""
COUNT_LIMIT = 2048
"""Half-unit count total past which a context's two counts are halved (1024 decisions of memory)."""
_MASK = 0xFFFFFFFF
# State fields: low bound, high bound, bytes written (encoder) or the decoder's window, next byte to read.
_X1, _X2, _POS, _X = 0, 1, 2, 3


@nb.njit(cache=True, inline="always")
def probability(n0: int, n1: int) -> int:  # pragma: no cover - numba
    """Probability of a 1 in 1/65536 from a context's half-unit counts."""
    p = ((n1 + 1) * PROB_ONE) // (n0 + n1 + 2)
    return min(max(p, 1), PROB_ONE - 1)


@nb.njit(cache=True, inline="always")
def update(counts: np.ndarray, ctx: int, bit: int) -> None:  # pragma: no cover - numba
    """Count ``bit`` in context ``ctx`` (``counts``: ``(n_contexts, 2) int32`` half units)."""
    counts[ctx, bit] += 2
    if counts[ctx, 0] + counts[ctx, 1] > COUNT_LIMIT:
        counts[ctx, 0] //= 2
        counts[ctx, 1] //= 2


@nb.njit(cache=True)
def new_encoder() -> np.ndarray:  # pragma: no cover - numba
    state = np.zeros(4, dtype=np.int64)
    state[_X2] = _MASK
    return state


@nb.njit(cache=True, inline="always")
def _split(state: np.ndarray, p: int) -> int:  # pragma: no cover - numba
    span = state[_X2] - state[_X1]
    return state[_X1] + (span >> 16) * p + (((span & 0xFFFF) * p) >> 16)


@nb.njit(cache=True, inline="always")
def _settled(state: np.ndarray) -> bool:  # pragma: no cover - numba
    """Whether both bounds share their top byte."""
    return ((state[_X1] ^ state[_X2]) & 0xFF000000) == 0


@nb.njit(cache=True, inline="always")
def _shift_bounds(state: np.ndarray) -> None:  # pragma: no cover - numba
    state[_X1] = (state[_X1] << 8) & _MASK
    state[_X2] = ((state[_X2] << 8) & _MASK) | 0xFF


@nb.njit(cache=True, inline="always")
def encode_bit(
    state: np.ndarray, out: np.ndarray, counts: np.ndarray, ctx: int, bit: int
) -> None:  # pragma: no cover - numba
    """Code ``bit`` in context ``ctx`` into ``out`` (grown by the caller: at most 4 bytes a bit)."""
    mid = _split(state, probability(counts[ctx, 0], counts[ctx, 1]))
    if bit:
        state[_X2] = mid
    else:
        state[_X1] = mid + 1
    update(counts, ctx, bit)
    while _settled(state):  # the top byte is decided: out with it
        out[state[_POS]] = state[_X2] >> 24
        state[_POS] += 1
        _shift_bounds(state)


@nb.njit(cache=True)
def finish(state: np.ndarray, out: np.ndarray, coded_any: bool) -> int:  # pragma: no cover - numba
    """Flush and return the stream's length. One byte, ``(x1 >> 24) + 1``, followed by the zeros the decoder
    reads past the end, lies inside the final interval (the bounds differ in their top byte); a stream
    that coded nothing is empty."""
    if not coded_any:
        return 0
    out[state[_POS]] = (state[_X1] >> 24) + 1
    return int(state[_POS]) + 1


@nb.njit(cache=True)
def new_decoder(data: np.ndarray) -> np.ndarray:  # pragma: no cover - numba
    state = np.zeros(4, dtype=np.int64)
    state[_X2] = _MASK
    x = 0
    for k in range(4):
        x = (x << 8) | (int(data[k]) if k < len(data) else 0)
    state[_X] = x
    state[_POS] = 4
    return state


@nb.njit(cache=True, inline="always")
def decode_bit(state: np.ndarray, data: np.ndarray, counts: np.ndarray, ctx: int) -> int:  # pragma: no cover
    """The next bit, in context ``ctx``; past the end the stream reads as zeros."""
    mid = _split(state, probability(counts[ctx, 0], counts[ctx, 1]))
    bit = 1 if state[_X] <= mid else 0
    if bit:
        state[_X2] = mid
    else:
        state[_X1] = mid + 1
    update(counts, ctx, bit)
    while _settled(state):  # the encoder wrote this top byte: shift the next one in
        _shift_bounds(state)
        pos = state[_POS]
        state[_X] = ((state[_X] << 8) & _MASK) | (int(data[pos]) if pos < len(data) else 0)
        state[_POS] = pos + 1
    return bit


@nb.njit(cache=True, inline="always")
def bytes_read(state: np.ndarray) -> int:  # pragma: no cover - numba
    """Bytes the decoder shifted in beyond its first four: the encoder wrote as many before its flush."""
    return int(state[_POS]) - 4
