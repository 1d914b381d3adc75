"""The simulator's transport between the robots and the centre: the in-process link of one episode, lossy
where the mission's faults say so, driving the same robot and centre objects a ROS 2 deployment runs
(:mod:`~mrexplore.preprocessing.agents`), and counting every byte for Table II."""

from __future__ import annotations

import time
from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from mrexplore.config import PreprocessConfig, SensorConfig
from mrexplore.preprocessing.agents import RobotAgent, TeamCentre
from mrexplore.preprocessing.frontiers import closing_reach
from mrexplore.preprocessing.reconstruction import CentreMap, free_iou
from mrexplore.preprocessing.transmission import (
    LinkStatus,
    Outgoing,
    TransmissionMode,
    TransmissionTotals,
    occupancy_grid_bytes,
)
from mrexplore.runtime.threads import map_threads
from mrexplore.sim.belief import Belief
from mrexplore.team.rounds import Reply, RoundCollector
from mrexplore.types import CellState, StateGrid

__all__ = ["TeamLink"]


class TeamLink:
    """The robots' senders and the centre's receiver for one episode, over a link that may lose messages.

    Parameters
    ----------
    mode:
        ``"delta"`` (default): the centre rebuilds from the incremental stream; ``"full"``: from whole
        maps. Both give the same grid; bytes of both are counted either way.
    message_loss:
        Probability that a message is lost, each way (robot to centre, and the centre's acknowledgement
        or request for a whole map back), drawn from ``rng``.
    count_grids:
        Count the int8-grid baselines of Table II too (False: their fields stay empty; nothing else
        changes, and a round on a large floor costs much less).

    The protocol under loss: a robot sends its delta against the last map the centre acknowledged to it.
    A robot whose last message got no acknowledgement cannot tell a lost message (the centre holds its
    base) from a lost acknowledgement (the centre is a round ahead), so it sends its whole map next. The
    centre never applies a delta to a base it lacks: it asks for the whole map and the robot resends it at
    once (the request and the resend may be lost too; then the robot tries again next round). That is how
    a restarted centre, which holds no base at all, gets every robot's map back.
    """

    def __init__(
        self,
        n_robots: int,
        shape: tuple[int, int],
        preprocess: PreprocessConfig,
        sensor: SensorConfig,
        mode: TransmissionMode = "delta",
        message_loss: float = 0.0,
        rng: np.random.Generator | None = None,
        silence_rounds: int = 3,
        count_grids: bool = True,
    ) -> None:
        self.preprocess = preprocess
        self.sensor = sensor
        self.mode = mode
        self.message_loss = message_loss
        self.silence_rounds = silence_rounds
        self._rng = rng if rng is not None else np.random.default_rng(0)
        self.team = TeamCentre(n_robots, shape, preprocess.closing_size_cells, silence_rounds)
        """The centre's receiving end."""
        self.rounds = RoundCollector(n_robots, timeout=1, ask_again=1, lost_after=silence_rounds)
        """The centre's side of each round, on a clock in rounds (a round here closes once every robot had
        its turn, as the ROS 2 centre's does on a clock in seconds)."""
        self.totals = TransmissionTotals(grids_counted=count_grids, mode=mode)
        self.robots = [RobotAgent(i, shape, preprocess, sensor) for i in range(n_robots)]
        """Each robot's on-board work: its grid kept up to date where its scans fell, its messages."""
        self.status = LinkStatus(np.zeros(n_robots, bool), np.ones(n_robots, bool), self.team.positions_rc.copy())
        self._free_count = np.zeros(shape, dtype=np.uint16)
        """Per cell, how many robots' own grids hold it free (their union is what the IoU compares with)."""
        self._grid_bytes: list[tuple[tuple[int, tuple[slice, slice]], tuple[int, int]] | None] = [None] * n_robots
        """Each robot's last :func:`occupancy_grid_bytes`, by its grid's state version and window: a robot
        whose grid did not change (driving through known space) would send the same grid again."""
        self.robot_ms = 0.0
        """Milliseconds the last round spent on the robots' side, all robots together: their grids' update,
        closing, codes and messages, which run on board in a real team."""
        self.robot_ms_each: list[float] = []
        """Milliseconds of on-board work of each robot that sent a map in the last round."""
        self.accounting_ms = 0.0
        """Milliseconds the last round spent on the episode's accounting: what the baselines would have sent
        (:class:`TransmissionTotals`) and the IoU; neither a robot nor the centre does this work."""

    @property
    def centre(self) -> CentreMap:
        """The centre's merged map."""
        return self.team.map

    def restart_centre(self) -> None:
        """The centre loses everything it held: the robots' maps and bases, their cells, whom it heard."""
        self.team.restart(self.totals.rounds)
        self.rounds = RoundCollector(len(self.robots), timeout=1, ask_again=1, lost_after=self.silence_rounds)
        self.totals.centre_restarts += 1

    def _lost(self) -> bool:
        return self.message_loss > 0 and bool(self._rng.random() < self.message_loss)

    def _send(self, data: bytes) -> bool:
        """One message over the link: whether it arrived."""
        self.totals.messages_sent += 1
        if self._lost():
            self.totals.messages_lost += 1
            self.totals.bytes_lost += len(data)
            return False
        return True

    def _deliver(self, i: int, data: bytes, out: Outgoing) -> None:
        """Robot i's message ``data`` of this round, with the whole-map request and resend when the centre
        lacks the delta's base, and the acknowledgement back."""
        if not self._send(data):
            return
        rounds, r = self.rounds, self.totals.rounds
        rounds.admit(i, r, is_delta=self.mode == "delta")  # the robot's first answer: new
        if rounds.take(i, self.team.read(data), now=r) is Reply.WHOLE_MAP:
            if self._lost():  # the centre's request for the whole map
                self.totals.acks_lost += 1
                return
            full = out.full_bytes()
            self.totals.messages_resent += 1
            self.totals.bytes_resent += len(full)
            if not self._send(full):
                return
            rounds.admit(i, r, is_delta=False)  # the whole map asked for
            reply = rounds.take(i, self.team.read(full), now=r)
            assert reply is Reply.ACK  # a whole map needs no base
        if self._lost():
            self.totals.acks_lost += 1
        else:
            self.robots[i].acknowledged(rounds.current.inbox[i])  # type: ignore[union-attr]

    def exchange(
        self,
        beliefs: Sequence[Belief],
        positions_rc: NDArray[np.integer],
        sending: NDArray[np.bool_] | None = None,
    ) -> StateGrid:
        """Run one round: every robot that can (``sending``, default all) sends, the centre rebuilds;
        returns the centre's ``(H, W) uint8`` grid and updates :attr:`status`."""
        r = self.totals.rounds
        self.rounds.open(r, set(range(len(beliefs))) if sending is None else set(map(int, np.flatnonzero(sending))), r)
        robot_s = accounting_s = 0.0
        self.robot_ms_each = []
        to_count: list[tuple[int, tuple[int, tuple[slice, slice]], StateGrid]] = []
        counted: list[int] = []  # robots whose grid bytes are known, kept from an earlier round or not
        sent: list[Outgoing] = []
        # A robot's message covers the box of its observed cells, grown by the closing's reach plus one
        # cell: the closing, the codes and the seeds there equal those of the whole grid (nothing beyond
        # is free).
        margin = closing_reach(self.preprocess.closing_size_cells) + 1
        for i, belief in enumerate(beliefs):
            t0 = time.perf_counter()
            robot = self.robots[i]
            robot.sense(belief, self._free_count)
            if sending is not None and not sending[i]:
                robot_s += time.perf_counter() - t0
                continue
            window = belief.window(margin)
            pos = (int(positions_rc[i][0]), int(positions_rc[i][1]))
            out = robot.compose(r, pos, window)
            data = out.incremental() if self.mode == "delta" else out.full_bytes()
            t1 = time.perf_counter()
            if self.totals.grids_counted:
                key = (robot.grid.state_version, window)
                cached = self._grid_bytes[i]
                if cached is None or cached[0] != key:
                    to_count.append((i, key, robot.grid.state[window]))
                else:
                    counted.append(i)
                self.totals.bytes_grid_delta_zlib += robot.grid_delta_bytes()
            sent.append(out)
            t2 = time.perf_counter()
            robot_s += t1 - t0
            accounting_s += t2 - t1
            self.robot_ms_each.append((t1 - t0) * 1e3)
            self._deliver(i, data, out)
        t0 = time.perf_counter()
        # What the other transmission mode would have sent, and the baseline grids, encoded on the threads
        # (zlib, the codec and the box's pass let go of the GIL): on a KTH floor the grids were a fifth of a
        # whole mission's time on one thread. Without the baselines, only what was sent is counted: the
        # whole map of a large floor is several ms to code, every round.
        if self.totals.grids_counted:
            for full_bytes, incremental in map_threads(Outgoing.both, sent):
                self.totals.bytes_sparse += len(full_bytes)
                self.totals.bytes_sparse_delta += len(incremental)
        else:
            for out in sent:
                if self.mode == "delta":
                    self.totals.bytes_sparse_delta += len(out.incremental())
                else:
                    self.totals.bytes_sparse += len(out.full_bytes())
        sizes = map_threads(lambda job: occupancy_grid_bytes(job[2]), to_count)
        for (i, key, _), counts in zip(to_count, sizes, strict=True):
            self._grid_bytes[i] = key, counts
            counted.append(i)
        for i in counted:
            raw, packed = self._grid_bytes[i][1]  # type: ignore[index]
            self.totals.bytes_grid += raw
            self.totals.bytes_grid_zlib += packed
        accounting_s += time.perf_counter() - t0
        for message in self.rounds.close().values():  # in robot order
            self.team.receive(message, r)
        state = self.team.state()
        t0 = time.perf_counter()
        self.totals.iou.append(free_iou(state == CellState.FREE, self._free_count > 0))
        self.robot_ms = robot_s * 1e3
        self.accounting_ms = (accounting_s + time.perf_counter() - t0) * 1e3
        self.status = self.team.status(r)
        self.totals.rounds += 1
        return state
