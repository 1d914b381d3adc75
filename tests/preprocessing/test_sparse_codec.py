"""The frontier message wire format: round trips, exact errors, fuzzing with random and mutated bytes."""

from __future__ import annotations

import struct
import zlib

import numpy as np
import pytest
from conftest import state_grid
from hypothesis import given, settings
from hypothesis import strategies as st

from mrexplore.preprocessing.sparse_codec import HEADER, MAX_CELLS, MAX_ROUND, CodecError, decode, encode
from mrexplore.preprocessing.sparse_map import FULL, SparseFrontierMap, sparse_frontier_map
from mrexplore.types import MrExploreError

ROOM = """
    #######
    #.....?
    #.#...?
    #.....#
    #######
"""


def sample() -> bytes:
    return encode(sparse_frontier_map(state_grid(ROOM), robot=2, round_=9, position_rc=(2, 3)))


@st.composite
def messages(draw: st.DrawFn) -> SparseFrontierMap:
    h = draw(st.integers(1, 300))
    w = draw(st.integers(1, 300))
    n = h * w
    cells = np.array(sorted(draw(st.sets(st.integers(0, n - 1), max_size=min(n, 400)))), dtype=np.int64)
    is_delta = draw(st.booleans())
    low = st.integers(0, 15)
    code = st.tuples(low, low).map(lambda lh: lh[0] | ((lh[1] & ~lh[0] & 15) << 4))
    codes = np.array(draw(st.lists(code, min_size=len(cells), max_size=len(cells))), dtype=np.uint8)
    if not is_delta:
        codes[codes == 0] = 1
    seeds = np.array(sorted(draw(st.sets(st.integers(0, n - 1), max_size=5))), dtype=np.int64)
    rnd = draw(st.integers(1, MAX_ROUND))
    base = draw(st.integers(0, rnd - 1)) if is_delta else FULL
    pos = (draw(st.integers(0, h - 1)), draw(st.integers(0, w - 1)))
    return SparseFrontierMap(draw(st.integers(0, 65535)), rnd, (h, w), pos, cells, codes, seeds, base)


@settings(max_examples=300, deadline=None)
@given(messages())
def test_roundtrip_random_messages(message: SparseFrontierMap) -> None:
    assert decode(encode(message)) == message


def test_encode_refuses_a_round_beyond_the_format() -> None:
    message = sparse_frontier_map(state_grid(ROOM), robot=0, round_=MAX_ROUND + 1, position_rc=(2, 3))
    with pytest.raises(MrExploreError) as err:
        encode(message)
    assert str(err.value) == (
        f"cannot encode robot 0 at round {MAX_ROUND + 1}: the wire format holds robots 0..65535 and rounds "
        f"0..{MAX_ROUND}; restart the round count"
    )


def test_roundtrip_hand_drawn_map_and_sizes() -> None:
    data = sample()
    message = decode(data)
    assert (message.robot, message.round, message.position_rc, message.shape) == (2, 9, (2, 3), (5, 7))
    assert len(message.cells) == 13 and len(message.seeds) == 1  # 14 free cells, (2, 4) is interior
    assert len(data) == HEADER.size + struct.unpack_from("<I", data, HEADER.size - 8)[0]


@settings(max_examples=500, deadline=None)
@given(st.binary(max_size=400))
def test_random_bytes_raise_codec_error(data: bytes) -> None:
    with pytest.raises(CodecError, match=r"^bad frontier message: .*; drop it and ask the robot for a full map$"):
        decode(data)


@settings(max_examples=500, deadline=None)
@given(st.data())
def test_mutated_bytes_raise_codec_error(data: st.DataObject) -> None:
    good = bytearray(sample())
    i = data.draw(st.integers(0, len(good) - 1))
    good[i] ^= data.draw(st.integers(1, 255))
    with pytest.raises(CodecError):
        decode(bytes(good))


def test_every_truncation_raises_codec_error() -> None:
    good = sample()
    for k in range(len(good)):
        with pytest.raises(CodecError):
            decode(good[:k])


FIELDS = [
    "magic",
    "version",
    "kind",
    "flags",
    "robot",
    "round",
    "base",
    "H",
    "W",
    "pr",
    "pc",
    "n_cells",
    "n_seeds",
    "raw_len",
    "pay_len",
]


def forge(**changes: int) -> bytes:
    """A header with some fields changed and a valid checksum, over an empty payload."""
    values = dict(zip(FIELDS, (b"MRXF", 1, 0, 0, 0, 0, -1, 4, 4, 0, 0, 0, 0, 0, 0), strict=True))
    values.update(changes)
    header = HEADER.pack(*values.values(), 0)
    return HEADER.pack(*values.values(), zlib.crc32(header))


@pytest.mark.parametrize(
    ("changes", "problem"),
    [
        ({"version": 2}, "version 2 is not the supported 1"),
        ({"kind": 1}, "base round -1 does not fit kind 1 at round 0"),
        ({"H": 1 << 15, "W": 1 << 14}, f"grid 32768x16384 outside 1..{MAX_CELLS} cells"),
        ({"pr": 4}, "position (4, 0) outside the 4x4 grid"),
        (
            {"n_cells": 1_000_000, "raw_len": 1_000_000},
            "sizes (raw 1000000, cells 1000000, seeds 0) do not fit 0 payload bytes",
        ),
    ],
)
def test_forged_headers_give_exact_errors(changes: dict[str, int], problem: str) -> None:
    with pytest.raises(CodecError) as err:
        decode(forge(**changes))
    assert str(err.value) == f"bad frontier message: {problem}; drop it and ask the robot for a full map"


def test_a_deflate_bomb_is_refused_without_inflating() -> None:
    # 100 kB of zeros deflate to ~100 bytes; a header claiming 100 MB from them exceeds deflate's ratio.
    bomb = zlib.compress(b"\0" * 100_000, 9)
    values = dict(zip(FIELDS, (b"MRXF", 1, 0, 1, 0, 0, -1, 4, 4, 0, 0, 0, 0, 100_000_000, len(bomb)), strict=True))
    zeroed = HEADER.pack(*values.values(), 0)
    data = HEADER.pack(*values.values(), zlib.crc32(bomb, zlib.crc32(zeroed))) + bomb
    with pytest.raises(CodecError, match="do not fit"):
        decode(data)
