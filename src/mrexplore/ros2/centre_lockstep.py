"""The centre's side of lockstep (``mrexplore ros2 sim --lockstep``): each decision request opens a round for
the robots the simulator says send; once all are in, the centre decides on the maps it received and answers
with the decision. A request for a round already answered gets the same answer again."""

from __future__ import annotations

from typing import Any

from mrexplore.ros2.centre_views import WHY
from mrexplore.ros2.lockstep import DecisionRequest, decide_lockstep
from mrexplore.types import MrExploreError

CentreNode = Any
"""A :class:`~mrexplore.ros2.centre_node.CentreNode` (not imported: it imports this module)."""

__all__ = ["LockstepAnswers"]


class LockstepAnswers:
    """Reads ``/mrexplore/lockstep/request`` and answers on ``/mrexplore/lockstep/decision`` for ``centre``."""

    def __init__(self, node: Any, centre: CentreNode) -> None:
        from std_msgs.msg import String

        self.node, self.centre, self._String = node, centre, String
        self.last_reply: str | None = None
        """The last decision's JSON, sent again where the simulator asks for that round again."""
        self._pub = node.create_publisher(String, "/mrexplore/lockstep/decision", 10)
        node.create_subscription(String, "/mrexplore/lockstep/request", self._on_request, 10)

    def _on_request(self, msg: Any) -> None:
        centre = self.centre
        try:
            request = DecisionRequest.from_json(msg.data)
        except MrExploreError as exc:
            centre.warn(f"decision request dropped: {exc}")
            return
        if centre.rounds.current is not None or request.round < centre.round:
            return  # that round is being collected, or long past
        if request.round == centre.round:
            if self.last_reply is not None:
                self._pub.publish(self._String(data=self.last_reply))  # asked again: the same answer
            return
        centre.open_round(request.round, request.stamp, set(request.sending), request)

    def decide(self, request: DecisionRequest) -> None:
        """Decide on ``request`` once its round closed; send the goals and the answer."""
        centre = self.centre
        decision, reply, mine = decide_lockstep(centre.planner, request)
        if mine != list(request.active):
            centre.warn(f"round {request.round}: the simulator assigns {request.active}, the centre heard {mine}")
        for j, i in enumerate(request.active):
            if decision.goals_rc[j][0] >= 0:
                centre.send_goal(i, decision.goals_rc[j])
        self.last_reply = reply.to_json()
        self._pub.publish(self._String(data=self.last_reply))
        if decision.done_reason is not None:
            self.node.get_logger().info(f"exploration finished: {WHY[decision.done_reason]}")
