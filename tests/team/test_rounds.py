"""The centre's rounds without any middleware: acknowledgements, whole-map requests, repeats and late
answers, timeouts on either clock, lost robots and their return."""

from __future__ import annotations

from mrexplore.team.rounds import Admit, Reply, RoundCollector


def test_a_round_closes_when_everyone_answered_and_says_what_each_message_was() -> None:
    rounds = RoundCollector(3, timeout=0.5, ask_again=0.2, lost_after=5.0)
    rounds.open(4, {0, 1, 2}, now=10.0)
    assert rounds.admit(0, 4, is_delta=True) is Admit.NEW
    assert rounds.take(0, "m0", now=10.1) is Reply.ACK
    assert rounds.admit(0, 4, is_delta=True) is Admit.REPEAT  # asked again before the answer arrived
    assert rounds.admit(1, 3, is_delta=True) is Admit.LATE  # an earlier round's answer
    assert rounds.admit(1, 4, is_delta=True) is Admit.NEW
    assert rounds.take(1, None, now=10.1) is Reply.WHOLE_MAP  # no base for the delta: the whole map
    assert rounds.admit(1, 4, is_delta=True) is Admit.REPEAT  # the refused delta once more
    assert rounds.admit(1, 4, is_delta=False) is Admit.RESENT
    assert rounds.take(1, "m1", now=10.2) is Reply.ACK
    assert not rounds.complete(10.2)  # robot 2 still to answer, within the timeout
    assert rounds.take(2, "m2", now=10.3) is Reply.ACK
    assert rounds.complete(10.3)
    assert rounds.close() == {0: "m0", 1: "m1", 2: "m2"}
    assert rounds.admit(2, 4, is_delta=True) is Admit.LATE  # closed


def test_a_round_times_out_on_the_clock_it_is_given_unless_it_must_wait() -> None:
    for timeout, now in ((0.5, 10.5), (1, 8)):  # seconds of a robot's clock, or simulator rounds
        rounds = RoundCollector(2, timeout=timeout, ask_again=timeout, lost_after=3 * timeout)
        rounds.open(1, {0, 1}, now=now - timeout)
        rounds.take(0, "m0", now=now - timeout)
        assert rounds.complete(now) and not rounds.complete(now, wait=True)
        assert rounds.close() == {0: "m0"}


def test_asking_again_every_ask_again() -> None:
    rounds = RoundCollector(1, timeout=5.0, ask_again=0.5, lost_after=5.0)
    rounds.open(1, {0}, now=0.0)
    asks = [t for t in (0.1, 0.4, 0.5, 0.7, 1.0, 1.2) if rounds.due_to_ask(t)]
    assert asks == [0.5, 1.0]


def test_a_silent_robot_is_lost_once_no_longer_waited_for_and_rejoins_when_it_speaks() -> None:
    rounds = RoundCollector(2, timeout=0.5, ask_again=0.5, lost_after=5.0)
    rounds.open(1, {0, 1}, now=0.0)
    rounds.take(0, "a", now=0.0)
    rounds.take(1, "b", now=0.0)
    rounds.close()
    assert rounds.mark_lost(4.0) == []
    rounds.open(2, {0, 1}, now=5.5)
    rounds.take(0, "a", now=5.5)
    assert rounds.mark_lost(6.0) == [(1, 6.0)]  # silent 6 s > 5 s
    assert rounds.mark_lost(9.0) == []  # said once
    assert rounds.complete(5.6, wait=True)  # the lost robot is not waited for
    rounds.close()
    rounds.open(3, {0, 1}, now=10.0)
    rounds.take(1, "b again", now=10.1)
    assert rounds.lost == set()  # it spoke: it rejoins
    assert not rounds.complete(10.1, wait=True)  # and is waited for again (robot 0 still to answer)


def test_a_robot_never_heard_is_not_lost() -> None:
    rounds = RoundCollector(2, timeout=0.5, ask_again=0.5, lost_after=1.0)
    assert rounds.mark_lost(100.0) == []
