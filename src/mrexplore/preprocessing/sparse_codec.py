"""Binary wire format of a :class:`~mrexplore.preprocessing.sparse_map.SparseFrontierMap` (encode / decode).

Layout, little-endian::

    header (54 bytes)
      magic    4s   b"MRXF"
      version  u8   1
      kind     u8   0 full map, 1 delta
      flags    u8   bit 0: payload is zlib-deflated
      (pad)    u8
      robot    u16
      round    u32
      base     i32  -1 for a full map, else the acknowledged round a delta applies to
      height   u32, width u32
      pos_r    u32, pos_c u32
      n_cells  u32, n_seeds u32
      raw_len  u32  payload length before deflate
      pay_len  u32  payload length as sent
      crc32    u32  zlib.crc32 of the header (this field zeroed) and the payload
    payload
      cells    runs of consecutive row-major indices: varint(gap since the previous run's end), varint(length - 1)
      codes    n_cells bytes
      seeds    varint deltas of the increasing seed indices

Varints are LEB128 (7 bits per byte). The payload is deflated (level 6) only where that makes it shorter.
Decoding checks every field before use and bounds every allocation by the bytes received (deflate expands
at most about 1032 times), so garbage, truncated or foreign bytes raise one :class:`CodecError`.
"""

from __future__ import annotations

import struct
import zlib

import numba as nb
import numpy as np

from mrexplore.preprocessing.sparse_map import FULL, SparseFrontierMap
from mrexplore.types import MrExploreError

__all__ = ["encode", "decode", "CodecError", "HEADER", "VERSION", "MAX_CELLS", "MAX_ROUND", "MAX_ROBOT"]

MAGIC = b"MRXF"
VERSION = 1
HEADER = struct.Struct("<4sBBBxHIiIIIIIIIII")
"""The fixed header; ``HEADER.size`` bytes."""
MAX_CELLS = 1 << 28
"""Largest grid (cells) a message may refer to: 268 M cells, 26 km² at 0.1 m."""
MAX_ROUND = (1 << 31) - 1
"""Largest round number: a delta's base round is a signed 32-bit field (-1 marks a full map)."""
MAX_ROBOT = (1 << 16) - 1
"""Largest robot id (16 bits)."""
_KIND_FULL, _KIND_DELTA = 0, 1
_FLAG_DEFLATE = 1
_DEFLATE_MAX_RATIO = 1100
_MAX_VARINT_BYTES = 9  # 63 bits
_CRC_OFFSET = HEADER.size - 4
_FIX = "drop it and ask the robot for a full map"


class CodecError(MrExploreError):
    """Bytes that are not a valid frontier message."""


def _fail(problem: str) -> CodecError:
    return CodecError(f"bad frontier message: {problem}; {_FIX}")


@nb.njit(cache=True, inline="always")
def _put_varint(out: np.ndarray, pos: int, value: int) -> int:  # pragma: no cover - numba
    while value >= 0x80:
        out[pos] = (value & 0x7F) | 0x80
        value >>= 7
        pos += 1
    out[pos] = value
    return pos + 1


@nb.njit(cache=True)
def _encode_payload(cells: np.ndarray, codes: np.ndarray, seeds: np.ndarray) -> np.ndarray:  # pragma: no cover
    n = len(cells)
    out = np.empty(n * (2 * _MAX_VARINT_BYTES + 1) + len(seeds) * _MAX_VARINT_BYTES + 1, dtype=np.uint8)
    pos = 0
    i = 0
    prev_end = 0
    while i < n:
        j = i
        while j + 1 < n and cells[j + 1] == cells[j] + 1:
            j += 1
        pos = _put_varint(out, pos, cells[i] - prev_end)
        pos = _put_varint(out, pos, j - i)
        prev_end = cells[j] + 1
        i = j + 1
    out[pos : pos + n] = codes
    pos += n
    prev = 0
    for s in seeds:
        pos = _put_varint(out, pos, s - prev)
        prev = s
    return out[:pos]


@nb.njit(cache=True, inline="always")
def _get_varint(buf: np.ndarray, pos: int) -> tuple[int, int]:  # pragma: no cover - numba
    """Value and next position; position -1 when truncated or longer than 63 bits."""
    value = 0
    shift = 0
    while pos < len(buf):
        b = int(buf[pos])
        pos += 1
        value |= (b & 0x7F) << shift
        if b < 0x80:
            return value, pos
        shift += 7
        if shift >= 7 * _MAX_VARINT_BYTES:
            return 0, -1
    return 0, -1


@nb.njit(cache=True)
def _decode_payload(
    buf: np.ndarray, n_cells: int, n_seeds: int, n_total: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:  # pragma: no cover - numba
    """Cells, codes, seeds and an error number (0: none; see ``_PAYLOAD_ERRORS``)."""
    cells = np.empty(n_cells, dtype=np.int64)
    seeds = np.empty(n_seeds, dtype=np.int64)
    empty_codes = np.empty(0, dtype=np.uint8)
    pos = 0
    k = 0
    prev_end = 0
    while k < n_cells:
        gap, pos = _get_varint(buf, pos)
        if pos < 0:
            return cells, empty_codes, seeds, 1
        run, pos = _get_varint(buf, pos)
        if pos < 0:
            return cells, empty_codes, seeds, 1
        if run >= n_cells - k:
            return cells, empty_codes, seeds, 2
        if gap >= n_total - prev_end or run >= n_total - prev_end - gap:
            return cells, empty_codes, seeds, 3
        start = prev_end + gap
        for t in range(run + 1):
            cells[k] = start + t
            k += 1
        prev_end = start + run + 1
    if pos + n_cells > len(buf):
        return cells, empty_codes, seeds, 1
    codes = buf[pos : pos + n_cells].copy()
    pos += n_cells
    prev = 0
    for s in range(n_seeds):
        step, pos = _get_varint(buf, pos)
        if pos < 0:
            return cells, codes, seeds, 1
        if s > 0 and step == 0:
            return cells, codes, seeds, 4
        if step >= n_total - prev:
            return cells, codes, seeds, 3
        prev += step
        seeds[s] = prev
    if pos != len(buf):
        return cells, codes, seeds, 5
    return cells, codes, seeds, 0


_PAYLOAD_ERRORS = {
    1: "payload truncated or a varint longer than 63 bits",
    2: "cell runs hold more cells than the header says",
    3: "an index lies outside the grid",
    4: "seeds not strictly increasing",
    5: "bytes left over after the payload",
}


def encode(message: SparseFrontierMap) -> bytes:
    """The message's bytes (header + payload, deflated where that is shorter).

    Examples
    --------
    >>> from mrexplore.preprocessing.sparse_map import sparse_frontier_map
    >>> from mrexplore.types import CellState
    >>> g = np.full((5, 5), CellState.OCCUPIED, np.uint8); g[1:4, 1:4] = CellState.FREE
    >>> data = encode(sparse_frontier_map(g, robot=1, round_=7, position_rc=(2, 2)))
    >>> len(data), decode(data).round  # 54-byte header, 8 bytes of runs, 8 codes, 1 seed
    (71, 7)
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
    raw = _encode_payload(
        np.ascontiguousarray(message.cells, dtype=np.int64),
        np.ascontiguousarray(message.codes, dtype=np.uint8),
        np.ascontiguousarray(message.seeds, dtype=np.int64),
    ).tobytes()
    packed = zlib.compress(raw, 6)
    flags, payload = (_FLAG_DEFLATE, packed) if len(packed) < len(raw) else (0, raw)
    kind = _KIND_DELTA if message.is_delta else _KIND_FULL
    fields = (
        MAGIC,
        VERSION,
        kind,
        flags,
        message.robot,
        message.round,
        message.base_round,
        H,
        W,
        message.position_rc[0],
        message.position_rc[1],
        len(message.cells),
        len(message.seeds),
        len(raw),
        len(payload),
    )
    header = HEADER.pack(*fields, 0)
    crc = zlib.crc32(payload, zlib.crc32(header))
    return HEADER.pack(*fields, crc) + payload


def decode(data: bytes) -> SparseFrontierMap:
    """Parse and validate one message; raises :class:`CodecError` on anything else."""
    if len(data) < HEADER.size:
        raise _fail(f"{len(data)} bytes, shorter than the {HEADER.size}-byte header")
    (magic, version, kind, flags, robot, round_, base, H, W, pr, pc, n_cells, n_seeds, raw_len, pay_len, crc) = (
        HEADER.unpack_from(data)
    )
    if magic != MAGIC:
        raise _fail(f"magic {magic!r} is not {MAGIC!r}")
    if version != VERSION:
        raise _fail(f"version {version} is not the supported {VERSION}")
    if pay_len != len(data) - HEADER.size:
        raise _fail(f"payload is {len(data) - HEADER.size} bytes, the header says {pay_len}")
    zeroed = data[:_CRC_OFFSET] + b"\0\0\0\0"
    if zlib.crc32(data[HEADER.size :], zlib.crc32(zeroed)) != crc:
        raise _fail("checksum mismatch")
    if kind not in (_KIND_FULL, _KIND_DELTA) or flags & ~_FLAG_DEFLATE:
        raise _fail(f"unknown kind {kind} or flags {flags}")
    if (kind == _KIND_FULL) != (base == FULL) or (kind == _KIND_DELTA and not 0 <= base < round_):
        raise _fail(f"base round {base} does not fit kind {kind} at round {round_}")
    if not (H >= 1 and W >= 1 and H * W <= MAX_CELLS):
        raise _fail(f"grid {H}x{W} outside 1..{MAX_CELLS} cells")
    if not (pr < H and pc < W):
        raise _fail(f"position ({pr}, {pc}) outside the {H}x{W} grid")
    deflated = bool(flags & _FLAG_DEFLATE)
    bound = _DEFLATE_MAX_RATIO * pay_len + 64 if deflated else pay_len
    if raw_len > bound or n_cells > raw_len or n_seeds > raw_len:
        raise _fail(f"sizes (raw {raw_len}, cells {n_cells}, seeds {n_seeds}) do not fit {pay_len} payload bytes")
    payload = data[HEADER.size :]
    if deflated:
        inflater = zlib.decompressobj()
        try:
            payload = inflater.decompress(payload, raw_len)
        except zlib.error as exc:
            raise _fail(f"deflate stream broken ({exc})") from None
        if not inflater.eof or inflater.unconsumed_tail or inflater.unused_data:
            raise _fail("deflate stream does not end where the payload ends")
    if len(payload) != raw_len:
        raise _fail(f"payload inflates to {len(payload)} bytes, the header says {raw_len}")
    cells, codes, seeds, err = _decode_payload(np.frombuffer(payload, dtype=np.uint8), n_cells, n_seeds, H * W)
    if err:
        raise _fail(_PAYLOAD_ERRORS[err])
    if ((codes & (codes >> 4)) & 0x0F).any():
        raise _fail("a code flags one neighbour both unknown and occupied")
    if kind == _KIND_FULL and n_cells and not codes.all():
        raise _fail("a full map lists a cell with code 0")
    return SparseFrontierMap(robot, round_, (H, W), (pr, pc), cells, codes, seeds, base)
