"""The computing centre of a real team as a plain object: the robots' messages merged into the team map
(:class:`~mrexplore.preprocessing.agents.TeamCentre`), layers 1-3 of any strategy on it, and the goals kept
between decisions as a robot's navigation reports on them. ``mrexplore ros2 centre`` is a thin adapter around
it; it imports no ROS.

A robot's goal ends when its navigation reports it reached (a goal it stood on that still borders unknown
space stops being a candidate, as in the simulator), aborted (the clusters centred around it, and the rest of
its cluster, are kept from that robot for ``blacklist_s``, as explore_lite's blacklist does; a place aborted
:data:`STRIKES_TO_DROP` times is dropped for the team for good), or when the goal no longer borders unknown space on
the team map (once ``min_replan_s`` passed since the last decision); the robot then moves on to the next
target of its local route that still does, and only with none left does it ask for a decision. The whole
team is re-assigned when a robot asks, and at least every ``replan_s``; a robot whose goal the new decision
keeps is not sent it again, and one left without a goal waits for the next decision: the simulator's
replanning events (:mod:`~mrexplore.mission`), read from what the robots' navigation reports. A robot the centre has
not heard for ``silence_rounds`` rounds gets no goal; its map stays. After a restart (a new object), the
robots' deltas are refused and their whole maps rebuild everything.

Examples
--------
>>> from mrexplore.pipeline import make_strategy
>>> from mrexplore.preprocessing.agents import RobotAgent
>>> from mrexplore.config import SensorConfig
>>> from mrexplore.types import CellState
>>> strategy = make_strategy("nearest")
>>> planner = TeamPlanner(1, (12, 12), 0.1, strategy, silence_rounds=3, blacklist_radius_m=0.2)
>>> state = np.full((12, 12), CellState.UNKNOWN, np.uint8); state[2:8, 2:8] = CellState.FREE
>>> robot = RobotAgent(0, (12, 12), strategy.preprocess, SensorConfig()); robot.sense_state(state)
>>> planner.receive(planner.read(robot.compose(0, (4, 4), robot.window()).incremental()), 0)
>>> planner.plan(0, now=0.0)  # the goal to send robot 0
{0: array([2, 3], dtype=int32)}
>>> planner.navigation(0, NavState.ABORTED, now=1.0)  # its navigation gave up on it
>>> planner.plan(0, now=1.0), planner.aborts  # another goal at once: that cluster is kept from it a while
({0: array([2, 6], dtype=int32)}, 1)
"""

from __future__ import annotations

import time
from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from mrexplore.pipeline import Decision, DecisionInput, ExplorationPipeline
from mrexplore.preprocessing.agents import TeamCentre
from mrexplore.preprocessing.sparse_map import SparseFrontierMap
from mrexplore.team.goal_book import GoalBook, KeepsGoals, decision_due
from mrexplore.types import BoolGrid, CellState, MrExploreError

__all__ = ["TeamPlanner", "NavState", "NO_ORACLE", "warm_up"]

STRIKES_TO_DROP = 3
"""Aborted goals whose areas overlap a cell before it is dropped for the whole team for good."""
NO_ORACLE = "the oracle needs the ground truth, which a real team lacks; pick another strategy"


class NavState:
    """What a robot's navigation last said of its goal."""

    IDLE = "idle"
    SENT = "sent"
    ACTIVE = "active"
    REACHED = "reached"
    ABORTED = "aborted"


class TeamPlanner(KeepsGoals):
    """The centre's work between the messages in and the goals out (module docstring).

    Parameters
    ----------
    blacklist_radius_m:
        Half the side of the square kept from the robots around an aborted goal.
    settle_s:
        The centre declares the exploration done only once it heard every robot, or this long after its first
        round (a robot lost for good).
    """

    def __init__(
        self,
        n_robots: int,
        shape: tuple[int, int],
        resolution_m: float,
        strategy: ExplorationPipeline,
        silence_rounds: int = 3,
        blacklist_s: float = 30.0,
        replan_s: float = 10.0,
        min_replan_s: float = 1.0,
        settle_s: float = 5.0,
        blacklist_radius_m: float = 0.5,
        seed: int = 0,
    ) -> None:
        if strategy.name == "oracle":
            raise MrExploreError(NO_ORACLE)
        self.strategy = strategy
        self.resolution_m = resolution_m
        self.team = TeamCentre(n_robots, shape, strategy.preprocess.closing_size_cells, silence_rounds)
        self.blacklist_s, self.replan_s, self.min_replan_s = blacklist_s, replan_s, min_replan_s
        self.settle_s = settle_s
        self._radius = max(1, round(blacklist_radius_m / resolution_m))
        self.book = GoalBook(n_robots, shape)
        """Each robot's goal and route, the blacklist, the areas barred from one robot: the simulator's rules."""
        self.nav = [NavState.IDLE] * n_robots
        self.starts = np.full((n_robots, 2), -1, dtype=np.int32)
        """``(n_robots, 2) int32`` each robot's cell in its first message (its way home)."""
        self._last_decision = -np.inf
        self._freed: set[int] = set()
        """Robots whose goal ended since the last decision."""
        self._reached: list[tuple[int, NDArray[np.int32], int]] = []
        """Goals reached, with the round of the robot's last message then: checked after its next two."""
        self._first_plan: float | None = None
        self.rng = np.random.default_rng(seed)
        self.decision: Decision | None = None
        self.done_reason: str | None = None
        self.aborts = 0
        """Goals the robots' navigation aborted."""
        self.decisions = 0

    # -- messages in ------------------------------------------------------------------------------------
    def accepts(self, message: SparseFrontierMap) -> bool:
        return self.team.accepts(message)

    def read(self, data: bytes) -> SparseFrontierMap | None:
        """A message's bytes decoded (:meth:`TeamCentre.read`): None for a delta on a base the centre lacks."""
        return self.team.read(data)

    def receive(self, message: SparseFrontierMap, round_: int) -> None:
        """Apply a message :meth:`accepts`, heard in ``round_``."""
        self.team.receive(message, round_)
        if self.starts[message.robot, 0] < 0:
            self.starts[message.robot] = message.position_rc

    # -- what the robots' navigation says ---------------------------------------------------------------
    def navigation(self, robot: int, state: str, now: float) -> None:
        """Robot ``robot``'s navigation says ``state`` (:class:`NavState`) of its current goal."""
        goal = self.goals[robot]
        if goal[0] < 0 or self.nav[robot] in (NavState.REACHED, NavState.ABORTED):
            return
        self.nav[robot] = state
        if state == NavState.ABORTED:
            # Kept from that robot a while: the goal's square and the rest of its cluster (else the next
            # decision picks the cluster's next member, which its navigation refuses the same way).
            self.book.bar(robot, goal, self._radius, until=now + self.blacklist_s, cells=self._cluster_of(goal))
            self.book.strike(goal, self._radius, STRIKES_TO_DROP)
            self.aborts += 1
            self._drop(robot)
        elif state == NavState.REACHED:
            # Whether it stayed a frontier shows in the robot's first map sent after it got there: checked then.
            self._reached.append((robot, goal.copy(), self.team.last_heard[robot]))
            self._drop(robot)

    def _cluster_of(self, goal: NDArray[np.integer]) -> NDArray[np.int32] | None:
        """The members of the last decision's cluster that holds ``goal`` (None: none does)."""
        if self.decision is None:
            return None
        clusters = self.decision.clusters
        hit = np.flatnonzero((clusters.members_rc == np.asarray(goal)).all(axis=1))
        return clusters.members_rc[clusters.labels == clusters.labels[hit[0]]] if len(hit) else None

    def _drop(self, robot: int) -> None:
        self._freed.add(robot)
        self.book.drop(robot)

    def blacklist(self) -> BoolGrid:
        """``(H, W) bool`` cells that are no candidates for any robot (goals stood on that stayed frontiers)."""
        return self.book.blacklist

    def barred(self, robot: int, now: float) -> BoolGrid | None:
        """``(H, W) bool`` cells whose clusters are kept from ``robot`` at ``now`` (None: none)."""
        return self.book.barred(robot, now)

    # -- decisions -------------------------------------------------------------------------------------
    def assignable(self, round_: int) -> NDArray[np.int64]:
        """The robots the centre may assign to after ``round_`` (heard recently, cell known)."""
        return np.flatnonzero(self.team.status(round_).assignable)

    def decision_input(
        self,
        round_: int,
        blacklist: BoolGrid,
        current: Sequence[NDArray[np.int32]],
        rng: np.random.Generator,
        active: NDArray[np.int64],
        barred: Sequence[BoolGrid | None] | None = None,
    ) -> DecisionInput:
        """What the strategy decides on after ``round_``: the team map, the ``active`` robots' cells,
        the blacklist, their current routes and what is kept from each."""
        return DecisionInput(
            self.team.state(),
            self.team.positions_rc[active],
            self.resolution_m,
            blacklist,
            current,
            rng,
            self.team.frontiers(),
            barred,
        )

    def plan(self, round_: int, now: float | None = None, force: bool = False) -> dict[int, NDArray[np.int32]]:
        """After ``round_``'s messages: move robots on along their routes; decide where a robot's goal
        ended (its navigation reached or aborted it, or it was seen with no target of its route left and
        ``min_replan_s`` passed since the last decision), where ``replan_s`` passed, or on ``force``;
        returns the goals to send, ``{robot: (r, c)}``. A robot left without a goal waits for the next
        decision. Sets :attr:`done_reason` when no reachable cluster is left."""
        now = time.monotonic() if now is None else now
        if self._first_plan is None:
            self._first_plan = now
        active = self.assignable(round_)
        un_mask = self.team.frontiers().un_mask
        pending = []
        for robot, goal, heard in self._reached:
            if self.team.last_heard[robot] < heard + 2:  # its next answer may predate the arrival
                pending.append((robot, goal, heard))
            else:
                self.book.stood_on(goal, still_frontier=bool(un_mask[goal[0], goal[1]]))
        self._reached = pending
        blacklist = self.blacklist()
        barred = [self.barred(int(i), now) for i in active]
        sent: dict[int, NDArray[np.int32]] = {}
        need = decision_due(now, self._last_decision, self.replan_s, force or bool(self._freed & set(map(int, active))))
        settled = now - self._last_decision >= self.min_replan_s
        for i in map(int, active):
            goal = self.goals[i]
            if goal[0] < 0 or un_mask[goal[0], goal[1]] or not settled:
                continue  # driving on towards a goal already seen costs little; a decision costs the team
            mine = barred[list(map(int, active)).index(i)]

            def take(t: NDArray[np.int32], mine: BoolGrid | None = mine) -> bool:
                return bool(
                    un_mask[t[0], t[1]] and not blacklist[t[0], t[1]] and (mine is None or not mine[t[0], t[1]])
                )

            # Seen: the next target of its route that still borders unknown space.
            if self.book.next_target(i, take):
                self.nav[i] = NavState.SENT
                sent[i] = self.goals[i].copy()
            else:
                self._drop(i)
                need = True
        if not need or len(active) == 0:
            return sent
        self._freed.clear()
        current = [self.book.current(i) for i in map(int, active)]
        decision = self.strategy.decide(self.decision_input(round_, blacklist, current, self.rng, active, barred))
        self.decision, self._last_decision = decision, now
        self.decisions += 1
        if decision.done_reason is not None:
            # Not while only aborted goals' areas are left (they are tried again once their time is up), nor
            # before every robot's map is in or settle_s passed (a restarted centre hears them one by one).
            everyone = bool((self.team.last_heard >= 0).all()) or now - self._first_plan >= self.settle_s
            if everyone and not any(b is not None for b in barred):
                self.done_reason = decision.done_reason
            return sent
        for j, i in enumerate(map(int, active)):
            goal = decision.goals_rc[j]
            if goal[0] < 0 or np.array_equal(goal, self.goals[i]):
                continue  # nothing for it, or its goal kept: Nav2 drives on
            self.book.assign(i, goal.copy(), decision.routes[j][1:])
            self.nav[i] = NavState.SENT
            sent[i] = goal.copy()
        return sent

    def free(self) -> BoolGrid:
        """``(H, W) bool`` free cells of the team map."""
        return self.team.state() == CellState.FREE


def warm_up(strategy: ExplorationPipeline) -> None:
    """Run one message in and one decision out on a small room, on a copy of ``strategy``: a node that does
    this before it joins the team compiles its kernels (a minute or more on a fresh install) while nobody waits
    for it, not in its first rounds, where the team would take the pause for a lost robot."""
    import copy

    from mrexplore.config import SensorConfig
    from mrexplore.preprocessing.agents import RobotAgent

    mine = copy.deepcopy(strategy)
    planner = TeamPlanner(1, (16, 16), 0.1, mine, silence_rounds=3)
    state = np.full((16, 16), CellState.UNKNOWN, np.uint8)
    state[2:10, 2:10] = CellState.FREE
    robot = RobotAgent(0, (16, 16), mine.preprocess, SensorConfig())
    robot.sense_state(state)
    out = robot.compose(0, (5, 5), robot.window())
    for data in (out.full_bytes(), out.incremental()):
        message = planner.read(data)
        if message is not None:
            planner.receive(message, 0)
    planner.plan(0, now=0.0, force=True)
