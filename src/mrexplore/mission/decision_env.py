"""A decision-level environment over :class:`~mrexplore.mission.Mission`, in Gymnasium's reset/step form.

One step is one decision of the centre: the observation is the :class:`AssignmentProblem` the global layer
sees, the action an :class:`Assignment` (or None: the strategy's own planner), and the reward paper eq. 9
summed over the simulation steps until the next decision (R_time per step plus lambda times the new
explorable area in m^2). ``terminated``: the mission ended on the paper's criteria (no frontier left or
reachable); ``truncated``: the step budget ran out. Observations are variable-sized graphs, so no fixed
Gymnasium space describes them; the trainer drives the same Mission through pose and commit.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

from mrexplore.global_planning.protocol import Assignment, AssignmentProblem
from mrexplore.mission import Mission, MissionSpec
from mrexplore.types import MrExploreError

__all__ = ["DecisionEnv"]


class DecisionEnv:
    """The team's decisions as an episodic environment (Gymnasium's reset/step conventions).

    Examples
    --------
    >>> from mrexplore.config import MapConfig
    >>> from mrexplore.maps.loaders import load_map
    >>> from mrexplore.pipeline import make_strategy
    >>> from mrexplore.mission import MissionSpec
    >>> env = DecisionEnv(MissionSpec(load_map("generated:0", MapConfig(resolution_m=0.2)), make_strategy("utility")))
    >>> problem, info = env.reset(seed=0)
    >>> total, done = 0.0, False
    >>> while not done:
    ...     problem, reward, terminated, truncated, info = env.step(None)
    ...     total += reward
    ...     done = terminated or truncated
    >>> terminated, info["coverage"] > 0.99
    (True, True)
    """

    def __init__(self, spec: MissionSpec) -> None:
        """``spec``: the missions' map, strategy and settings; :meth:`reset` sets the seed and the starts."""
        self.spec = spec
        self.mission: Mission | None = None
        self._problem: AssignmentProblem | None = None

    def reset(
        self, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[AssignmentProblem | None, dict[str, Any]]:
        """Start a mission (``seed``: the spec's where None; starts from the seed unless
        ``options["starts_rc"]``); run to its first decision."""
        starts = (options or {}).get("starts_rc", self.spec.starts_rc)
        spec = replace(self.spec, seed=self.spec.seed if seed is None else seed, starts_rc=starts)
        self.mission = Mission(spec, progress=False)
        self._to_next_decision()  # nothing happens before the first decision (step 0)
        return self._problem, self._info()

    def step(self, action: Assignment | None) -> tuple[AssignmentProblem | None, float, bool, bool, dict[str, Any]]:
        """Apply ``action`` to the pending decision and run to the next one."""
        m = self._require()
        if self._problem is None:
            raise MrExploreError("the episode is over; call reset() to start another")
        m.commit(action)
        reward = self._to_next_decision()
        terminated = m.done and m.done_reason != "max_steps"
        truncated = m.done_reason == "max_steps"
        return self._problem, reward, terminated, truncated, self._info()

    def _to_next_decision(self) -> float:
        """Run to the next decision and pose it (None where the mission ends); the reward on the way."""
        m = self._require()
        self._problem = None
        reward = 0.0
        while self._problem is None:  # rounds where the centre heard no robot (faults) pose nothing
            if not m.advance():
                return m.reward_since_decision
            reward = m.reward_since_decision  # read first: a pose that ends the mission resets it
            self._problem = m.pose()
            if m.done:
                break
        return reward

    def _info(self) -> dict[str, Any]:
        m = self._require()
        return {"coverage": m.sim.coverage, "steps": m.steps, "done_reason": m.done_reason}

    def _require(self) -> Mission:
        if self.mission is None:
            raise MrExploreError("call reset() before step()")
        return self.mission
