"""The two ends of the team's link as plain objects, whatever carries the bytes (the in-process link of the
simulator, ROS 2 topics, a lossy relay): a robot's on-board work (:class:`RobotAgent`) and the centre's
receiving end (:class:`TeamCentre`)."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from mrexplore.config import PreprocessConfig, SensorConfig
from mrexplore.maps.boxes import mask_box
from mrexplore.preprocessing.frontiers import Frontiers, closing_reach
from mrexplore.preprocessing.onboard import OnBoardGrid
from mrexplore.preprocessing.reconstruction import CentreMap
from mrexplore.preprocessing.sparse_map import SparseFrontierMap
from mrexplore.preprocessing.transmission import LinkStatus, Outgoing, RobotSender
from mrexplore.sim.belief import Belief
from mrexplore.types import CellState, StateGrid

__all__ = ["RobotAgent", "TeamCentre"]


class RobotAgent:
    """One robot's on-board work: its grid kept up to date (from the simulator's belief, or from its own
    published map as three states), this round's sparse frontier message, and its side of the protocol (a
    delta against what the centre acknowledged; the whole map where the centre may lack the base or asks
    for it).

    Examples
    --------
    >>> robot = RobotAgent(0, (6, 6), PreprocessConfig(closing_size_cells=1), SensorConfig())
    >>> state = np.full((6, 6), CellState.UNKNOWN, np.uint8); state[1:4, 1:4] = CellState.FREE
    >>> robot.sense_state(state)
    >>> out = robot.compose(0, (2, 2), robot.window())
    >>> message = out.incremental_message()  # what out.incremental() encodes
    >>> message.is_delta, message.position_rc, len(message.cells)
    (False, (2, 2), 8)
    """

    def __init__(self, robot: int, shape: tuple[int, int], preprocess: PreprocessConfig, sensor: SensorConfig) -> None:
        self.robot = robot
        self.preprocess = preprocess
        self.grid = OnBoardGrid(shape, preprocess.closing_size_cells, sensor)
        """The robot's grid, closed and coded, kept up to date where it changed."""
        self.sender = RobotSender(robot, shape)

    @staticmethod
    def warm_up(preprocess: PreprocessConfig) -> None:
        """One message of a small room, both ways it is encoded: a robot node that does this before it joins
        the team compiles its kernels while nobody waits for it."""
        agent = RobotAgent(0, (16, 16), preprocess, SensorConfig())
        state = np.full((16, 16), CellState.UNKNOWN, np.uint8)
        state[2:10, 2:10] = CellState.FREE
        agent.sense_state(state)
        agent.compose(0, (5, 5), agent.window()).both()

    def sense(self, belief: Belief, free_count: NDArray[np.uint16] | None = None) -> None:
        """Bring the grid in line with the robot's belief (``free_count``: as :meth:`OnBoardGrid.update`)."""
        self.sender.note_changed(self.grid.update(belief, free_count))

    def sense_state(self, state: StateGrid) -> None:
        """Bring the grid in line with the robot's own map, ``(H, W) uint8`` states in the team's grid."""
        self.sender.note_changed(self.grid.update_state(state))

    def window(self) -> tuple[slice, slice]:
        """The box of the robot's known cells grown by the closing's reach plus one cell (a message covers
        it: the closing, the codes and the seeds there equal those of the whole grid); the whole grid where
        nothing is known yet."""
        shape = self.grid.state.shape
        box = mask_box(self.grid.state != CellState.UNKNOWN) or (0, shape[0], 0, shape[1])
        m = closing_reach(self.preprocess.closing_size_cells) + 1
        return slice(max(0, box[0] - m), min(shape[0], box[1] + m)), slice(
            max(0, box[2] - m), min(shape[1], box[3] + m)
        )

    def compose(self, round_: int, position_rc: tuple[int, int], window: tuple[slice, slice]) -> Outgoing:
        """This round's messages (whole and incremental, each encoded when asked for), ``window`` holding
        every known cell with the closing's margin (:meth:`window`, or the belief's own)."""
        return self.sender.send_onboard(self.grid, round_, position_rc, window)

    def acknowledged(self, message: SparseFrontierMap) -> None:
        """The centre holds ``message``: later deltas apply to it."""
        self.sender.acknowledged(message)

    def grid_delta_bytes(self) -> int:
        """Table II's generic competitor: the int8 grid's changed cells since the last acknowledgement."""
        return self.sender.onboard_grid_delta_bytes(self.grid)


class TeamCentre:
    """The centre's receiving end: the robots' maps merged into the team's grid, whom it heard in which
    round and where, and a restart that forgets it all.

    A delta whose base the centre lacks is not applied (:meth:`read` gives None, :meth:`accepts` says no);
    the transport then asks the robot for its whole map. A robot is assignable while the centre heard it
    within ``silence_rounds`` rounds and knows its cell.
    """

    def __init__(self, n_robots: int, shape: tuple[int, int], closing_size_cells: int, silence_rounds: int) -> None:
        self.map = CentreMap(n_robots, shape, closing_size_cells)
        self.silence_rounds = silence_rounds
        self.last_heard = np.full(n_robots, -1, dtype=np.int64)
        """``(n_robots,) int64`` the round of each robot's last message that arrived (-1: none)."""
        self.positions_rc = np.full((n_robots, 2), -1, dtype=np.int32)
        """``(n_robots, 2) int32`` each robot's cell in its last message that arrived ((-1, -1): none)."""

    def accepts(self, message: SparseFrontierMap) -> bool:
        """Whether the centre can apply ``message`` (a whole map, or a delta on a base it holds)."""
        return self.map.accepts(message)

    def read(self, data: bytes) -> SparseFrontierMap | None:
        """Decode a message's bytes: a whole map, or a delta against the base the centre holds; None for a
        delta on a base it lacks (the transport asks the robot for its whole map). Bad bytes raise
        :class:`~mrexplore.preprocessing.sparse_codec.CodecError`."""
        return self.map.read(data)

    def receive(self, message: SparseFrontierMap, round_: int) -> None:
        """Apply a message it accepts, heard in ``round_``."""
        self.map.receive(message)
        self.last_heard[message.robot] = round_
        self.positions_rc[message.robot] = message.position_rc

    def restart(self, round_: int) -> None:
        """Lose everything: the robots' maps and bases, their cells, whom it heard (as of ``round_``)."""
        n = len(self.last_heard)
        self.map = CentreMap(n, self.map.shape, self.map.closing_size_cells)
        self.last_heard[:] = round_ - 1
        self.positions_rc[:] = -1

    def status(self, round_: int) -> LinkStatus:
        """Whom the centre heard in ``round_``, whom it may assign to, and where they are."""
        heard = self.last_heard == round_
        known = self.positions_rc[:, 0] >= 0
        assignable = (round_ - self.last_heard < self.silence_rounds) & known
        return LinkStatus(heard, assignable, self.positions_rc.copy())

    def state(self) -> StateGrid:
        """``(H, W) uint8`` the team's grid, closed."""
        return self.map.state()

    def frontiers(self) -> Frontiers:
        """The team grid's frontiers as the centre keeps them."""
        return self.map.frontiers()
