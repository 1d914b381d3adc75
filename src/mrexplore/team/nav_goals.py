"""A robot's goal as a navigation stack reports on it, read without trusting any clock but the stack's own.

A goal sent on Nav2's ``goal_pose`` topic gets an id the centre never sees: bt_navigator forwards it to its
own ``navigate_to_pose`` action server (``NavigateToPoseNavigator::onGoalPoseReceived``), and rcl_action
re-stamps each accepted goal with the *server's* clock (``rcl_action_accept_new_goal``). A robot on sim time,
or one whose clock lags the centre's, stamps its goals at times that say nothing about when the centre sent
them. Nav2's simple action server aborts the running goal when a newer one preempts it
(``SimpleActionServer::accept_pending_goal``), and its status array lists every goal it still holds, the
terminal ones until rcl_action's result timeout expires them. docs/ros2.md cites the files.

So the tracker never compares a goal's stamp with the centre's clock:

- an id seen before the centre's goal was sent belongs to an earlier goal; its status is ignored (the abort
  of a goal the centre's own new goal preempted is no abort);
- every id first seen after the goal was sent is a copy of it (the centre sends a goal again while the
  robot lists no new id: a message published before the robot's subscription matched is lost), unless the
  stack stamped it no later than a goal it listed before the send: that goal is someone else's, set
  aside in :attr:`GoalTracker.foreign`;
- the goal's state is that of its newest copy, ordered by the stamps the stack gave them (one clock, the
  stack's own); an older copy's abort is the stack preempting it with the newer;
- the newest copy's abort counts only once every copy sent has shown up, or ``settle`` after the last send:
  a copy still on its way would preempt it.

Examples
--------
>>> track = GoalTracker(resend_after=1.0, settle=2.0)
>>> track.status([(b"old", 50.0, EXECUTING)], now=0.0)  # a goal from before: known, ignored
>>> track.sent(now=10.0)
>>> track.status([(b"old", 50.0, ABORTED), (b"new", 51.0, EXECUTING)], now=10.1)  # preempted, then ours
'active'
>>> track.status([(b"old", 50.0, ABORTED), (b"new", 51.0, ABORTED)], now=12.0)  # ours aborted for real
'aborted'
>>> track.sent(now=20.0); track.resent(now=21.0)  # sent twice: one copy may still be on its way
>>> track.status([(b"new2", 60.0, ABORTED)], now=21.5) is None, track.poll(now=24.0)  # settled: an abort
(True, 'aborted')
"""

from __future__ import annotations

from collections.abc import Iterable

__all__ = ["GoalTracker", "ACCEPTED", "EXECUTING", "CANCELING", "SUCCEEDED", "CANCELED", "ABORTED"]

ACCEPTED, EXECUTING, CANCELING, SUCCEEDED, CANCELED, ABORTED = 1, 2, 3, 4, 5, 6
"""action_msgs/GoalStatus's codes."""
_STATE = {ACCEPTED: "active", EXECUTING: "active", CANCELING: "active", SUCCEEDED: "reached"}
_STATE.update({CANCELED: "aborted", ABORTED: "aborted"})


class GoalTracker:
    """One robot's current goal at its navigation stack (module docstring).

    Parameters
    ----------
    resend_after:
        The goal is sent again when no copy of it has shown up this long after the last send (clock units).
    settle:
        The newest copy's abort counts this long after the last send even where an earlier send never
        showed up (it was lost).
    """

    def __init__(self, resend_after: float, settle: float) -> None:
        self.resend_after, self.settle = resend_after, settle
        self.known: set[bytes] = set()
        """Every id the stack listed before the current goal was sent."""
        self.latest = float("-inf")
        """The latest stamp (the stack's clock) of those ids: a copy of a goal sent since is stamped later."""
        self.foreign: list[bytes] = []
        """Ids that cannot be the centre's (stamped before its goal could have arrived), as they come."""
        self.copies: dict[bytes, tuple[float, int]] = {}
        """The current goal's copies at the stack: id -> (the stack's stamp, latest status code)."""
        self.sends = 0
        """Times the current goal was sent (0: no goal)."""
        self.last_send = 0.0
        self.state: str | None = None
        """The current goal's state as last reported: ``active``, ``reached``, ``aborted`` (None: no word yet)."""

    def _forget_copies(self) -> None:
        if self.copies:
            self.latest = max(self.latest, *(stamp for stamp, _ in self.copies.values()))
        self.known.update(self.copies)

    def sent(self, now: float) -> None:
        """A new goal went out: whatever the stack listed so far belongs to earlier goals."""
        self._forget_copies()
        self.copies, self.sends, self.last_send, self.state = {}, 1, now, None

    def resent(self, now: float) -> None:
        """The current goal went out once more."""
        self.sends += 1
        self.last_send = now

    def due_to_resend(self, now: float) -> bool:
        """Whether the goal should go out again: sent, no copy listed yet, ``resend_after`` passed."""
        return self.sends > 0 and not self.copies and now - self.last_send >= self.resend_after

    def status(self, listed: Iterable[tuple[bytes, float, int]], now: float) -> str | None:
        """Read one status array, ``(id, the stack's stamp in seconds, status code)`` per goal; returns the
        current goal's new state where it changed (``active``, ``reached``, ``aborted``), else None."""
        for gid, stamp, code in listed:
            if gid in self.known:
                continue
            if gid in self.copies:
                self.copies[gid] = (stamp, code)
            elif self.sends == 0 or stamp <= self.latest:
                self.known.add(gid)  # listed while the centre had no goal out, or stamped too early: not ours
                self.latest = max(self.latest, stamp) if self.sends == 0 else self.latest
                if self.sends:
                    self.foreign.append(gid)
            else:
                self.copies[gid] = (stamp, code)
        return self.poll(now)

    def poll(self, now: float) -> str | None:
        """The current goal's new state where it changed since last said; an abort held back for a copy still
        on its way counts once ``settle`` passed, with no new status needed."""
        if not self.copies:
            return None
        newest = max(self.copies.values(), key=lambda v: v[0])
        state = _STATE.get(newest[1])
        if state == "aborted" and len(self.copies) < self.sends and now - self.last_send < self.settle:
            return None  # a copy still on its way preempted this one
        if state is None or state == self.state:
            return None
        self.state = state
        return state
