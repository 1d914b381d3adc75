"""The Nav2 double's NavigateToPose action servers, where nav2_msgs can be imported (a Nav2 installation, or
the interface built in the tests): every goal, whether sent to the action or on ``goal_pose`` (which
bt_navigator forwards to its own action server, as here), is one action goal; rcl accepts and stamps it and
publishes the status array; a new goal aborts the running one, as nav2_util's ``SimpleActionServer`` does; a
cancel request stops the robot."""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from mrexplore.team.nav_goals import ABORTED, SUCCEEDED

__all__ = ["ActionDouble"]


class ActionDouble:
    """NavigateToPose action servers for a :class:`~mrexplore.ros2.nav2_double.Nav2Double`'s robots."""

    def __init__(self, node: Any, double: Any) -> None:
        from nav2_msgs.action import NavigateToPose
        from rclpy.action import ActionClient, ActionServer, CancelResponse, GoalResponse

        self.double, self._Action = double, NavigateToPose
        n = len(double.robots)
        self.current: list[tuple[Any, Any] | None] = [None] * n
        """Each robot's running goal: its handle and the future its execution waits on."""
        self.received = 0
        self._outcomes: dict[int, Any] = {}
        """Each accepted goal's future by its handle's id, awaited by its execution whenever that starts."""
        self._clients = []
        for i, robot in enumerate(double.robots):
            name = robot.nav_status_topic.removesuffix("/_action/status")
            ActionServer(
                node,
                NavigateToPose,
                name,
                execute_callback=self._executor(i),
                goal_callback=lambda request: GoalResponse.ACCEPT,
                handle_accepted_callback=lambda handle, i=i: self._accepted(i, handle),
                cancel_callback=lambda handle: CancelResponse.ACCEPT,
            )
            self._clients.append(ActionClient(node, NavigateToPose, name))  # goal_pose's way in

    def forward(self, i: int, pose_stamped: Any) -> None:
        """A goal on ``goal_pose``: sent to the robot's own action server."""
        goal = self._Action.Goal()
        goal.pose = pose_stamped
        self._clients[i].send_goal_async(goal)

    def has_goal(self, i: int) -> bool:
        return self.current[i] is not None

    def _accepted(self, i: int, handle: Any) -> None:
        from rclpy.task import Future

        self.received += 1
        if self.current[i] is not None:  # preempted: aborted, as SimpleActionServer::accept_pending_goal does
            self.current[i][1].set_result(ABORTED)  # type: ignore[index]
            self.double.preempted += 1
        done = Future()
        self.current[i] = (handle, done)
        self._outcomes[id(handle)] = done
        if not self.double.mission.sim.alive[i] or not self.double.begin(i, handle.request.pose.pose):
            self.double.aborts_caused += 1
            self.current[i] = None
            done.set_result(ABORTED)
        handle.execute()

    def _executor(self, i: int) -> Any:
        """Robot i's execute callback: a coroutine function, as rclpy awaits only those."""

        async def execute(handle: Any) -> Any:
            return await self._execute(i, handle)

        return execute

    async def _execute(self, i: int, handle: Any) -> Any:
        # The goal may have ended before its execution started (preempted, refused, or already there).
        outcome = await self._outcomes.pop(id(handle))
        if outcome == SUCCEEDED:
            handle.succeed()
        elif handle.is_cancel_requested:
            handle.canceled()
        else:
            handle.abort()
        return self._Action.Result()

    def after_step(self, blocked: NDArray[np.bool_]) -> None:
        """After a simulation step: each running goal goes on, succeeds, is aborted or, on request, cancelled."""
        sim = self.double.mission.sim
        for i, running in enumerate(self.current):
            if running is None:
                continue
            handle, done = running
            if not sim.alive[i]:
                continue  # a failed robot's Nav2 says nothing more
            if handle.is_cancel_requested:
                sim.set_path(i, np.zeros((0, 2), np.int32))
                outcome: int | None = ABORTED
            else:
                outcome = self.double.progress(i, bool(blocked[i]))
            if outcome is not None:
                self.current[i] = None
                done.set_result(outcome)
