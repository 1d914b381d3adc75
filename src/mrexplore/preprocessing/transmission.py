"""One communication round between the robots and the centre, with the episode's byte accounting.

Each round every robot closes its own grid, builds its sparse frontier map and encodes it twice: whole
(the paper's message) and as a delta against the map the centre acknowledged last (RACER-style
incremental sharing). The centre decodes the stream chosen by ``mode`` and rebuilds the team grid that
every strategy plans on. For the same rounds the accounting counts what the paper's baseline would send,
each robot's occupancy grid as int8 per cell over the bounding box of its known cells (a ROS
OccupancyGrid's data), raw and zlib-compressed, and the free-space IoU of the centre's grid against the
union of the robots' own beliefs.
"""

from __future__ import annotations

import time
import zlib
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from mrexplore.boxes import mask_box
from mrexplore.config import PreprocessConfig, SensorConfig
from mrexplore.preprocessing.frontiers import close_unknown_holes, closing_reach
from mrexplore.preprocessing.reconstruction import CentreMap, free_iou
from mrexplore.preprocessing.sparse_codec import HEADER, decode, encode
from mrexplore.preprocessing.sparse_map import FULL, SparseFrontierMap, changed_since, sparse_frontier_map
from mrexplore.sim.belief import Belief, classify
from mrexplore.types import CellState, StateGrid

__all__ = ["TeamLink", "RobotSender", "TransmissionTotals", "occupancy_grid_bytes", "TRANSMISSION_MODES"]

TransmissionMode = Literal["delta", "full"]
TRANSMISSION_MODES: tuple[TransmissionMode, ...] = ("delta", "full")
_ROS_VALUES = {CellState.FREE: 0, CellState.OCCUPIED: 100, CellState.UNKNOWN: -1}


def occupancy_grid_bytes(state: StateGrid) -> tuple[int, int]:
    """Bytes of the baseline message of one grid: int8 cells (ROS: -1 unknown, 0 free, 100 occupied) over
    the bounding box of known cells plus the same header as a frontier message; raw and zlib level 6.

    Examples
    --------
    >>> g = np.full((10, 10), CellState.UNKNOWN, np.uint8); g[2:4, 3:8] = CellState.FREE
    >>> raw, packed = occupancy_grid_bytes(g)
    >>> raw - HEADER.size  # a 2 x 5 box
    10
    """
    known = mask_box(state != CellState.UNKNOWN)
    if known is None:
        return HEADER.size, HEADER.size
    box = state[known[0] : known[1], known[2] : known[3]]
    lut = np.zeros(len(CellState), dtype=np.int8)
    for s, v in _ROS_VALUES.items():
        lut[s] = v
    data = lut[box].tobytes()
    return HEADER.size + len(data), HEADER.size + len(zlib.compress(data, 6))


class RobotSender:
    """One robot's side of the link: builds its message each round and remembers what the centre holds.

    :meth:`send` gives the whole map (the paper's message) and the incremental one: the delta against the
    last acknowledged map, or the whole map where that is shorter (the first round, or after most of the
    boundary moved).
    """

    def __init__(self, robot: int, shape: tuple[int, int]) -> None:
        self.robot = robot
        self._acked = np.zeros(shape, dtype=np.uint8)
        self._acked_round = FULL

    def send(
        self, closed: StateGrid, round_: int, position_rc: tuple[int, int], window: tuple[slice, slice] | None = None
    ) -> tuple[bytes, bytes]:
        """``(full, incremental)`` message bytes of this round from the robot's closed grid.

        ``window``: where ``closed`` lies in the map when it is a window of the robot's grid (holding every
        free cell with a one-cell margin, and growing from round to round); None: ``closed`` is the map."""
        if window is None:
            window = (slice(0, closed.shape[0]), slice(0, closed.shape[1]))
        origin = (window[0].start, window[1].start)
        full = sparse_frontier_map(closed, self.robot, round_, position_rc, origin, self._acked.shape)
        full_bytes = encode(full)
        incremental = full_bytes
        if self._acked_round != FULL:
            # The acknowledged map's cells lie in an earlier, smaller window: comparing in this one suffices.
            delta_bytes = encode(changed_since(self._acked, full, self._acked_round, window))
            if len(delta_bytes) < len(full_bytes):
                incremental = delta_bytes
        return full_bytes, incremental

    def acknowledged(self, message: SparseFrontierMap) -> None:
        """The centre confirmed this round's message: later deltas apply to it."""
        if not message.is_delta:
            self._acked.fill(0)
        np.put(self._acked, message.cells, message.codes)
        self._acked_round = message.round


@dataclass
class TransmissionTotals:
    """Bytes sent over an episode, per encoding, and how faithful the centre's grid was."""

    rounds: int = 0
    bytes_grid: int = 0
    bytes_grid_zlib: int = 0
    bytes_sparse: int = 0
    bytes_sparse_delta: int = 0
    iou: list[float] = field(default_factory=list)

    def as_measures(self) -> dict[str, float | int]:
        """Flat fields for an episode record."""
        iou = np.asarray(self.iou) if self.iou else np.ones(1)
        return {
            "rounds": self.rounds,
            "bytes_grid": self.bytes_grid,
            "bytes_grid_zlib": self.bytes_grid_zlib,
            "bytes_sparse": self.bytes_sparse,
            "bytes_sparse_delta": self.bytes_sparse_delta,
            "reconstruction_iou_min": round(float(iou.min()), 6),
            "reconstruction_iou_mean": round(float(iou.mean()), 6),
        }


class TeamLink:
    """The robots' senders and the centre's receiver for one episode.

    Parameters
    ----------
    mode:
        ``"delta"`` (default): the centre rebuilds from the incremental stream; ``"full"``: from whole
        maps. Both give the same grid; bytes of both are counted either way.
    """

    def __init__(
        self,
        n_robots: int,
        shape: tuple[int, int],
        preprocess: PreprocessConfig,
        sensor: SensorConfig,
        mode: TransmissionMode = "delta",
    ) -> None:
        self.preprocess = preprocess
        self.sensor = sensor
        self.mode = mode
        self.centre = CentreMap(n_robots, shape, preprocess.closing_size_cells)
        self.totals = TransmissionTotals()
        self.senders = [RobotSender(i, shape) for i in range(n_robots)]
        self.robot_ms = 0.0
        """Milliseconds the last round spent on the robots' side (their closing and encoding, which run on
        the robots in a real team, and the byte accounting), as opposed to the centre's decoding and
        rebuilding."""

    def exchange(self, beliefs: Sequence[Belief], positions_rc: NDArray[np.integer]) -> StateGrid:
        """Run one round: every robot sends, the centre rebuilds; returns the centre's ``(H, W) uint8`` grid."""
        r = self.totals.rounds
        team_free = np.zeros(self.centre.shape, dtype=bool)
        robot_s = 0.0
        # A robot works on the box of its observed cells, grown by the closing's reach plus one cell: the
        # closing, the codes and the seeds there equal those of the whole grid (nothing beyond is free).
        margin = closing_reach(self.preprocess.closing_size_cells) + 1
        for i, belief in enumerate(beliefs):
            t0 = time.perf_counter()
            window = belief.window(margin)
            own = classify(belief.log_odds[window], belief.observed[window], self.sensor)
            team_free[window] |= own == CellState.FREE
            closed = close_unknown_holes(own, self.preprocess.closing_size_cells)
            pos = (int(positions_rc[i][0]), int(positions_rc[i][1]))
            full_bytes, delta_bytes = self.senders[i].send(closed, r, pos, window)
            raw, packed = occupancy_grid_bytes(own)
            self.totals.bytes_grid += raw
            self.totals.bytes_grid_zlib += packed
            self.totals.bytes_sparse += len(full_bytes)
            self.totals.bytes_sparse_delta += len(delta_bytes)
            robot_s += time.perf_counter() - t0
            received = decode(delta_bytes if self.mode == "delta" else full_bytes)
            self.centre.receive(received)
            # The simulated link is reliable: the centre acknowledges every message at once.
            self.senders[i].acknowledged(received)
        state = self.centre.state()
        t0 = time.perf_counter()
        self.totals.iou.append(free_iou(state == CellState.FREE, team_free))
        self.robot_ms = (robot_s + time.perf_counter() - t0) * 1e3  # the IoU is accounting too
        self.totals.rounds += 1
        return state
