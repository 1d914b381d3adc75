"""Sparse frontier maps and the centre's reconstruction on hand-drawn maps, random maps and merges."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import bool_grid, cells, state_grid
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy import ndimage

from mrexplore.preprocessing.frontiers import close_unknown_holes, detect_frontiers
from mrexplore.preprocessing.reconstruction import CentreMap, fill_free, fill_paper, free_iou, reconstruct
from mrexplore.preprocessing.sparse_codec import decode, encode
from mrexplore.preprocessing.sparse_map import (
    changed_since,
    component_seeds,
    neighbour_codes,
    sparse_frontier_map,
)
from mrexplore.preprocessing.transmission import RobotSender
from mrexplore.types import CellState, MrExploreError

F, O, U = CellState.FREE, CellState.OCCUPIED, CellState.UNKNOWN  # noqa: E741

# Two rooms joined by a one-cell corridor (no interior cell in it), a room behind a wall seen through
# nothing (its own component), a one-cell pocket of free space inside the wall, and unknown on the right.
ROOMS = """
    ###############
    #....#########?
    #....#.....#..?
    #...........#.?
    #....#.....#..?
    ######.....####
    ###.##.....####
    ###############
"""


def rim(state: np.ndarray) -> np.ndarray:
    """Free cells and the non-free cells 4-adjacent to them: what a boundary code describes."""
    free = state == F
    pad = np.pad(free, 1)
    near = pad[:-2, 1:-1] | pad[2:, 1:-1] | pad[1:-1, :-2] | pad[1:-1, 2:]
    return free | near


def roundtrip(state: np.ndarray, position: tuple[int, int]) -> np.ndarray:
    message = decode(encode(sparse_frontier_map(state, 0, 0, position)))
    return reconstruct(message.code_grid(), message.seeds)


def test_codes_carry_the_paper_labels() -> None:
    state = state_grid(ROOMS)
    codes = neighbour_codes(state)
    f = detect_frontiers(state)
    assert np.array_equal((codes & 0x0F) != 0, f.un_mask)  # F_un: an unknown neighbour
    assert np.array_equal((codes >> 4) != 0, f.occ_mask)  # F_occ: an occupied neighbour


def test_seeds_one_per_component_with_interior() -> None:
    state = state_grid(ROOMS)
    seeds = component_seeds(state, neighbour_codes(state), (3, 2))
    # The robot's room seeds at the robot; the right room (interior) at its first interior cell; the
    # pocket at (6, 3) and the strip at (2..4, 12..13) are all boundary and need no seed.
    assert [divmod(int(s), 15) for s in seeds] == [(3, 2)]
    state[3, 5] = O  # cut the corridor: the rooms become two components
    seeds = component_seeds(state, neighbour_codes(state), (3, 2))
    assert [divmod(int(s), 15) for s in seeds] == [(3, 2), (3, 7)]


def test_roundtrip_exact_on_hand_drawn_map() -> None:
    state = state_grid(ROOMS)
    rebuilt = roundtrip(state, (3, 2))
    near = rim(state)
    assert np.array_equal(rebuilt == F, state == F)
    assert np.array_equal(rebuilt[near], state[near])
    assert (rebuilt[~near] == U).all()  # the inside of walls is never sent


def test_paper_fill_loses_the_room_behind_a_thin_corridor() -> None:
    state = state_grid(ROOMS)
    boundary = detect_frontiers(state).un_mask | detect_frontiers(state).occ_mask
    paper = fill_paper(boundary, (3, 2))
    lost = (state == F) & ~paper
    # The second room's interior: its free cells off the boundary, behind the corridor cell (3, 5).
    assert cells_of(lost) == cells("""
        ...............
        ...............
        ...............
        ......xxxxx....
        .......xxx.....
        .......xxx.....
        ...............
        ...............
    """)
    assert free_iou(paper, state == F) < free_iou(roundtrip(state, (3, 2)) == F, state == F) == 1.0


def cells_of(mask: np.ndarray) -> list[list[int]]:
    return np.argwhere(mask).tolist()


def test_fill_stays_inside_and_crosses_doors_by_codes() -> None:
    state = state_grid("""
        #########
        #...#...#
        #.......#
        #...#...#
        #########
    """)
    codes = neighbour_codes(state)
    assert np.array_equal(fill_free(codes, np.array([2 * 9 + 2])), state == F)
    assert np.array_equal(fill_free(codes, np.zeros(0, np.int64)), codes != 0)  # no seed: boundary only


@st.composite
def random_maps(draw: st.DrawFn) -> tuple[np.ndarray, tuple[int, int]]:
    h = draw(st.integers(3, 14))
    w = draw(st.integers(3, 14))
    flat = draw(st.lists(st.sampled_from([F, F, F, O, U]), min_size=h * w, max_size=h * w))
    state = np.array(flat, dtype=np.uint8).reshape(h, w)
    r, c = draw(st.integers(0, h - 1)), draw(st.integers(0, w - 1))
    state[r, c] = F
    return state, (r, c)


@settings(max_examples=300, deadline=None)
@given(random_maps())
def test_roundtrip_exact_on_random_maps(case: tuple[np.ndarray, tuple[int, int]]) -> None:
    state, position = case
    rebuilt = roundtrip(state, position)
    near = rim(state)
    assert np.array_equal(rebuilt == F, state == F)
    assert np.array_equal(rebuilt[near], state[near])


@settings(max_examples=100, deadline=None)
@given(random_maps(), random_maps(), st.integers(0, 20), st.integers(0, 20), st.sampled_from([1, 3, 5]))
def test_centre_merges_and_closes_on_its_box_as_on_the_whole_grid(
    a: tuple[np.ndarray, tuple[int, int]],
    b: tuple[np.ndarray, tuple[int, int]],
    dr: int,
    dc: int,
    closing: int,
) -> None:
    # Two robots' maps placed apart in a larger grid: the centre merges and closes on the box of their
    # messages grown by the closing's reach; the reference merges and closes the whole grid.
    shape = (40, 40)
    messages = []
    for i, ((state, (r, c)), (r0, c0)) in enumerate(zip((a, b), ((3, 4), (3 + dr, 4 + dc)), strict=True)):
        grid = np.full(shape, U, np.uint8)
        grid[r0 : r0 + state.shape[0], c0 : c0 + state.shape[1]] = state
        messages.append(sparse_frontier_map(grid, i, 0, (r0 + r, c0 + c)))
    centre = CentreMap(2, shape, closing_size_cells=closing)
    for m in messages:
        centre.receive(m)
    rebuilt = [reconstruct(m.code_grid(), m.seeds) for m in messages]
    free = (rebuilt[0] == F) | (rebuilt[1] == F)
    occupied = (rebuilt[0] == O) | (rebuilt[1] == O)
    whole = np.full(shape, U, np.uint8)
    whole[occupied] = O
    whole[free & ~occupied] = F
    assert np.array_equal(centre.state(), close_unknown_holes(whole, closing))
    for m, r in zip(messages, rebuilt, strict=True):  # given the message's cells: the same grid
        assert np.array_equal(reconstruct(m.code_grid(), m.seeds, m.cells), r)


def test_fill_beyond_the_box_of_the_message_is_rebuilt() -> None:
    # Known free space up to the map's edges and one unknown cell: the message's coded cells and seed
    # span rows and columns 2..5 only, but the free space it stands for is the whole map but one cell.
    state = state_grid("""
        .......
        .......
        .......
        .......
        ....?..
        .......
    """)
    message = sparse_frontier_map(state, 0, 0, (2, 2))
    assert sorted(divmod(int(c), 7) for c in message.cells) == [(3, 4), (4, 3), (4, 5), (5, 4)]
    assert np.array_equal(roundtrip(state, (2, 2)), state)


def two_robots() -> tuple[np.ndarray, np.ndarray]:
    a = state_grid("""
        ##########
        #.....????
        #.....????
        ######????
    """)
    b = state_grid("""
        ##########
        ???.....?#
        ???......#
        ???#######
    """)
    return a, b


def test_merge_drops_frontiers_inside_space_another_robot_saw() -> None:
    a, b = two_robots()
    centre = CentreMap(2, a.shape, closing_size_cells=1)
    centre.receive(sparse_frontier_map(a, 0, 0, (1, 1)))
    centre.receive(sparse_frontier_map(b, 1, 0, (1, 7)))
    merged = centre.state()
    assert np.array_equal(
        merged == F,
        bool_grid(
            """
        ##########
        #.......??
        #........#
        ######????
    """,
            ".",
        ),
    )
    # Robot a's F_un (column 5) lies in b's free space; the team's frontier is where (1, 8) is unknown.
    assert detect_frontiers(merged).un_rc.tolist() == [[1, 7], [2, 8]]


def test_merge_prefers_obstacles_on_conflict() -> None:
    a = state_grid("....\n....")
    b = state_grid("..#.\n....")
    centre = CentreMap(2, a.shape, closing_size_cells=1)
    centre.receive(sparse_frontier_map(a, 0, 0, (0, 0)))
    centre.receive(sparse_frontier_map(b, 1, 0, (0, 0)))
    assert centre.state()[0, 2] == O


def test_deltas_rebuild_what_full_maps_rebuild() -> None:
    rng = np.random.default_rng(3)
    truth = state_grid(ROOMS)
    full_centre = CentreMap(1, truth.shape, 1)
    delta_centre = CentreMap(1, truth.shape, 1)
    sender = RobotSender(0, truth.shape)
    kinds = []
    for rnd, col in enumerate((4, 7, 10, 15, 15)):
        seen = np.full(truth.shape, U, np.uint8)
        seen[:, :col] = truth[:, :col]
        if rnd < 3:
            seen[rng.random(truth.shape) < 0.05] = U  # gaps between beams, filled in later rounds
        seen[3, 2] = F
        full, incremental = sender.send(seen, rnd, (3, 2))
        full_centre.receive(decode(full))
        message = delta_centre.read(incremental)
        assert message is not None
        delta_centre.receive(message)
        sender.acknowledged(message)
        assert np.array_equal(full_centre.state(), delta_centre.state())
        assert len(incremental) <= len(full)
        kinds.append(message.is_delta)
    # The first map is whole; a round with nothing new costs a header and the seeds.
    assert not kinds[0] and kinds[-1] and len(message.cells) == 0


@settings(max_examples=100, deadline=None)
@given(st.integers(0, 10**6))
def test_a_window_sends_what_the_whole_grid_sends(seed: int) -> None:
    # A robot seeing more and more of a random map, in a window that grows round by round: every full
    # map and every delta equals the one built from the whole grid.
    rng = np.random.default_rng(seed)
    shape = (int(rng.integers(8, 30)), int(rng.integers(8, 30)))
    truth = rng.choice(np.array([F, F, F, O], np.uint8), shape)
    whole, windowed = RobotSender(0, shape), RobotSender(0, shape)
    r, c = int(rng.integers(0, shape[0])), int(rng.integers(0, shape[1]))
    h, w = 2, 2
    for rnd in range(4):
        h, w = h + int(rng.integers(0, 4)), w + int(rng.integers(0, 4))
        seen = np.full(shape, U, np.uint8)
        seen[r : r + h, c : c + w] = truth[r : r + h, c : c + w]
        seen[r, c] = F
        window = (slice(max(r - 2, 0), min(r + h + 2, shape[0])), slice(max(c - 2, 0), min(c + w + 2, shape[1])))
        expected = whole.outgoing(seen, rnd, (r, c))
        assert windowed.send(seen[window], rnd, (r, c), window) == expected.both()
        whole.acknowledged(expected.incremental_message())
        windowed.acknowledged(expected.incremental_message())


def test_delta_on_the_wrong_base_is_refused() -> None:
    a, _ = two_robots()
    centre = CentreMap(1, a.shape, 1)
    first = sparse_frontier_map(a, 0, 0, (1, 1))
    centre.receive(first)
    later = changed_since(first.code_grid(), sparse_frontier_map(a, 0, 5, (1, 1)), 4)
    with pytest.raises(MrExploreError) as err:
        centre.receive(later)
    assert str(err.value) == (
        "delta from robot 0 applies to round 4, the centre holds round 0; ask the robot for a full map"
    )


@settings(max_examples=200, deadline=None)
@given(st.data())
def test_paper_fill_is_the_seed_component_off_the_fence(data: st.DataObject) -> None:
    h, w = data.draw(st.integers(1, 12)), data.draw(st.integers(1, 12))
    fence = np.array(data.draw(st.lists(st.booleans(), min_size=h * w, max_size=h * w)), bool).reshape(h, w)
    seed = (data.draw(st.integers(0, h - 1)), data.draw(st.integers(0, w - 1)))
    labels, _ = ndimage.label(~fence)
    expected = fence | ((labels == labels[seed]) & ~fence)
    assert np.array_equal(fill_paper(fence, seed), expected)


@settings(max_examples=200, deadline=None)
@given(
    st.lists(st.integers(0, 60), max_size=40, unique=True),
    st.lists(st.tuples(st.integers(0, 60), st.integers(0, 3)), max_size=40),
)
def test_delta_leaves_the_cells_numpys_set_operations_give(held: list[int], delta: list[tuple[int, int]]) -> None:
    """The centre's coded cells after a delta: one merge, the same sorted cells as the set operations it
    replaced, duplicates in the delta included (a cell stays when one of its codes is not 0)."""
    from mrexplore.preprocessing.reconstruction import _updated_cells

    cells_ = np.array(sorted(held), np.int64)
    delta.sort(key=lambda cc: cc[0])
    changed = np.array([c for c, _ in delta], np.int64)
    codes = np.array([k for _, k in delta], np.uint8)
    expected = np.union1d(np.setdiff1d(cells_, changed[codes == 0]), changed[codes != 0])
    assert _updated_cells(cells_, changed, codes).tolist() == expected.tolist()


def test_a_delta_after_an_unsorted_full_map_keeps_every_cell() -> None:
    """A full map whose cells come in another order, then a delta: the cells are those of the set operations."""
    from mrexplore.preprocessing.sparse_map import SparseFrontierMap

    centre = CentreMap(1, (4, 4), 1)
    full = SparseFrontierMap(
        0, 0, (4, 4), (0, 0), np.array([9, 2, 5], np.int64), np.array([1, 1, 1], np.uint8), np.zeros(0, np.int64)
    )
    centre.receive(full)
    delta = SparseFrontierMap(
        0, 1, (4, 4), (0, 0), np.array([2, 7], np.int64), np.array([0, 3], np.uint8), np.zeros(0, np.int64), 0
    )
    centre.receive(delta)
    assert centre._cells[0].tolist() == [5, 7, 9]


@settings(max_examples=200, deadline=None)
@given(st.integers(0, 10**6), st.sampled_from([1, 3, 5]), st.booleans())
def test_the_centre_kept_between_rounds_equals_the_centre_rebuilt_from_scratch(
    seed: int, closing: int, walled: bool
) -> None:
    """Robots whose grids change round by round in random boxes (cells seen, forgotten, flipped; free
    space reaching the grid's edge or not), sending deltas: the grid the centre keeps and redoes where
    deltas fell equals the one it rebuilds from every robot's whole map, every round, and so do its
    frontiers."""
    rng = np.random.default_rng(seed)
    shape = (int(rng.integers(6, 28)), int(rng.integers(6, 28)))
    n = int(rng.integers(1, 4))
    truth = rng.choice(np.array([F, F, F, F, O], np.uint8), shape)
    if walled:  # a map closed by walls, as the dev maps are: no free space on the grid's edge
        truth[[0, -1], :] = O
        truth[:, [0, -1]] = O
    grids = [np.full(shape, U, np.uint8) for _ in range(n)]
    senders = [RobotSender(i, shape) for i in range(n)]
    centre = CentreMap(n, shape, closing_size_cells=closing)
    for rnd in range(8):
        for i in range(n):
            r0, c0 = int(rng.integers(0, shape[0])), int(rng.integers(0, shape[1]))
            r1, c1 = r0 + int(rng.integers(1, 9)), c0 + int(rng.integers(1, 9))
            kind = rng.random()
            if kind < 0.6:  # seen
                grids[i][r0:r1, c0:c1] = truth[r0:r1, c0:c1]
            elif kind < 0.8:  # forgotten
                grids[i][r0:r1, c0:c1] = U
            else:  # a few cells flip
                box = grids[i][r0:r1, c0:c1]
                flip = rng.random(box.shape) < 0.3
                box[flip] = rng.choice(np.array([F, O, U], np.uint8), int(flip.sum()))
            free = np.argwhere(grids[i] == F)
            pos = tuple(int(v) for v in free[rng.integers(len(free))]) if len(free) else (0, 0)
            full, delta = senders[i].send(grids[i], rnd, pos)  # type: ignore[arg-type]
            message = centre.read(delta if rng.random() < 0.9 else full)
            assert message is not None  # every message is acknowledged: the centre holds each base
            centre.receive(message)
            senders[i].acknowledged(message)
        if rng.random() < 0.7:  # the centre is not asked every round: deltas pile up
            _assert_kept_as_from_scratch(centre)
    _assert_kept_as_from_scratch(centre)


def _assert_kept_as_from_scratch(centre: CentreMap) -> None:
    """The kept grid equals the one rebuilt from scratch, and the kept frontiers are the grid's."""
    kept = centre.state()
    assert np.array_equal(kept, centre.state_from_scratch())
    frontiers, expected = centre.frontiers(), detect_frontiers(kept)
    assert np.array_equal(frontiers.un_mask, expected.un_mask)
    assert np.array_equal(frontiers.occ_mask, expected.occ_mask)


def _kept_and_scratch(rounds: list[str], positions: list[tuple[int, int]]) -> tuple[np.ndarray, np.ndarray]:
    """One robot sending the grids drawn in ``rounds``, a full map then deltas: the centre's kept grid and
    the one it rebuilds from scratch after the last round."""
    grids = [state_grid(g) for g in rounds]
    centre = CentreMap(1, grids[0].shape, closing_size_cells=1)
    acked, kept = None, None
    for rnd, (grid, pos) in enumerate(zip(grids, positions, strict=True)):
        full = sparse_frontier_map(grid, 0, rnd, pos)
        centre.receive(full if acked is None else changed_since(acked, full, rnd - 1))
        acked = full.code_grid()
        kept = centre.state()
    assert kept is not None
    return kept, centre.state_from_scratch()


@pytest.mark.parametrize("later", [(2, 4), (0, 8)])
def test_a_robot_that_sees_the_whole_map_at_once_is_rebuilt_beyond_its_delta(later: tuple[int, int]) -> None:
    # Round 1 codes change only round the old room and the one cell left unknown: the delta's box, grown
    # by a cell, is columns 0..7. Column 8 turns free too, with no code of its own (interior cells). From
    # the robot at (2, 4) the fill in the box steps out into a cell that was not free; from (0, 8), a seed
    # outside the box lies outside the free space the centre held. Either way the centre fills it all.
    kept, scratch = _kept_and_scratch(
        [
            """
            ?????????
            ?????????
            ??#...???
            ??#...???
            ?????????
            ?????????
            """,
            """
            .........
            .........
            ..#......
            .....?...
            .........
            .........
            """,
        ],
        [(2, 4), later],
    )
    assert np.array_equal(kept, scratch)
    assert int((kept == F).sum()) == 9 * 6 - 2


def test_a_robot_that_forgets_free_space_reaching_the_grid_edge_is_rebuilt_whole() -> None:
    # Its free space on the left reached the grid's edges round one unknown cell; forgetting it changes
    # the codes of that cell's neighbours and of column 6 only, and the delta's box, grown by a cell, leaves
    # out column 0. Free space on the grid's edge can change beyond any box: the robot is rebuilt whole.
    kept, scratch = _kept_and_scratch(
        [
            """
            .......#.#
            .......#.#
            ...?...#.#
            .......#.#
            .......#.#
            """,
            """
            ???????#.#
            ???????#.#
            ???????#.#
            ???????#.#
            ???????#.#
            """,
        ],
        [(0, 0), (0, 8)],
    )
    assert np.array_equal(kept, scratch)
    assert np.array_equal(kept[:, :7] == U, np.ones((5, 7), bool))


def test_a_short_delta_is_sent_without_encoding_the_whole_map(monkeypatch: pytest.MonkeyPatch) -> None:
    # Round 0 has no acknowledged base: the whole map goes. Round 1 changes one cell of a cluttered hall,
    # so its delta (a header and a few cells) is under half of round 0's whole map (hundreds of boundary
    # cells) and goes without this round's whole map being encoded: the one encode call is the delta's.
    # The whole map is encoded when asked for, for the accounting.
    import mrexplore.preprocessing.transmission as transmission

    encoded: list[bool] = []
    monkeypatch.setattr(transmission, "encode", lambda m, base=None: encoded.append(m.is_delta) or encode(m, base))
    seen = np.full((40, 60), O, np.uint8)
    seen[1:-1, 1:-1] = np.where(np.random.default_rng(0).random((38, 58)) < 0.1, O, F)
    seen[1:-1, -1] = U
    seen[20, 30] = F
    sender = RobotSender(0, seen.shape)
    first = sender.outgoing(seen, 0, (20, 30))
    assert first.delta is None and first.incremental() == first.full_bytes() and encoded == [False]
    sender.acknowledged(first.incremental_message())
    seen[20, 31] = O
    encoded.clear()
    second = sender.outgoing(seen, 1, (20, 30))
    delta = decode(second.incremental(), first.full.code_grid())
    assert encoded == [True] and delta == second.incremental_message() == second.delta
    assert delta.is_delta and delta.base_round == 0 and 2 * len(second.incremental()) < len(first.full_bytes())
    assert second.full_bytes() == encode(sparse_frontier_map(seen, 0, 1, (20, 30)))
    assert encoded == [True, False]


def test_a_long_delta_is_weighed_against_the_whole_map() -> None:
    # After an acknowledged round with a single free cell, the next round sees the whole map: the delta
    # lists every boundary cell, as the whole map does (and the lost cell), so it is no shorter than half
    # the last whole map; the two are encoded and compared, and the shorter goes (the whole map on a tie).
    full_map = state_grid(ROOMS)
    one = np.full(full_map.shape, U, np.uint8)
    one[3, 2] = F
    sender = RobotSender(0, full_map.shape)
    first = sender.outgoing(one, 0, (3, 2))
    sender.acknowledged(first.incremental_message())
    out = sender.outgoing(full_map, 1, (3, 2))
    assert out.delta is not None and len(out.delta.cells) >= len(out.full.cells)
    full, incremental = out.both()
    delta = encode(out.delta, first.full.code_grid())
    assert 2 * len(delta) >= len(first.full_bytes())
    assert incremental == (delta if len(delta) < len(full) else full)
