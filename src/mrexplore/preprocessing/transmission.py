"""A robot's messages and the byte accounting of a round: the sparse frontier map built each round, whole
(the paper's message) and as a delta against the map the centre acknowledged last (RACER-style incremental
sharing), each encoded only when asked for (:class:`Outgoing`, :class:`RobotSender`); the episode's totals
(:class:`TransmissionTotals`); what the paper's baseline would send, each robot's occupancy grid as int8 per
cell over the bounding box of its known cells (a ROS OccupancyGrid's data), raw and zlib-compressed; and what
the centre knows of its robots after a round (:class:`LinkStatus`). The link itself is
:class:`~mrexplore.preprocessing.link.TeamLink`.
"""

from __future__ import annotations

import zlib
from collections.abc import Callable
from dataclasses import asdict, dataclass, field
from typing import Literal

import numba as nb
import numpy as np
from numpy.typing import NDArray

from mrexplore.maps.boxes import Box, box_union
from mrexplore.maps.occupancy_grid import OCCUPANCY_VALUES
from mrexplore.preprocessing.onboard import OnBoardGrid
from mrexplore.preprocessing.sparse_codec import BASELINE_HEADER_BYTES, encode
from mrexplore.preprocessing.sparse_map import (
    FULL,
    SparseFrontierMap,
    changed_in_box,
    changed_since,
    coded_frontier_map,
    sparse_frontier_map,
)
from mrexplore.types import CellState, StateGrid

__all__ = [
    "LinkStatus",
    "RobotSender",
    "Outgoing",
    "TransmissionTotals",
    "occupancy_grid_bytes",
    "TRANSMISSION_MODES",
    "GRID_BASELINE_FIELDS",
]

TransmissionMode = Literal["delta", "full"]
TRANSMISSION_MODES: tuple[TransmissionMode, ...] = ("delta", "full")
GRID_BASELINE_FIELDS = ("bytes_grid", "bytes_grid_zlib", "bytes_grid_delta_zlib")
"""The record's fields of Table II's int8-grid baselines: empty where a mission did not count them."""
_EMPTY: Box = (0, 0, 0, 0)


@nb.njit(cache=True, nogil=True)
def _ros_box(state: np.ndarray, lut: np.ndarray, unknown: int) -> np.ndarray:  # pragma: no cover  # noqa: C901 - numba kernel
    """The ROS values (``lut`` of each state) of the bounding box of the cells that are not ``unknown``,
    flattened row by row; empty when every cell is unknown. The box's rows and columns are found by scans
    that stop at the first known cell, then the box is written in one pass, where numpy's comparison, the
    box's reductions and the table lookup each passed over the whole window (2.9 s of a 60 s mission on a
    KTH floor under cProfile, zlib aside)."""
    H, W = state.shape
    r0 = H
    for r in range(H):
        for c in range(W):
            if state[r, c] != unknown:
                r0 = r
                break
        if r0 < H:
            break
    if r0 == H:
        return np.zeros(0, dtype=np.int8)
    r1 = r0 + 1
    for r in range(H - 1, r0, -1):
        hit = False
        for c in range(W):
            if state[r, c] != unknown:
                hit = True
                break
        if hit:
            r1 = r + 1
            break
    c0, c1 = W, 0
    for r in range(r0, r1):
        for c in range(c0):
            if state[r, c] != unknown:
                c0 = c
                break
        for c in range(W - 1, c1 - 1, -1):
            if state[r, c] != unknown:
                c1 = c + 1
                break
    out = np.empty((r1 - r0) * (c1 - c0), dtype=np.int8)
    n = 0
    for r in range(r0, r1):
        for c in range(c0, c1):
            out[n] = lut[state[r, c]]
            n += 1
    return out


def occupancy_grid_bytes(state: StateGrid) -> tuple[int, int]:
    """Bytes of the baseline message of one grid: int8 cells (ROS: -1 unknown, 0 free, 100 occupied) over
    the bounding box of known cells plus the fields every message needs (:data:`BASELINE_HEADER_BYTES`);
    raw and zlib level 6.

    Examples
    --------
    >>> g = np.full((10, 10), CellState.UNKNOWN, np.uint8); g[2:4, 3:8] = CellState.FREE
    >>> raw, packed = occupancy_grid_bytes(g)
    >>> raw - BASELINE_HEADER_BYTES  # a 2 x 5 box
    10
    """
    data = _ros_box(state, OCCUPANCY_VALUES, int(CellState.UNKNOWN))
    if len(data) == 0:
        return BASELINE_HEADER_BYTES, BASELINE_HEADER_BYTES
    return BASELINE_HEADER_BYTES + len(data), BASELINE_HEADER_BYTES + len(zlib.compress(data.data, 6))


class Outgoing:
    """One robot's messages of one round, each encoded only when asked for: the robot encodes the one it
    sends, and the byte accounting the other (what the other transmission mode would have sent).

    The incremental message is the delta where it is shorter than the whole map, else the whole map. The
    delta is encoded when the round's messages are composed (against the acknowledged codes, which change
    once the centre acknowledges). A delta under half the bytes of the last whole map encoded is sent
    without encoding this round's (the whole map of a robot that has seen much covers a large box, and
    changes little from round to round); otherwise both are encoded and the shorter goes.
    """

    def __init__(
        self,
        sender: RobotSender,
        full: SparseFrontierMap,
        delta: SparseFrontierMap | None,
        delta_bytes: bytes | None,
        last_full_len: int,
    ) -> None:
        self._sender = sender
        self.full = full
        self.delta = delta
        """None where the centre may not hold the delta's base: the incremental message is the whole map."""
        self._delta_bytes = delta_bytes
        self._last_full_len = last_full_len
        self._full_bytes: bytes | None = None
        self._incremental: bytes | None = None

    def full_bytes(self) -> bytes:
        """The whole map's bytes (the paper's message)."""
        if self._full_bytes is None:
            self._full_bytes = encode(self.full)
            self._sender._full_len = len(self._full_bytes)
        return self._full_bytes

    def incremental(self) -> bytes:
        """The bytes sent in the default ``"delta"`` mode."""
        if self._incremental is None:
            delta = self._delta_bytes
            if delta is None:
                self._incremental = self.full_bytes()
            elif len(delta) * 2 < self._last_full_len:
                self._incremental = delta
            else:
                full = self.full_bytes()
                self._incremental = delta if len(delta) < len(full) else full
        return self._incremental

    def incremental_message(self) -> SparseFrontierMap:
        """The message :meth:`incremental` encodes (what the robot remembers as sent)."""
        data = self.incremental()
        return self.delta if self.delta is not None and data is self._delta_bytes else self.full

    def both(self) -> tuple[bytes, bytes]:
        """``(full, incremental)``, both encoded."""
        return self.full_bytes(), self.incremental()


class RobotSender:
    """One robot's side of the link: builds its message each round and remembers what the centre holds.

    :meth:`send` gives the whole map (the paper's message) and the incremental one: the delta against the
    last acknowledged map, or the whole map where that is shorter (the first round, or after most of the
    boundary moved) or where the last message went unacknowledged (the centre may or may not hold it).
    """

    def __init__(self, robot: int, shape: tuple[int, int]) -> None:
        self.robot = robot
        self._acked = np.zeros(shape, dtype=np.uint8)
        self._acked_round = FULL
        self._acked_grid = np.full(shape, OCCUPANCY_VALUES[CellState.UNKNOWN], dtype=np.int8)
        self._sent_grid: tuple[tuple[slice, slice], NDArray[np.int8]] | None = None
        self._unconfirmed = False
        """The last message got no acknowledgement: the centre may hold it or not, so send the whole map."""
        self._changed: Box | None = None
        """Where the robot's :class:`OnBoardGrid` changed since the last acknowledged round (None: nowhere)."""
        self._changed_since_sent: Box | None = None
        """Where it changed since the last message was composed: what the centre lacks once it acknowledges
        that message (a robot on ROS 2 keeps sensing between sending and the acknowledgement)."""
        self._full_len = 0
        """Bytes of the last whole map encoded (0: none yet): :class:`Outgoing` sends a delta of under half of
        it without encoding this round's whole map."""

    def send(
        self, closed: StateGrid, round_: int, position_rc: tuple[int, int], window: tuple[slice, slice] | None = None
    ) -> tuple[bytes, bytes]:
        """``(full, incremental)`` message bytes of this round from the robot's closed grid.

        ``window``: where ``closed`` lies in the map when it is a window of the robot's grid (holding every
        free cell with a one-cell margin, and growing from round to round); None: ``closed`` is the map."""
        return self.outgoing(closed, round_, position_rc, window).both()

    def outgoing(
        self, closed: StateGrid, round_: int, position_rc: tuple[int, int], window: tuple[slice, slice] | None = None
    ) -> Outgoing:
        """:meth:`send`'s messages, each encoded when asked for."""
        if window is None:
            window = (slice(0, closed.shape[0]), slice(0, closed.shape[1]))
        origin = (window[0].start, window[1].start)
        full = sparse_frontier_map(closed, self.robot, round_, position_rc, origin, self._acked.shape)
        # The acknowledged map's cells lie in an earlier, smaller window: comparing in this one suffices.
        return self._outgoing(full, lambda: changed_since(self._acked, full, self._acked_round, window))

    def note_changed(self, box: Box | None) -> None:
        """The robot's :class:`OnBoardGrid` changed in ``box`` this round (what :meth:`OnBoardGrid.update`
        returned); :meth:`send_onboard` compares only where it changed since the last acknowledgement."""
        if box is not None:
            self._changed = box_union(self._changed, box)
            self._changed_since_sent = box_union(self._changed_since_sent, box)

    def send_onboard(
        self, grid: OnBoardGrid, round_: int, position_rc: tuple[int, int], window: tuple[slice, slice]
    ) -> Outgoing:
        """:meth:`send`'s messages from the robot's up-to-date :class:`OnBoardGrid` (the same bytes), its
        codes reused and the delta compared only where the grid changed since the last acknowledgement;
        encoded when asked for (:class:`Outgoing`)."""
        origin, shape = (window[0].start, window[1].start), self._acked.shape
        closed, codes = grid.closed[window], grid.codes[window]
        seeds = grid.seeds(position_rc, window)
        full = coded_frontier_map(
            closed, codes, self.robot, round_, position_rc, origin, shape, grid.cells, grid.n_free, seeds
        )
        box = self._changed if self._changed is not None else _EMPTY
        return self._outgoing(full, lambda: changed_in_box(self._acked, grid.codes, full, self._acked_round, box))

    def onboard_grid_delta_bytes(self, grid: OnBoardGrid) -> int:
        """:meth:`grid_delta_bytes` of the robot's :class:`OnBoardGrid` state, compared only where it changed
        since the last acknowledgement (same bytes)."""
        box = self._changed if self._changed is not None else _EMPTY
        rows, cols = slice(box[0], box[1]), slice(box[2], box[3])
        return self.grid_delta_bytes(grid.state[rows, cols], (rows, cols))

    def _outgoing(self, full: SparseFrontierMap, delta: Callable[[], SparseFrontierMap]) -> Outgoing:
        """This round's messages; the delta is built now (the acknowledgement of this round changes its
        base) where the centre surely holds that base, and either is encoded when asked for."""
        base_held = self._acked_round != FULL and not self._unconfirmed
        self._unconfirmed = True  # until the centre acknowledges this round
        self._changed_since_sent = None
        if not base_held:
            return Outgoing(self, full, None, None, self._full_len)
        message = delta()
        return Outgoing(self, full, message, encode(message, self._acked), self._full_len)

    def grid_delta_bytes(self, own: StateGrid, window: tuple[slice, slice]) -> int:
        """Bytes of the generic competitor of the sparse delta: the cells of the int8 occupancy grid that
        changed since the last acknowledged round, as gaps between their sorted indices (uint32) and their
        values (int8), zlib level 6, plus the fields every message needs (:data:`BASELINE_HEADER_BYTES`).
        ``own`` is the robot's grid in ``window`` (every known cell lies inside it)."""
        ros = OCCUPANCY_VALUES[own]
        width = self._acked_grid.shape[1]
        local = np.flatnonzero(ros != self._acked_grid[window])
        rows, cols = np.divmod(local, ros.shape[1])
        cells = (rows + window[0].start) * width + cols + window[1].start
        gaps = np.diff(cells, prepend=0).astype(np.uint32)
        self._sent_grid = (window, ros)
        return BASELINE_HEADER_BYTES + len(zlib.compress(gaps.tobytes() + ros.ravel()[local].tobytes(), 6))

    def acknowledged(self, message: SparseFrontierMap) -> None:
        """The centre confirmed this round's message: later deltas apply to it."""
        if not message.is_delta:
            self._acked.fill(0)
        np.put(self._acked, message.cells, message.codes)
        self._acked_round = message.round
        self._unconfirmed = False
        # The centre holds the grid as it was when this message was composed: what changed since is still
        # to send. (Forgetting it lost those changes for good where sensing went on before the
        # acknowledgement came, as on ROS 2: the centre's codes then had gaps its fill leaked through.)
        self._changed = self._changed_since_sent
        if self._sent_grid is not None:
            window, ros = self._sent_grid
            self._acked_grid[window] = ros


@dataclass
class TransmissionTotals:
    """Bytes sent over an episode, per encoding, and how faithful the centre's grid was."""

    rounds: int = 0
    bytes_grid: int = 0
    bytes_grid_zlib: int = 0
    bytes_sparse: int = 0
    bytes_sparse_delta: int = 0
    bytes_grid_delta_zlib: int = 0
    messages_sent: int = 0
    """Robot-to-centre messages sent (first tries and resends)."""
    messages_lost: int = 0
    messages_resent: int = 0
    """Whole maps sent again because the centre could not apply a delta (it asked for them)."""
    acks_lost: int = 0
    """Centre-to-robot acknowledgements (and requests for a whole map) lost."""
    bytes_lost: int = 0
    bytes_resent: int = 0
    centre_restarts: int = 0
    iou: list[float] = field(default_factory=list)
    grids_counted: bool = True
    """The int8-grid baselines (:data:`GRID_BASELINE_FIELDS`) and the other transmission mode's sparse
    bytes were counted; False: they were not, and the record leaves them empty."""
    mode: TransmissionMode = "delta"
    """The mode the messages were sent in (its sparse bytes are counted either way)."""

    def as_measures(self) -> dict[str, float | int | None]:
        """Flat fields for an episode record."""
        iou = np.asarray(self.iou) if self.iou else np.ones(1)
        counts: dict[str, float | int | None] = {
            k: v for k, v in asdict(self).items() if k not in ("iou", "grids_counted", "mode")
        }
        if not self.grids_counted:
            counts.update(dict.fromkeys(GRID_BASELINE_FIELDS))
            counts["bytes_sparse" if self.mode == "delta" else "bytes_sparse_delta"] = None
        return {
            **counts,
            "reconstruction_iou_min": round(float(iou.min()), 6),
            "reconstruction_iou_mean": round(float(iou.mean()), 6),
        }


@dataclass(frozen=True)
class LinkStatus:
    """What the centre knows of its robots after a round (read by the mission and drawn in a GIF)."""

    heard: NDArray[np.bool_]
    """``(n_robots,) bool``: the robot's map of this round reached the centre."""
    assignable: NDArray[np.bool_]
    """``(n_robots,) bool``: heard within the silence limit and at a known cell: the centre assigns to it."""
    positions_rc: NDArray[np.int32]
    """``(n_robots, 2) int32`` each robot's cell in its last message that arrived ((-1, -1): none since
    the centre started)."""
