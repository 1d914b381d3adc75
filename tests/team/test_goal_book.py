"""The goal book's rules on a 6 x 6 grid: stood-on goals, blacklists, areas barred from one robot until
a time, moving on along a route, when a decision is due."""

from __future__ import annotations

import numpy as np

from mrexplore.team.goal_book import NO_ROUTE, GoalBook, decision_due


def test_moving_on_along_a_route_skips_refused_targets_and_uses_them_up() -> None:
    book = GoalBook(1, (6, 6))
    book.assign(0, np.array([0, 0]), np.array([[1, 1], [2, 2], [3, 3]], np.int32))
    assert book.next_target(0, lambda t: int(t[0]) == 2)
    assert book.goals[0].tolist() == [2, 2] and book.routes[0].tolist() == [[3, 3]]
    assert not book.next_target(0, lambda t: False)
    assert book.goals[0].tolist() == [2, 2]  # unchanged; the route is used up
    assert len(book.routes[0]) == 0
    book.drop(0)
    assert book.goals[0].tolist() == [-1, -1] and book.current(0) is NO_ROUTE


def test_blacklists_for_the_team_and_bars_for_one_robot_until_a_time() -> None:
    book = GoalBook(2, (6, 6))
    book.stood_on(np.array([0, 5]), still_frontier=False)
    book.stood_on(np.array([5, 0]), still_frontier=True)
    assert book.blacklist.sum() == 1 and book.blacklist[5, 0]
    book.blacklist_around(np.array([0, 0]), radius_cells=1)  # clipped at the border: 2 x 2
    assert book.blacklist[:2, :2].all() and book.blacklist.sum() == 5
    book.bar(1, np.array([3, 3]), radius_cells=1, until=10.0)
    assert book.barred(0, now=0.0) is None
    mask = book.barred(1, now=9.9)
    assert mask is not None and mask.sum() == 9 and mask[2:5, 2:5].all()
    assert book.barred(1, now=10.0) is None  # expired
    book.forget()
    assert not book.blacklist.any()


def test_a_decision_is_due_on_the_timer_or_when_asked() -> None:
    assert decision_due(now=10.0, last=0.0, replan=10.0, asked=False)
    assert not decision_due(now=9.0, last=0.0, replan=10.0, asked=False)
    assert decision_due(now=9.0, last=0.0, replan=10.0, asked=True)


def test_a_place_aborted_three_times_is_dropped_for_the_team_and_a_bar_covers_given_cells() -> None:
    book = GoalBook(2, (6, 6))
    assert book.strike(np.array([2, 2]), radius_cells=0, limit=3) == 0
    assert book.strike(np.array([2, 2]), radius_cells=1, limit=3) == 0  # (2, 2) twice, its neighbours once
    assert book.strike(np.array([2, 2]), radius_cells=0, limit=3) == 1
    assert np.argwhere(book.blacklist).tolist() == [[2, 2]]
    book.bar(0, np.array([0, 0]), radius_cells=0, until=5.0, cells=np.array([[5, 5], [4, 5]], np.int32))
    mask = book.barred(0, now=1.0)
    assert mask is not None and np.argwhere(mask).tolist() == [[0, 0], [4, 5], [5, 5]]
