"""The team's goals between decisions, whatever the clock: each robot's goal and the route after it, the
cells no robot should be sent to again, the areas kept from one robot for a while, and when the team needs a
decision.

The simulator's mission (:class:`~mrexplore.mission.Mission`) keeps it on a clock in steps, the real team's
centre (:class:`~mrexplore.mission.centre.TeamPlanner`) on one in seconds; both apply the same rules:

- a goal a robot stood on that still borders unknown space is blacklisted for the whole team (its cell
  cannot be seen from where a robot can stand);
- an area around a goal may be blacklisted for the whole team (the simulator's watchdog and pathless goals)
  or barred from one robot until a time (the robot's navigation aborted it, as explore_lite's blacklist);
- a robot whose goal ended moves on to the first target of its route that the caller still accepts;
- a decision is due at least every ``replan`` and where a robot is left without a target, but not within
  ``min_replan`` of the last one for goals merely seen (driving on costs little; a decision costs the team).

Examples
--------
>>> book = GoalBook(2, (6, 6))
>>> book.assign(0, np.array([1, 1]), np.array([[2, 2], [4, 4]], np.int32))
>>> book.stood_on(np.array([1, 1]), still_frontier=True); bool(book.blacklist[1, 1])
True
>>> book.next_target(0, lambda t: t[0] != 2), book.goals[0].tolist()  # (2, 2) refused, (4, 4) taken
(True, [4, 4])
>>> book.bar(1, np.array([3, 3]), radius_cells=1, until=10.0)
>>> int(book.barred(1, now=5.0).sum()), book.barred(1, now=10.0)  # a 3 x 3 square, until t = 10
(9, None)
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from mrexplore.types import BoolGrid

__all__ = ["GoalBook", "KeepsGoals", "NO_GOAL", "NO_ROUTE", "decision_due"]

NO_GOAL = np.array([-1, -1], dtype=np.int32)
"""``(2,) int32`` the goal cell of a robot without one."""
NO_ROUTE = np.zeros((0, 2), dtype=np.int32)
"""``(0, 2) int32`` an empty route or path."""


def _box(goal: NDArray[np.integer], r: int) -> tuple[int, int, int, int]:
    g0, g1 = int(goal[0]), int(goal[1])
    return max(0, g0 - r), g0 + r + 1, max(0, g1 - r), g1 + r + 1


class GoalBook:
    """Each robot's goal and route, the team's blacklist and the areas barred from one robot (module
    docstring).

    Parameters
    ----------
    n_robots:
        The team's size.
    shape:
        The team grid's ``(H, W)``.
    """

    def __init__(self, n_robots: int, shape: tuple[int, int]) -> None:
        self.goals = np.tile(NO_GOAL, (n_robots, 1))
        """``(n_robots, 2) int32`` each robot's goal in the team grid ((-1, -1): none)."""
        self.routes: list[NDArray[np.int32]] = [NO_ROUTE] * n_robots
        """Each robot's targets after its goal, ``(k, 2) int32``."""
        self.blacklist = np.zeros(shape, dtype=bool)
        """``(H, W) bool`` cells no robot is sent to again."""
        self._barred: list[tuple[int, NDArray[np.int64], NDArray[np.int64], float]] = []
        """Cells kept from one robot: ``(robot, rows, cols, until)``."""
        self.strikes = np.zeros(shape, dtype=np.uint8)
        """``(H, W) uint8`` how many aborted goals' areas each cell lay in (:meth:`strike`)."""

    def assign(self, i: int, goal: NDArray[np.integer], route: NDArray[np.int32]) -> None:
        """Robot i's goal and the targets after it."""
        self.goals[i], self.routes[i] = goal, route

    def drop(self, i: int) -> None:
        """Robot i has no goal and no route."""
        self.goals[i] = NO_GOAL
        self.routes[i] = NO_ROUTE

    def next_target(self, i: int, take: Callable[[NDArray[np.int32]], bool]) -> bool:
        """Move robot i on to the first target of its route that ``take`` accepts (it may set the robot's
        path as it checks); the targets before it are used up. False, with the route used up, where ``take``
        accepts none (the goal is then left as it was)."""
        route = self.routes[i]
        while len(route):
            target, route = route[0], route[1:]
            self.routes[i] = route
            if take(target):
                self.goals[i] = target
                return True
        return False

    def stood_on(self, goal: NDArray[np.integer], still_frontier: bool) -> None:
        """A robot stood on ``goal``; where it still borders unknown space, no robot is sent there again."""
        if still_frontier:
            self.blacklist[int(goal[0]), int(goal[1])] = True

    def blacklist_around(self, goal: NDArray[np.integer], radius_cells: int) -> None:
        """The square of half-side ``radius_cells`` around ``goal`` stops being a candidate for every robot."""
        r0, r1, c0, c1 = _box(goal, radius_cells)
        self.blacklist[r0:r1, c0:c1] = True

    def bar(
        self,
        robot: int,
        goal: NDArray[np.integer],
        radius_cells: int,
        until: float,
        cells: NDArray[np.integer] | None = None,
    ) -> None:
        """The square of half-side ``radius_cells`` around ``goal``, and ``cells`` (``(k, 2)``, e.g. the rest
        of its cluster), are kept from ``robot`` until ``until``."""
        r0, r1, c0, c1 = _box(goal, radius_cells)
        h, w = self.blacklist.shape
        rows, cols = np.mgrid[r0 : min(r1, h), c0 : min(c1, w)]
        rows, cols = rows.ravel(), cols.ravel()
        if cells is not None and len(cells):
            rows = np.concatenate([rows, np.asarray(cells)[:, 0]])
            cols = np.concatenate([cols, np.asarray(cells)[:, 1]])
        self._barred.append((robot, rows.astype(np.int64), cols.astype(np.int64), until))

    def barred(self, robot: int, now: float) -> BoolGrid | None:
        """``(H, W) bool`` cells kept from ``robot`` at ``now`` (None: none)."""
        self._barred = [b for b in self._barred if b[3] > now]
        mine = [(rows, cols) for i, rows, cols, _ in self._barred if i == robot]
        if not mine:
            return None
        mask = np.zeros(self.blacklist.shape, dtype=bool)
        for rows, cols in mine:
            mask[rows, cols] = True
        return mask

    def strike(self, goal: NDArray[np.integer], radius_cells: int, limit: int) -> int:
        """An aborted goal: one strike on the square of half-side ``radius_cells`` around it; a cell struck
        ``limit`` times is blacklisted for the team for good (no robot could reach it however often it was
        tried, as explore_lite's blacklist keeps a goal). Returns how many cells were newly blacklisted."""
        r0, r1, c0, c1 = _box(goal, radius_cells)
        box = self.strikes[r0:r1, c0:c1]
        box[box < 255] += 1
        newly = (box >= limit) & ~self.blacklist[r0:r1, c0:c1]
        self.blacklist[r0:r1, c0:c1] |= newly
        return int(newly.sum())

    def forget(self) -> None:
        """A restarted centre's memory: no blacklist, nothing barred."""
        self.blacklist = np.zeros(self.blacklist.shape, dtype=bool)
        self.strikes = np.zeros(self.blacklist.shape, dtype=np.uint8)
        self._barred = []

    def current(self, i: int) -> NDArray[np.int32]:
        """Robot i's goal followed by its route, ``(k, 2) int32`` (empty without a goal)."""
        return np.vstack([self.goals[i : i + 1], self.routes[i]]) if self.goals[i, 0] >= 0 else NO_ROUTE


class KeepsGoals:
    """What keeps its team's goals in a :class:`GoalBook` (``self.book``) shows them as its own."""

    book: GoalBook

    @property
    def goals(self) -> NDArray[np.int32]:
        """``(n_robots, 2) int32`` each robot's goal in the team grid ((-1, -1): none)."""
        return self.book.goals

    @property
    def routes(self) -> list[NDArray[np.int32]]:
        """Each robot's targets after its goal (the local layer's route)."""
        return self.book.routes


def decision_due(now: float, last: float, replan: float, asked: bool) -> bool:
    """Whether the team needs a decision at ``now``: ``replan`` passed since the ``last`` one, or a robot
    ``asked`` (its goal ended with no target of its route left)."""
    return asked or now - last >= replan
