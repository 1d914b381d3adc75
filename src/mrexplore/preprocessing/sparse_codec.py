"""Binary wire format of a :class:`~mrexplore.preprocessing.sparse_map.SparseFrontierMap` (encode / decode).

A message codes the robot's *code grid* (each boundary cell's neighbour code, 0 elsewhere) inside the box
of the cells it lists, cell by cell in row-major order, with a context-modelled binary arithmetic coder
(:mod:`~mrexplore.preprocessing.binary_coder`), in the manner of JBIG2's refinement coding. A whole map is
coded against an empty grid; a delta against the code grid the centre acknowledged (its *base*), which
both ends hold. Each cell is one decision "boundary or not"; a boundary cell then gives, for each of its
4 neighbours, "free or not" and "occupied or unknown". The contexts are what the decoder already knows
there: the cell's base code, the neighbours decoded so far, and what their codes say of the cell and of
its neighbours (a boundary cell's code states each neighbour's state, so most of a frontier's codes
follow from the cells before it). Stretches of cells that nothing decoded or acknowledged borders are
coded as runs (as in JPEG-LS), so that the coding's work follows the boundary more than the box's area.
Each context starts from a prior learned on training maps (``codec_prior.npy``, made by
``benchmarks/codec_prior.py``) and adapts to the message.

Layout::

    magic    1 byte   b"M"
    format   1 byte   version << 1 | kind (0 whole map, 1 delta)
    varints  robot, round; a delta: round - base round (>= 1); a whole map: height, width;
             box: first row, first column, rows, columns (rows = columns = 0: empty);
             position: zigzag(row - first row), zigzag(column - first column);
             seeds: count, then zigzag(first seed - the position's index), then the gaps between seeds
    stream   the arithmetic-coded box (empty where the box is)
    crc32    u32 little-endian, zlib.crc32 of every byte before it

Varints are LEB128 (7 bits per byte), zigzag maps signed to unsigned. Decoding checks every field before
use, and the coder's stream must end where the decoder's last decision ends, so garbage, truncated or
foreign bytes raise one :class:`CodecError`. A delta decodes only against its base
(:func:`decode` ``base=``); :func:`peek` reads the fields that say which base that is.
"""

from __future__ import annotations

import hashlib
import io
import struct
import zlib
from dataclasses import dataclass
from importlib.resources import files

import numba as nb
import numpy as np
from numpy.typing import NDArray

from mrexplore.preprocessing.binary_coder import (
    bytes_read,
    decode_bit,
    encode_bit,
    finish,
    new_decoder,
    new_encoder,
)
from mrexplore.preprocessing.sparse_map import FULL, SparseFrontierMap
from mrexplore.types import MrExploreError

__all__ = [
    "encode",
    "decode",
    "peek",
    "MessageHead",
    "CodecError",
    "BASELINE_HEADER_BYTES",
    "VERSION",
    "MAX_CELLS",
    "MAX_ROUND",
    "MAX_ROBOT",
    "N_CONTEXTS",
    "PRIOR_SHA256",
    "context_counts",
    "prior",
    "prior_sha256",
]

MAGIC = 0x4D  # "M"
VERSION = 2
MAX_CELLS = 1 << 28
"""Largest grid (cells) a message may refer to: 268 M cells, 26 km² at 0.1 m."""
MAX_ROUND = (1 << 31) - 1
"""Largest round number."""
MAX_ROBOT = (1 << 16) - 1
"""Largest robot id."""
BASELINE_HEADER_BYTES = 10
"""Header charged to Table II's int8-grid baselines: the fields every message needs (magic and format,
robot, round and base round as varints of typical size: 1 + 1 + 1 + 2 + 1) and the checksum (4)."""
_KIND_FULL, _KIND_DELTA = 0, 1
_CRC = struct.Struct("<I")
_MAX_VARINT_BYTES = 9  # 63 bits
_FIX = "drop it and ask the robot for a full map"
_PAD = 2  # the contexts read up to two cells beyond the coded cell
_OUTSIDE = -1  # a cell beyond the grid
_UNSEEN = -2  # a cell of the box the decoder has not reached

# Contexts: the boundary decision (state the decoded neighbours give the cell, 6; base boundary; boundary
# up, left, up-right, up-left; base boundary right, down), then per direction "free or not" and "occupied
# or unknown" (direction, 4; state decoded for that neighbour, 6; the base code's, the left cell's and the
# upper cell's state in that direction, 4 each; whether the code may still be all free, 2).
_BD = 6 * 2 * 2**6
_DIR = 4 * 6 * 4 * 4 * 4 * 2
# Run mode: whether a stretch is empty (by the bit length of the stretch), then the Exp-Golomb code of the
# first boundary cell's place (unary prefix bits, then the bits below the top, by position).
_RUN = _BD + 2 * _DIR
_RUN_PRE = _RUN + 16
_RUN_SUF = _RUN_PRE + 16
N_CONTEXTS = _RUN_SUF + 16
"""Contexts of the model (rows of the prior table)."""
PRIOR_SHA256 = "2b3ac5731beff0920a83b90efdcde75c3e1d47d212e54c0941190c3ee0c645b3"
"""Digest of the shipped prior table: a changed table is a new wire format (bump :data:`VERSION`)."""
_DR = np.array([-1, 1, 0, 0], dtype=np.int64)
_DC = np.array([0, 0, -1, 1], dtype=np.int64)


class CodecError(MrExploreError):
    """Bytes that are not a valid frontier message."""


def _fail(problem: str) -> CodecError:
    return CodecError(f"bad frontier message: {problem}; {_FIX}")


_prior_table: NDArray[np.uint8] | None = None


def prior() -> NDArray[np.uint8]:
    """``(N_CONTEXTS, 2) uint8`` the shipped prior: each context's starting counts of 0s and 1s, in half
    units (read once)."""
    global _prior_table
    if _prior_table is None:
        raw = files("mrexplore.preprocessing").joinpath("codec_prior.npy").read_bytes()
        table = np.load(io.BytesIO(raw), allow_pickle=False)
        if table.shape != (N_CONTEXTS, 2) or table.dtype != np.uint8:
            raise MrExploreError(
                f"the codec's prior table is {table.shape} {table.dtype}, not ({N_CONTEXTS}, 2) uint8; "
                "reinstall mrexplore"
            )
        _prior_table = table
    return _prior_table


# -- the context model ---------------------------------------------------------------------------------


@nb.njit(cache=True, inline="always")
def _dstate(code: int, d: int) -> int:  # pragma: no cover - numba
    """What a code says of its neighbour ``d``: 0 free, 1 unknown, 2 occupied; 3 where there is no code."""
    if code <= 0:
        return 3
    if (code >> d) & 1:
        return 1
    if (code >> (4 + d)) & 1:
        return 2
    return 0


@nb.njit(cache=True, inline="always")
def _state(P: np.ndarray, qr: int, qc: int, dr: np.ndarray, dc: np.ndarray) -> int:  # pragma: no cover - numba
    """What the decoded cells say of cell ``(qr, qc)``: 0 free, 1 unknown, 2 occupied (a decoded neighbour's
    code says so, or beyond the grid), 3 a boundary cell, 4 decoded and not boundary, 5 nothing."""
    a = P[qr, qc]
    if a == _OUTSIDE:
        return 2
    if a > 0:
        return 3
    for d in range(4):
        m = P[qr + dr[d], qc + dc[d]]
        if m > 0:
            return _dstate(m, d ^ 1)  # the opposite direction: up 0 / down 1, left 2 / right 3
    return 4 if a == 0 else 5


@nb.njit(cache=True, inline="always")
def _bit(
    mode: int, st: np.ndarray, out: np.ndarray, stream: np.ndarray, counts: np.ndarray, ctx: int, bit: int
) -> int:  # pragma: no cover - numba
    """Encode ``bit`` (mode 0), decode one (mode 1) or count ``bit`` (mode 2) in context ``ctx``; the bit."""
    if mode == 0:
        encode_bit(st, out, counts, ctx, bit)
        return bit
    if mode == 1:
        return decode_bit(st, stream, counts, ctx)
    counts[ctx, bit] += 1
    return bit


@nb.njit(cache=True, inline="always")
def _bit_length(v: int) -> int:  # pragma: no cover - numba
    n = 0
    while v:
        v >>= 1
        n += 1
    return n


@nb.njit(cache=True, inline="always")
def _block(quiet: np.ndarray, c: int) -> None:  # pragma: no cover - numba
    if 0 <= c < len(quiet):
        quiet[c] = False


@nb.njit(cache=True, nogil=True)
def _code_box(  # noqa: C901 - numba kernel
    mode: int,
    P: np.ndarray,
    B: np.ndarray,
    b_start: np.ndarray,
    b_cols: np.ndarray,
    N: np.ndarray,
    counts: np.ndarray,
    stream: np.ndarray,
    dr: np.ndarray,
    dc: np.ndarray,
) -> tuple[np.ndarray, int]:  # pragma: no cover - numba
    """Code the box's cells in row-major order. ``P``: ``(rows + 4, cols + 4) int16`` the codes known around
    the box (the base, ``_OUTSIDE`` beyond the grid, ``_UNSEEN`` in the box), each cell's written as it is
    coded, so that the contexts read what the decoder knows; ``B``: the base codes
    there (0 beyond the grid), whose non-zero cells in padded row ``i`` are at the padded columns
    ``b_cols[b_start[i]:b_start[i + 1]]``; ``N``: ``(rows, cols)`` the codes to encode (mode 0), unused when decoding
    (mode 1, codes written into ``P``), or counted (mode 2: ``counts`` gets the raw decision counts).

    Cells whose boundary decision would see nothing (no code around them decoded, none in the base: the
    inside of rooms and the unknown, most of a whole map's box) are coded as runs, as JPEG-LS's run mode
    does: per stretch of such cells in a row, whether all are non-boundary, else where the first boundary
    cell lies (Exp-Golomb, adaptive). Most of the work is then the boundary cells, not the box's area.

    Returns the encoder's bytes (mode 0), and the stream length (mode 0), the bytes the decoder read (mode
    1; -1: a boundary cell decoded without a code, -2: a run beyond its stretch)."""
    rows, cols = P.shape[0] - 2 * _PAD, P.shape[1] - 2 * _PAD
    out = np.empty(1024 if mode == 0 else 0, dtype=np.uint8)
    st = new_decoder(stream) if mode == 1 else new_encoder()
    # quiet[c]: cell c of the row is in run mode once the cells left of it are empty. Found from the codes
    # around: the row above's (the columns of its boundary cells, gathered as it was coded), the base's,
    # and beyond the box's right and lower edges.
    quiet = np.zeros(cols, dtype=np.bool_)
    above = np.empty(cols + 2 * _PAD, dtype=np.int64)
    n_above = 0
    for pc in range(cols + 2 * _PAD):  # the row above the box lies beyond it
        if P[_PAD - 1, pc] > 0:
            above[n_above] = pc
            n_above += 1
    here = np.empty(cols + 2 * _PAD, dtype=np.int64)
    for r in range(rows):
        pr = r + _PAD
        if mode == 0 and st[2] + 64 * cols + 64 > len(out):
            grown = np.empty(2 * len(out) + 64 * cols + 64, dtype=np.uint8)
            grown[: len(out)] = out
            out = grown
        quiet[:] = True
        for k in range(n_above):
            for c in range(above[k] - _PAD - 1, above[k] - _PAD + 2):
                _block(quiet, c)
        for k in range(b_start[pr], b_start[pr + 1]):  # the base here and to the right
            _block(quiet, b_cols[k] - _PAD)
            _block(quiet, b_cols[k] - _PAD - 1)
        for k in range(b_start[pr + 1], b_start[pr + 2]):  # the base below
            _block(quiet, b_cols[k] - _PAD)
        if P[pr, cols + _PAD] > 0:  # right of the box
            _block(quiet, cols - 1)
        if r == rows - 1:  # below the box
            for c in range(cols):
                if P[pr + 1, c + _PAD] > 0:
                    _block(quiet, c)
        n_here = 0
        for pc in range(_PAD):  # left of the box: known
            if P[pr, pc] > 0:
                here[n_here] = pc
                n_here += 1
        c = 0
        while c < cols:
            pc = c + _PAD
            b = int(B[pr, pc])
            cur = int(N[r, c]) if mode != 1 else 0
            if quiet[c] and P[pr, pc - 1] <= 0:
                stretch = 1
                while c + stretch < cols and quiet[c + stretch]:
                    stretch += 1
                k = 0
                if mode != 1:
                    while k < stretch and N[r, c + k] == 0:
                        k += 1
                ctx = _RUN + min(_bit_length(stretch), 15)
                if _bit(mode, st, out, stream, counts, ctx, 1 if k == stretch else 0):
                    P[pr, pc : pc + stretch] = 0
                    c += stretch
                    continue
                # Exp-Golomb of k + 1: the length of its binary form in unary, then its bits below the top
                v = k + 1
                n = _bit_length(v) - 1
                i = 0
                while True:
                    more = _bit(mode, st, out, stream, counts, _RUN_PRE + min(i, 15), 1 if i < n else 0)
                    if not more:
                        break
                    i += 1
                    if i > 40:
                        return out, -2
                n = i
                if mode == 1:
                    v = 1
                for j in range(n - 1, -1, -1):
                    one = _bit(mode, st, out, stream, counts, _RUN_SUF + min(n - 1 - j, 15), (v >> j) & 1)
                    if mode == 1:
                        v = (v << 1) | one
                k = v - 1
                if k >= stretch:
                    return out, -2
                P[pr, pc : pc + k] = 0
                c += k  # the first boundary cell of the stretch: its boundary decision is known
                pc = c + _PAD
                b = int(B[pr, pc])
                cur = int(N[r, c]) if mode != 1 else 1
            else:
                sx = _state(P, pr, pc, dr, dc)
                n_up = P[pr - 1, pc] > 0
                n_left = P[pr, pc - 1] > 0
                n_ur = P[pr - 1, pc + 1] > 0
                n_ul = P[pr - 1, pc - 1] > 0
                ctx = sx * 128 + (64 if b != 0 else 0) + (32 if n_up else 0) + (16 if n_left else 0)
                ctx += (8 if n_ur else 0) + (4 if n_ul else 0) + (2 if B[pr, pc + 1] != 0 else 0)
                ctx += 1 if B[pr + 1, pc] != 0 else 0
                if not _bit(mode, st, out, stream, counts, ctx, 1 if cur != 0 else 0):
                    P[pr, pc] = 0
                    c += 1
                    continue
            left = max(P[pr, pc - 1], 0)
            up = max(P[pr - 1, pc], 0)
            code = 0
            for d in range(4):
                sn = _state(P, pr + dr[d], pc + dc[d], dr, dc)
                may_be_free = 1 if (code != 0 or d < 3) else 0
                ctx = ((d * 6 + sn) * 4 + _dstate(b, d)) * 4 + _dstate(left, d)
                ctx = _BD + (ctx * 4 + _dstate(up, d)) * 2 + may_be_free
                want = _dstate(cur, d) if mode != 1 else 0
                if not _bit(mode, st, out, stream, counts, ctx, 1 if want != 0 else 0):
                    continue
                if _bit(mode, st, out, stream, counts, ctx + _DIR, 1 if want == 2 else 0):
                    code |= 1 << (4 + d)
                else:
                    code |= 1 << d
            if code == 0:
                return out, -1
            P[pr, pc] = code
            here[n_here] = pc
            n_here += 1
            c += 1
        for pc in range(cols + _PAD, cols + 2 * _PAD):  # right of the box: known
            if P[pr, pc] > 0:
                here[n_here] = pc
                n_here += 1
        above, here = here, above
        n_above = n_here
    if mode == 0:
        return out, finish(st, out, rows * cols > 0)
    if mode == 1:
        return out, bytes_read(st)
    return out, 0


def _padded(
    base: NDArray[np.uint8] | None, shape: tuple[int, int], box: tuple[int, int, int, int]
) -> tuple[np.ndarray, np.ndarray]:
    """``(rows + 4, cols + 4) int16`` the codes known around ``box`` before coding (the base's on the ring
    around it, 0 for a whole map, ``_OUTSIDE`` beyond the grid, ``_UNSEEN`` inside), and the base's codes
    over the same cells (0 beyond the grid). Only the ring is read from the base: the box's inside is
    written once."""
    r0, r1, c0, c1 = box
    H, W = shape
    P = np.full((r1 - r0 + 2 * _PAD, c1 - c0 + 2 * _PAD), _UNSEEN, dtype=np.int16)
    h, w = P.shape
    strips = (
        ((0, _PAD), (0, w)),
        ((h - _PAD, h), (0, w)),
        ((_PAD, h - _PAD), (0, _PAD)),
        ((_PAD, h - _PAD), (w - _PAD, w)),
    )
    for (pr0, pr1), (pc0, pc1) in strips:
        strip = P[pr0:pr1, pc0:pc1]
        strip[:] = _OUTSIDE
        gr0, gr1 = max(pr0 + r0 - _PAD, 0), min(pr1 + r0 - _PAD, H)
        gc0, gc1 = max(pc0 + c0 - _PAD, 0), min(pc1 + c0 - _PAD, W)
        if gr0 < gr1 and gc0 < gc1:
            inside = strip[gr0 - r0 + _PAD - pr0 : gr1 - r0 + _PAD - pr0, gc0 - c0 + _PAD - pc0 : gc1 - c0 + _PAD - pc0]
            inside[:] = 0 if base is None else base[gr0:gr1, gc0:gc1]
    B = np.zeros(P.shape, dtype=np.int16)
    if base is not None:
        a0, a1, b0, b1 = max(r0 - _PAD, 0), min(r1 + _PAD, H), max(c0 - _PAD, 0), min(c1 + _PAD, W)
        B[a0 - r0 + _PAD : a1 - r0 + _PAD, b0 - c0 + _PAD : b1 - c0 + _PAD] = base[a0:a1, b0:b1]
    return P, B


def _coded(
    mode: int,
    base: NDArray[np.uint8] | None,
    shape: tuple[int, int],
    box: tuple[int, int, int, int],
    new: np.ndarray,
    counts: np.ndarray,
    stream: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, int]:
    """:func:`_code_box` over ``box`` against ``base`` (None: an empty grid): the padded codes after coding,
    the encoder's bytes and its result."""
    P, B = _padded(base, shape, box)
    if base is None:
        b_start = np.zeros(P.shape[0] + 1, dtype=np.int64)
        b_cols = np.zeros(0, dtype=np.int64)
    else:
        rows, cols = np.nonzero(B)
        b_start = np.searchsorted(rows, np.arange(P.shape[0] + 1)).astype(np.int64)
        b_cols = cols.astype(np.int64)
    out, n = _code_box(mode, P, B, b_start, b_cols, new, counts, stream, _DR, _DC)
    return P, out, n


def context_counts(message: SparseFrontierMap, base: NDArray[np.uint8] | None = None) -> NDArray[np.int64]:
    """``(N_CONTEXTS, 2) int64`` how often each context saw a 0 and a 1 in ``message`` (against ``base``
    for a delta): the statistics the prior table is learned from."""
    counts = np.zeros((N_CONTEXTS, 2), dtype=np.int64)
    box, new = _box_and_codes(message, base)
    _coded(2, base, message.shape, box, new, counts, np.zeros(0, np.uint8))
    return counts


# -- header fields ---------------------------------------------------------------------------------------


def _put(out: bytearray, value: int) -> None:
    while value >= 0x80:
        out.append((value & 0x7F) | 0x80)
        value >>= 7
    out.append(value)


def _zigzag(v: int) -> int:
    return 2 * v if v >= 0 else -2 * v - 1


class _Reader:
    """The header's varints, read from ``pos`` up to ``end``, each checked."""

    def __init__(self, data: bytes, end: int, pos: int) -> None:
        self.data, self.end, self.pos = data, end, pos

    def varint(self, what: str) -> int:
        value = 0
        for shift in range(0, 7 * _MAX_VARINT_BYTES, 7):
            if self.pos >= self.end:
                raise _fail(f"truncated before the end of {what}")
            b = self.data[self.pos]
            self.pos += 1
            value |= (b & 0x7F) << shift
            if b < 0x80:
                return value
        raise _fail(f"{what}: a varint longer than {_MAX_VARINT_BYTES} bytes")

    def signed(self, what: str) -> int:
        z = self.varint(what)
        return z >> 1 if z % 2 == 0 else -(z + 1) // 2


@dataclass(frozen=True)
class MessageHead:
    """The fields of a message that say what it is and what it applies to (:func:`peek`)."""

    robot: int
    round: int
    base_round: int
    """:data:`~mrexplore.preprocessing.sparse_map.FULL` for a whole map, else the round of its base."""
    shape: tuple[int, int] | None
    """A whole map's grid; None for a delta (its base's)."""
    box: tuple[int, int, int, int]
    offset_rc: tuple[int, int]
    """The position minus the box's first cell."""
    seeds: tuple[int, ...]
    """The first seed minus the position's index, then the gaps between seeds."""
    stream: tuple[int, int]
    """Where the coded box lies in the bytes."""

    @property
    def is_delta(self) -> bool:
        return self.base_round != FULL


def peek(data: bytes) -> MessageHead:
    """The checked fields of a message, without its coded box (a delta's base may be unknown yet)."""
    if len(data) < 2 + _CRC.size:
        raise _fail(f"{len(data)} bytes, shorter than the smallest message")
    if data[0] != MAGIC:
        raise _fail(f"magic {data[0]:#04x} is not {MAGIC:#04x}")
    version, kind = data[1] >> 1, data[1] & 1
    if version != VERSION:
        raise _fail(f"version {version} is not the supported {VERSION}")
    end = len(data) - _CRC.size
    if zlib.crc32(data[:end]) != _CRC.unpack_from(data, end)[0]:
        raise _fail("checksum mismatch")
    rd = _Reader(data, end, 2)
    robot, round_ = rd.varint("the robot"), rd.varint("the round")
    if robot > MAX_ROBOT or round_ > MAX_ROUND:
        raise _fail(f"robot {robot} or round {round_} beyond the format's {MAX_ROBOT} and {MAX_ROUND}")
    shape: tuple[int, int] | None = None
    if kind == _KIND_DELTA:
        gap = rd.varint("the base round")
        if not 1 <= gap <= round_:
            raise _fail(f"base round {round_ - gap} does not come before round {round_}")
        base = round_ - gap
    else:
        base = FULL
        H, W = rd.varint("the height"), rd.varint("the width")
        if not (H >= 1 and W >= 1 and H * W <= MAX_CELLS):
            raise _fail(f"grid {H}x{W} outside 1..{MAX_CELLS} cells")
        shape = (H, W)
    r0, c0, rows, cols = (rd.varint("the box") for _ in range(4))
    if (rows == 0) != (cols == 0):
        raise _fail(f"box of {rows}x{cols} cells")
    offset = (rd.signed("the position"), rd.signed("the position"))
    n_seeds = rd.varint("the seeds")
    if n_seeds > end - rd.pos:
        raise _fail(f"{n_seeds} seeds in {end - rd.pos} bytes")
    seeds = tuple(rd.signed("the seeds") if k == 0 else rd.varint("the seeds") for k in range(n_seeds))
    if any(s == 0 for s in seeds[1:]):
        raise _fail("seeds not strictly increasing")
    return MessageHead(robot, round_, base, shape, (r0, r0 + rows, c0, c0 + cols), offset, seeds, (rd.pos, end))


# -- encode / decode ---------------------------------------------------------------------------------------


def _box_and_codes(
    message: SparseFrontierMap, base: NDArray[np.uint8] | None
) -> tuple[tuple[int, int, int, int], NDArray[np.uint8]]:
    """The box of the listed cells and the new codes in it (the base's there, changed as listed; None: a
    whole map, an empty grid)."""
    H, W = message.shape
    cells = np.asarray(message.cells, dtype=np.int64)
    if len(cells) == 0:
        return (0, 0, 0, 0), np.zeros((0, 0), dtype=np.uint8)
    rr, cc = np.divmod(cells, W)
    box = (int(rr.min()), int(rr.max()) + 1, int(cc.min()), int(cc.max()) + 1)
    new = (
        np.zeros((box[1] - box[0], box[3] - box[2]), dtype=np.uint8)
        if base is None
        else base[box[0] : box[1], box[2] : box[3]].copy()
    )
    new[rr - box[0], cc - box[2]] = message.codes
    return box, new


def encode(message: SparseFrontierMap, base: NDArray[np.uint8] | None = None) -> bytes:
    """The message's bytes; a delta needs ``base``, the ``(H, W) uint8`` code grid it applies to.

    Examples
    --------
    >>> from mrexplore.preprocessing.sparse_map import sparse_frontier_map
    >>> from mrexplore.types import CellState
    >>> g = np.full((5, 5), CellState.OCCUPIED, np.uint8); g[1:4, 1:4] = CellState.FREE
    >>> data = encode(sparse_frontier_map(g, robot=1, round_=7, position_rc=(2, 2)))
    >>> len(data), decode(data).round  # 14 bytes of header, 5 of coded cells, a 4-byte checksum
    (23, 7)
    """
    H, W = message.shape
    if not 0 <= message.robot <= MAX_ROBOT or not 0 <= message.round <= MAX_ROUND:
        raise MrExploreError(
            f"cannot encode robot {message.robot} at round {message.round}: the wire format holds robots "
            f"0..{MAX_ROBOT} and rounds 0..{MAX_ROUND}; restart the round count"
        )
    if not (H >= 1 and W >= 1 and H * W <= MAX_CELLS):
        raise MrExploreError(
            f"cannot encode a {H}x{W} grid: the wire format holds 1..{MAX_CELLS} cells; use a coarser grid"
        )
    codes = np.asarray(message.codes, dtype=np.uint8)
    if ((codes & (codes >> 4)) & 0x0F).any():
        raise MrExploreError("cannot encode a code that flags one neighbour both unknown and occupied")
    if message.is_delta:
        if base is None or base.shape != message.shape:
            raise MrExploreError(
                f"cannot encode the delta of robot {message.robot} at round {message.round} without its base: "
                f"pass the {H}x{W} code grid of round {message.base_round}"
            )
        if (base.ravel()[message.cells] == codes).any():
            raise MrExploreError("cannot encode a delta that lists a cell whose code did not change")
        base_grid: NDArray[np.uint8] | None = np.ascontiguousarray(base, dtype=np.uint8)
    else:
        if len(codes) and not codes.all():
            raise MrExploreError("cannot encode a whole map that lists a cell with code 0")
        base_grid = None
    box, new = _box_and_codes(message, base_grid)
    _, out, n = _coded(0, base_grid, message.shape, box, new, prior().astype(np.int32), np.zeros(0, np.uint8))
    head = bytearray((MAGIC, VERSION << 1 | (_KIND_DELTA if message.is_delta else _KIND_FULL)))
    _put(head, message.robot)
    _put(head, message.round)
    if message.is_delta:
        _put(head, message.round - message.base_round)
    else:
        _put(head, H)
        _put(head, W)
    r0, r1, c0, c1 = box
    for v in (r0, c0, r1 - r0, c1 - c0):
        _put(head, v)
    pr, pc = message.position_rc
    _put(head, _zigzag(pr - r0))
    _put(head, _zigzag(pc - c0))
    seeds = np.asarray(message.seeds, dtype=np.int64)
    _put(head, len(seeds))
    if len(seeds):
        _put(head, _zigzag(int(seeds[0]) - (pr * W + pc)))
        for gap in np.diff(seeds).tolist():
            _put(head, gap)
    head += out[:n].tobytes()
    return bytes(head) + _CRC.pack(zlib.crc32(head))


def decode(data: bytes, base: NDArray[np.uint8] | None = None) -> SparseFrontierMap:
    """Parse and validate one message; raises :class:`CodecError` on anything else. A delta needs
    ``base``, the ``(H, W) uint8`` code grid of its base round (:func:`peek` says which round that is)."""
    head = peek(data)
    if head.is_delta:
        if base is None:
            raise MrExploreError(
                f"cannot decode robot {head.robot}'s delta of round {head.round} without its base: pass the code "
                f"grid of round {head.base_round}"
            )
        shape = (int(base.shape[0]), int(base.shape[1]))
    else:
        assert head.shape is not None
        shape = head.shape
    H, W = shape
    r0, r1, c0, c1 = head.box
    if r1 > H or c1 > W:
        raise _fail(f"box rows {r0}..{r1}, columns {c0}..{c1} outside the {H}x{W} grid")
    pr, pc = head.offset_rc[0] + r0, head.offset_rc[1] + c0
    if not (0 <= pr < H and 0 <= pc < W):
        raise _fail(f"position ({pr}, {pc}) outside the {H}x{W} grid")
    seeds = np.cumsum(np.array(head.seeds, dtype=np.int64)) + pr * W + pc if head.seeds else np.zeros(0, np.int64)
    if len(seeds) and not (seeds[0] >= 0 and seeds[-1] < H * W):
        raise _fail("a seed lies outside the grid")
    stream = np.frombuffer(data, dtype=np.uint8)[head.stream[0] : head.stream[1]]
    if r1 > r0 and not len(stream):
        raise _fail(f"a box of {r1 - r0}x{c1 - c0} cells without its coded cells")
    base_grid = None if not head.is_delta else np.ascontiguousarray(base, dtype=np.uint8)
    P, _, used = _coded(1, base_grid, shape, head.box, np.zeros((0, 0), np.uint8), prior().astype(np.int32), stream)
    if used == -1:
        raise _fail("a boundary cell without a code")
    if used == -2:
        raise _fail("a run of empty cells beyond its stretch")
    takes = used + 1 if r1 > r0 else 0  # the decoder's bytes and the encoder's flush
    if takes != len(stream):
        raise _fail(f"the coded box takes {takes} bytes, the message holds {len(stream)}")
    now = P[_PAD:-_PAD, _PAD:-_PAD].astype(np.uint8)
    was = np.zeros_like(now) if base_grid is None else base_grid[r0:r1, c0:c1]
    local = np.flatnonzero(now != was)
    rows, cols = np.divmod(local, max(c1 - c0, 1))
    cells = (rows + r0) * W + cols + c0
    if len(cells) and (cells[0] // W != r0 or cells[-1] // W != r1 - 1):
        raise _fail("the box is larger than the cells it holds")
    if len(cells) and (int(cols.min()) != 0 or int(cols.max()) != c1 - c0 - 1):
        raise _fail("the box is larger than the cells it holds")
    if not len(cells) and r1 > r0:
        raise _fail("a box without a changed cell")
    return SparseFrontierMap(
        head.robot, head.round, shape, (pr, pc), cells.astype(np.int64), now.ravel()[local], seeds, head.base_round
    )


def prior_sha256() -> str:
    """Digest of the prior table in use (a test holds it equal to :data:`PRIOR_SHA256`)."""
    return hashlib.sha256(prior().tobytes()).hexdigest()
