"""The frontier message wire format: round trips (whole maps and deltas), the header by hand, exact errors,
fuzzing with random and mutated bytes, and what the context model saves."""

from __future__ import annotations

import struct
import zlib

import numpy as np
import pytest
from conftest import state_grid
from hypothesis import given, settings
from hypothesis import strategies as st

from mrexplore.preprocessing.sparse_codec import (
    MAX_CELLS,
    MAX_ROUND,
    N_CONTEXTS,
    PRIOR_SHA256,
    CodecError,
    context_counts,
    decode,
    encode,
    peek,
    prior_sha256,
)
from mrexplore.preprocessing.sparse_map import SparseFrontierMap, changed_since, sparse_frontier_map
from mrexplore.types import CellState, MrExploreError

ROOM = """
    #######
    #.....?
    #.#...?
    #.....#
    #######
"""
BAD = r"^bad frontier message: .*; drop it and ask the robot for a full map$"


def sample() -> bytes:
    return encode(sparse_frontier_map(state_grid(ROOM), robot=2, round_=9, position_rc=(2, 3)))


def varint(v: int) -> bytes:
    out = bytearray()
    while v >= 0x80:
        out.append((v & 0x7F) | 0x80)
        v >>= 7
    out.append(v)
    return bytes(out)


def signed_codes(draw: st.DrawFn, n: int) -> np.ndarray:
    """``n`` valid non-zero codes: each neighbour free, unknown or occupied, one at least not free."""
    low = st.integers(0, 15)
    code = st.tuples(low, low).map(lambda lh: lh[0] | ((lh[1] & ~lh[0] & 15) << 4)).filter(bool)
    return np.array(draw(st.lists(code, min_size=n, max_size=n)), dtype=np.uint8)


@st.composite
def code_grids(draw: st.DrawFn, h: int, w: int) -> np.ndarray:
    """An ``(h, w)`` code grid with arbitrary valid codes on a random set of cells (not a real map's)."""
    cells = np.array(sorted(draw(st.sets(st.integers(0, h * w - 1), max_size=min(h * w, 300)))), dtype=np.int64)
    grid = np.zeros(h * w, dtype=np.uint8)
    grid[cells] = signed_codes(draw, len(cells))
    return grid.reshape(h, w)


@st.composite
def whole_and_delta(draw: st.DrawFn) -> tuple[SparseFrontierMap, SparseFrontierMap, np.ndarray]:
    """A whole map and the delta of another against it, with the base code grid."""
    h, w = draw(st.integers(1, 120)), draw(st.integers(1, 120))
    base, now = draw(code_grids(h, w)), draw(code_grids(h, w))
    if draw(st.booleans()):  # a local change, as a robot's deltas are
        keep = np.ones((h, w), dtype=bool)
        r, c = draw(st.integers(0, h - 1)), draw(st.integers(0, w - 1))
        keep[r : r + draw(st.integers(1, 30)), c : c + draw(st.integers(1, 30))] = False
        now = np.where(keep, base, now)
    rnd = draw(st.integers(1, MAX_ROUND))
    pos = (draw(st.integers(0, h - 1)), draw(st.integers(0, w - 1)))
    seeds = np.array(sorted(draw(st.sets(st.integers(0, h * w - 1), max_size=5))), dtype=np.int64)
    robot = draw(st.integers(0, 65535))
    cells = np.flatnonzero(base).astype(np.int64)
    whole = SparseFrontierMap(robot, rnd - 1, (h, w), pos, cells, base.ravel()[cells], seeds)
    current = SparseFrontierMap(robot, rnd, (h, w), pos, np.flatnonzero(now), now.ravel()[np.flatnonzero(now)], seeds)
    return whole, changed_since(base, current, draw(st.integers(0, rnd - 1))), base


@settings(max_examples=300, deadline=None)
@given(whole_and_delta())
def test_roundtrip_random_whole_maps_and_deltas(case: tuple[SparseFrontierMap, SparseFrontierMap, np.ndarray]) -> None:
    whole, delta, base = case
    assert decode(encode(whole)) == whole
    assert decode(encode(delta, base), base) == delta


@settings(max_examples=100, deadline=None)
@given(st.lists(st.lists(st.sampled_from(".#?"), min_size=12, max_size=12), min_size=10, max_size=10))
def test_roundtrip_random_grids(rows: list[list[str]]) -> None:
    state = state_grid("\n".join("".join(r) for r in rows))
    message = sparse_frontier_map(state, robot=1, round_=3, position_rc=(4, 5))
    assert decode(encode(message)) == message


def test_the_header_by_hand() -> None:
    data = sample()
    message = decode(data)
    assert (message.robot, message.round, message.position_rc, message.shape) == (2, 9, (2, 3), (5, 7))
    assert len(message.cells) == 13 and message.seeds.tolist() == [17]  # 14 free cells, (2, 3) is interior
    head = bytes(
        [
            0x4D,  # magic
            2 << 1 | 0,  # version 2, a whole map
            2, 9, 5, 7,  # robot, round, height, width
            1, 1, 3, 5,  # box: rows 1-3, columns 1-5
            2, 4,  # position (2, 3): zigzag of +1 and +2 from the box's corner
            1, 0,  # one seed, at the position (zigzag 0)
        ]
    )  # fmt: skip
    assert data[: len(head)] == head
    assert data[-4:] == struct.pack("<I", zlib.crc32(data[:-4]))
    assert peek(data).stream == (len(head), len(data) - 4)


def test_a_delta_decodes_only_against_its_base() -> None:
    state = state_grid(ROOM)
    whole = sparse_frontier_map(state, 0, 0, (2, 3))
    state[1, 6] = state[2, 6] = CellState.FREE  # the unknown cells seen free: the boundary moves right
    delta = changed_since(whole.code_grid(), sparse_frontier_map(state, 0, 1, (2, 3)), 0)
    data = encode(delta, whole.code_grid())
    assert peek(data).base_round == 0 and peek(data).shape is None
    assert decode(data, whole.code_grid()) == delta
    with pytest.raises(MrExploreError) as err:
        decode(data)
    assert str(err.value) == "cannot decode robot 0's delta of round 1 without its base: pass the code grid of round 0"
    with pytest.raises(MrExploreError) as err:
        encode(delta)
    assert str(err.value) == (
        "cannot encode the delta of robot 0 at round 1 without its base: pass the 5x7 code grid of round 0"
    )


def test_a_delta_without_changes_is_its_header_alone() -> None:
    message = sparse_frontier_map(state_grid(ROOM), 0, 1, (2, 3))
    nothing = changed_since(message.code_grid(), message, 0)
    data = encode(nothing, message.code_grid())
    # magic, format, robot, round, base gap, box (4), position (2), one seed and its offset, checksum
    assert len(data) == 2 + 1 + 1 + 1 + 4 + 2 + 2 + 4
    assert decode(data, message.code_grid()) == nothing


def test_a_straight_frontier_costs_a_fraction_of_a_bit_a_cell() -> None:
    # A 400-cell corridor, walls above, unknown below: every code follows from the one before it.
    state = np.full((5, 402), CellState.UNKNOWN, np.uint8)
    state[0] = CellState.OCCUPIED
    state[1:3, 1:401] = CellState.FREE
    message = sparse_frontier_map(state, 0, 0, (1, 1))
    assert len(message.cells) == 800
    start, end = peek(encode(message)).stream
    assert (end - start) * 8 < 0.3 * len(message.cells)  # under 0.3 bits a boundary cell


def test_encode_refuses_what_the_format_cannot_hold() -> None:
    message = sparse_frontier_map(state_grid(ROOM), robot=0, round_=MAX_ROUND + 1, position_rc=(2, 3))
    with pytest.raises(MrExploreError) as err:
        encode(message)
    assert str(err.value) == (
        f"cannot encode robot 0 at round {MAX_ROUND + 1}: the wire format holds robots 0..65535 and rounds "
        f"0..{MAX_ROUND}; restart the round count"
    )
    whole = sparse_frontier_map(state_grid(ROOM), 0, 1, (2, 3))
    same = SparseFrontierMap(0, 1, whole.shape, (2, 3), whole.cells[:1], whole.codes[:1], whole.seeds, 0)
    with pytest.raises(MrExploreError, match="^cannot encode a delta that lists a cell whose code did not change$"):
        encode(same, whole.code_grid())
    both = SparseFrontierMap(0, 1, whole.shape, (2, 3), whole.cells[:1], np.array([0x11], np.uint8), whole.seeds)
    with pytest.raises(MrExploreError, match="both unknown and occupied"):
        encode(both)


@settings(max_examples=500, deadline=None)
@given(st.binary(max_size=400))
def test_random_bytes_raise_codec_error(data: bytes) -> None:
    with pytest.raises(CodecError, match=BAD):
        decode(data)


@settings(max_examples=500, deadline=None)
@given(st.data())
def test_mutated_bytes_raise_codec_error(data: st.DataObject) -> None:
    good = bytearray(sample())
    i = data.draw(st.integers(0, len(good) - 1))
    good[i] ^= data.draw(st.integers(1, 255))
    with pytest.raises(CodecError, match=BAD):
        decode(bytes(good))


def test_every_truncation_raises_codec_error() -> None:
    good = sample()
    for k in range(len(good)):
        with pytest.raises(CodecError, match=BAD):
            decode(good[:k])


def forge(*fields: bytes | int, stream: bytes = b"") -> bytes:
    """Header bytes (ints as varints) and a coded box, with a valid checksum."""
    body = b"".join(f if isinstance(f, bytes) else varint(f) for f in fields) + stream
    return body + struct.pack("<I", zlib.crc32(body))


WHOLE = bytes([0x4D, 2 << 1])
DELTA = bytes([0x4D, 2 << 1 | 1])


@pytest.mark.parametrize(
    ("data", "problem"),
    [
        (bytes([0x4C, 4, 0, 0, 0, 0]), "magic 0x4c is not 0x4d"),
        (forge(bytes([0x4D, 1 << 1]), 0, 0), "version 1 is not the supported 2"),
        (forge(WHOLE, 0, 0), "truncated before the end of the height"),
        (forge(DELTA, 0, 5, 6), "base round -1 does not come before round 5"),
        (forge(WHOLE, 0, 0, 1 << 15, 1 << 14), f"grid 32768x16384 outside 1..{MAX_CELLS} cells"),
        (forge(WHOLE, 0, 0, 4, 4, 0, 0, 1, 0), "box of 1x0 cells"),
        (forge(WHOLE, 0, 0, 4, 4, 0, 0, 0, 0, 8, 0, 0), "position (4, 0) outside the 4x4 grid"),
        (forge(WHOLE, 0, 0, 4, 4, 3, 0, 2, 1, 0, 0, 0), "box rows 3..5, columns 0..1 outside the 4x4 grid"),
        (forge(WHOLE, 0, 0, 4, 4, 0, 0, 0, 0, 0, 0, 2, 0, 0), "seeds not strictly increasing"),
        (forge(WHOLE, 0, 0, 4, 4, 0, 0, 0, 0, 0, 0, 1, 40), "a seed lies outside the grid"),
        (
            forge(WHOLE, 0, 0, 4, 4, 0, 0, 0, 0, 0, 0, 0, stream=b"\1"),
            "the coded box takes 0 bytes, the message holds 1",
        ),
        (forge(WHOLE, 0, 0, 4, 4, 0, 0, 1, 1, 0, 0, 0), "a box of 1x1 cells without its coded cells"),
        (forge(WHOLE, 0, 0, 4, 4, 0, 0, 0, 0, 0, 0, b"\xff" * 10), "the seeds: a varint longer than 9 bytes"),
    ],
)
def test_forged_headers_give_exact_errors(data: bytes, problem: str) -> None:
    with pytest.raises(CodecError) as err:
        decode(data)
    assert str(err.value) == f"bad frontier message: {problem}; drop it and ask the robot for a full map"


def test_the_shipped_prior_is_the_one_this_format_names() -> None:
    # A changed table decodes other messages: it must come with a new format version.
    assert prior_sha256() == PRIOR_SHA256


def test_context_counts_are_the_decisions_of_a_message() -> None:
    # A 3 x 3 room walled in: 8 boundary cells, the corners with 2 walls beside them, the sides with 1. Each
    # wall is one "occupied or unknown" decision that says occupied: 4 x 2 + 4 x 1 = 12 of them, no unknown.
    g = np.full((5, 5), CellState.OCCUPIED, np.uint8)
    g[1:4, 1:4] = CellState.FREE
    counts = context_counts(sparse_frontier_map(g, 0, 0, (2, 2)))
    assert counts.shape == (N_CONTEXTS, 2)
    boundary, direction = 6 * 2 * 2**6, 4 * 6 * 4 * 4 * 4 * 2  # the model's blocks, as the codec lays them out
    occupied_or_unknown = counts[boundary + direction : boundary + 2 * direction]
    assert occupied_or_unknown.sum(axis=0).tolist() == [0, 12]
