"""A goal's state as Nav2's status array reports it, read on the stack's own stamps only: sim time, clock
skew, preemption of the centre's earlier goal, copies of a resent goal, a stranger's goal."""

from __future__ import annotations

from mrexplore.team.nav_goals import ABORTED, EXECUTING, SUCCEEDED, GoalTracker


def test_the_goal_is_tracked_whatever_the_stacks_clock_says() -> None:
    # The robot runs on sim time: its stamps (7 s) are far behind the centre's clock (1000 s).
    track = GoalTracker(resend_after=1.0, settle=2.0)
    track.sent(now=1000.0)
    assert track.status([(b"a", 7.0, EXECUTING)], now=1000.1) == "active"
    assert track.status([(b"a", 7.0, EXECUTING)], now=1000.2) is None  # no change, nothing said
    assert track.status([(b"a", 7.0, SUCCEEDED)], now=1001.0) == "reached"


def test_the_abort_of_a_goal_the_centre_replaced_is_no_abort() -> None:
    track = GoalTracker(resend_after=1.0, settle=2.0)
    track.sent(now=0.0)
    track.status([(b"a", 7.0, EXECUTING)], now=0.1)
    track.sent(now=5.0)  # a new goal: Nav2 aborts "a" as it takes "b"
    assert track.status([(b"a", 7.0, ABORTED)], now=5.05) is None
    assert track.status([(b"a", 7.0, ABORTED), (b"b", 12.0, EXECUTING)], now=5.1) == "active"
    assert track.status([(b"a", 7.0, ABORTED), (b"b", 12.0, ABORTED)], now=8.0) == "aborted"  # "b" itself


def test_copies_of_a_resent_goal_the_newest_speaks_for_it() -> None:
    track = GoalTracker(resend_after=1.0, settle=2.0)
    track.sent(now=0.0)
    assert not track.due_to_resend(0.5) and track.due_to_resend(1.0)  # nothing listed after 1 s
    track.resent(now=1.0)
    # Both copies arrived: the second preempted the first, which Nav2 aborted.
    listed = [(b"c1", 3.0, ABORTED), (b"c2", 3.1, EXECUTING)]
    assert track.status(listed, now=1.1) == "active"
    assert not track.due_to_resend(5.0)  # listed: never sent again


def test_an_abort_waits_for_a_copy_still_on_its_way_then_counts() -> None:
    track = GoalTracker(resend_after=1.0, settle=2.0)
    track.sent(now=0.0)
    track.resent(now=1.0)
    assert track.status([(b"c1", 3.0, ABORTED)], now=1.05) is None  # the second copy may preempt it
    assert track.poll(now=2.5) is None
    assert track.poll(now=3.0) == "aborted"  # the second copy was lost: a real abort


def test_a_strangers_goal_stamped_before_ours_could_arrive_is_set_aside() -> None:
    track = GoalTracker(resend_after=1.0, settle=2.0)
    track.sent(now=0.0)
    track.status([(b"ours", 20.0, EXECUTING)], now=0.1)
    track.sent(now=3.0)
    assert track.status([(b"stranger", 19.0, SUCCEEDED)], now=3.1) is None  # older than a goal we saw
    assert track.foreign == [b"stranger"]
    assert track.status([(b"next", 24.0, SUCCEEDED)], now=4.0) == "reached"


def test_a_restarted_centre_takes_goals_listed_before_its_first_send_as_earlier_ones() -> None:
    track = GoalTracker(resend_after=1.0, settle=2.0)
    assert track.status([(b"before", 40.0, EXECUTING)], now=0.0) is None
    track.sent(now=1.0)
    assert track.status([(b"before", 40.0, ABORTED)], now=1.1) is None  # preempted by ours
    assert track.status([(b"before", 40.0, ABORTED), (b"mine", 41.0, EXECUTING)], now=1.2) == "active"
