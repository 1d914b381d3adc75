"""The centre's side of a round, whatever carries the messages and whatever the clock: whom it waits for,
what came in, whether each message is acknowledged or the whole map is asked for, when to ask again, when
the round closes, and which robots are lost.

The simulator's link (:class:`~mrexplore.preprocessing.link.TeamLink`) drives it with a clock in rounds and
closes each round at once; ``mrexplore ros2 centre`` drives it with the node's clock in seconds (sim time
where ``use_sim_time`` is set) and closes a round when every robot it waits for answered or at its timeout.

Examples
--------
>>> rounds = RoundCollector(2, timeout=0.5, ask_again=0.2, lost_after=5.0)
>>> rounds.open(7, expected={0, 1}, now=0.0)
>>> rounds.admit(0, 7, is_delta=True), rounds.take(0, "map of robot 0", now=0.1)
(<Admit.NEW: 'new'>, <Reply.ACK: 'ack'>)
>>> rounds.admit(0, 7, is_delta=True), rounds.admit(1, 6, is_delta=False)  # robot 0 again; a closed round
(<Admit.REPEAT: 'repeat'>, <Admit.LATE: 'late'>)
>>> rounds.take(1, None, now=0.2)  # a delta on a base the centre lacks: ask for the whole map
<Reply.WHOLE_MAP: 'whole_map'>
>>> rounds.admit(1, 7, is_delta=False), rounds.take(1, "map of robot 1", now=0.3), rounds.complete(0.3)
(<Admit.RESENT: 'resent'>, <Reply.ACK: 'ack'>, True)
>>> rounds.close()
{0: 'map of robot 0', 1: 'map of robot 1'}
"""

from __future__ import annotations

import enum
from dataclasses import dataclass, field
from typing import Any

__all__ = ["RoundCollector", "OpenRound", "Admit", "Reply"]


class Admit(enum.Enum):
    """What a robot's message is to the round being collected."""

    NEW = "new"
    """The robot's first answer of the round: decode it and :meth:`RoundCollector.take` it."""
    RESENT = "resent"
    """The whole map the centre asked for: decode it and take it."""
    REPEAT = "repeat"
    """An answer already in, or the refused delta sent again before the request arrived: dropped."""
    LATE = "late"
    """A round already closed, or a robot the round does not wait for: dropped."""


class Reply(enum.Enum):
    """The centre's answer to a message it took."""

    ACK = "ack"
    """The centre holds it: the robot's later deltas apply to it."""
    WHOLE_MAP = "whole_map"
    """A delta on a base the centre lacks: send the whole map."""


@dataclass
class OpenRound:
    """The round being collected."""

    number: int
    expected: set[int]
    """The robots it waits for."""
    deadline: float
    """It closes at this time with what came in (clock units)."""
    inbox: dict[int, Any] = field(default_factory=dict)
    """Each robot's decoded message."""
    asked_whole: set[int] = field(default_factory=set)
    next_ask: float = 0.0
    last_in: float | None = None
    """When its last message came in (None: none yet)."""


class RoundCollector:
    """One centre's rounds (module docstring).

    Parameters
    ----------
    n_robots:
        The team's size.
    timeout:
        A round closes this long after it opened, with whatever came in (clock units).
    ask_again:
        A round still waiting is asked for again this often (a robot may still be starting).
    lost_after:
        A robot heard before and silent this long is lost: rounds stop waiting for it until it speaks again.
        A robot never heard is not lost (the centre may have started first).
    """

    def __init__(self, n_robots: int, timeout: float, ask_again: float, lost_after: float) -> None:
        self.n_robots = n_robots
        self.timeout, self.ask_again, self.lost_after = timeout, ask_again, lost_after
        self.current: OpenRound | None = None
        self.heard_at: list[float | None] = [None] * n_robots
        """When each robot's last message was taken (None: never)."""
        self.lost: set[int] = set()

    def open(self, number: int, expected: set[int], now: float) -> None:
        """Start collecting round ``number``, waiting for the ``expected`` robots; ask it at once."""
        self.current = OpenRound(number, set(expected), now + self.timeout, next_ask=now + self.ask_again)

    def due_to_ask(self, now: float) -> bool:
        """Whether the open round should be asked for again now (and note that it is)."""
        r = self.current
        if r is None or now < r.next_ask:
            return False
        r.next_ask = now + self.ask_again
        return True

    def admit(self, robot: int, round_: int, is_delta: bool) -> Admit:
        """Whether robot ``robot``'s message of round ``round_`` is to be taken."""
        r = self.current
        if r is None or round_ != r.number or robot not in r.expected:
            return Admit.LATE
        if robot in r.inbox or (robot in r.asked_whole and is_delta):
            return Admit.REPEAT
        return Admit.RESENT if robot in r.asked_whole else Admit.NEW

    def take(self, robot: int, decoded: Any | None, now: float) -> Reply:
        """Take an admitted message, ``decoded`` (None: a delta on a base the centre lacks); returns the
        reply to send the robot."""
        r = self.current
        assert r is not None, "take() needs an open round"
        if decoded is None:
            r.asked_whole.add(robot)
            return Reply.WHOLE_MAP
        r.inbox[robot] = decoded
        r.last_in = now
        self.heard_at[robot] = now
        self.lost.discard(robot)
        return Reply.ACK

    def complete(self, now: float, wait: bool = False) -> bool:
        """Whether the open round can close: every robot it waits for (lost ones aside) answered, or its
        timeout passed (unless ``wait``: a round that must hear everyone, as in lockstep)."""
        r = self.current
        if r is None:
            return False
        return r.expected - self.lost <= set(r.inbox) or (not wait and now >= r.deadline)

    def close(self) -> dict[int, Any]:
        """End the open round; returns its messages by robot, in robot order."""
        r = self.current
        assert r is not None, "close() needs an open round"
        self.current = None
        return {i: r.inbox[i] for i in sorted(r.inbox)}

    def mark_lost(self, now: float) -> list[tuple[int, float]]:
        """Robots heard before and silent for more than ``lost_after`` become lost; returns each newly lost
        robot with how long it was silent."""
        newly = []
        for i, at in enumerate(self.heard_at):
            if at is not None and i not in self.lost and now - at > self.lost_after:
                self.lost.add(i)
                newly.append((i, now - at))
        return newly
