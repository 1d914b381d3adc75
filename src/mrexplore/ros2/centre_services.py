"""The centre's services (std_srvs/Trigger): ``/mrexplore/pause``, ``resume``, ``stop`` and ``return_home``.
Each answers at once and the centre's status says what it did before the service returns, so that a launcher
or simulator waiting on the status acts on it."""

from __future__ import annotations

from typing import Any

CentreNode = Any
"""A :class:`~mrexplore.ros2.centre_node.CentreNode` (not imported: it imports this module)."""

__all__ = ["add_services", "pause", "resume", "stop", "return_home"]


def pause(centre: CentreNode) -> tuple[bool, str]:
    """Robots hold where they stand (their goals cancelled, or their own cell as goal); maps keep arriving."""
    centre.paused = True
    for i, here in enumerate(centre.planner.team.positions_rc):
        if here[0] >= 0:
            centre.goals[i].hold(*centre.goal_pose(i, here))
    return True, "paused: robots hold their positions; maps keep arriving"


def resume(centre: CentreNode) -> tuple[bool, str]:
    """Decide again at the next round."""
    centre.paused, centre.force = False, True
    return True, "resumed"


def stop(centre: CentreNode) -> tuple[bool, str]:
    """Hold, and end the exploration: the status says ``stopped``."""
    pause(centre)
    centre.finished = "stopped"
    return True, "stopped: robots hold their positions"


def return_home(centre: CentreNode) -> tuple[bool, str]:
    """Each robot drives to the cell of its first message; no more decisions until resumed."""
    centre.paused = True
    for i, start in enumerate(centre.planner.starts):
        if start[0] >= 0:
            centre.send_goal(i, start)
    return True, "returning: each robot drives to where its first message came from"


def add_services(node: Any, centre: CentreNode) -> None:
    """Serve the four services on ``node`` for ``centre``."""
    from std_srvs.srv import Trigger

    def serve(action: Any) -> Any:
        def callback(request: Any, response: Any) -> Any:
            response.success, response.message = action(centre)
            centre.publish_views()
            return response

        return callback

    for name, action in (("pause", pause), ("resume", resume), ("stop", stop), ("return_home", return_home)):
        node.create_service(Trigger, f"/mrexplore/{name}", serve(action))
