"""One mission: its step budget, replanning, what is sent, and the faults injected."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal

from mrexplore.config.schema import Checked, Interval, OneOf, at_least, is_integer, positive, require

__all__ = ["FaultConfig", "MissionConfig"]


@dataclass(frozen=True)
class FaultConfig(Checked):
    """Faults injected into a mission: lost robots, lost messages, a restarting centre, limited radio range."""

    robot_failures: tuple[tuple[int, int], ...] = ()
    """``(robot, step)`` pairs: at that simulation step the robot stops driving, scanning and sending for
    good; robot ids and steps count from 0. A robot id beyond the team is refused by the mission."""
    message_loss: float = 0.0
    """Probability that one robot-to-centre message, or one centre-to-robot acknowledgement, is lost
    (independent draws from the mission's seed)."""
    centre_restarts: tuple[int, ...] = ()
    """Simulation steps at which the centre loses all its state (robot maps, what it acknowledged, its
    blacklist); it rebuilds from the next messages."""
    comm_range_m: float | None = None
    """A robot farther than this straight-line distance from the relay (the first robot's start) cannot
    send; it keeps exploring on its own grid and syncs when back in range, metres; None: unlimited."""
    silence_rounds: int = 3
    """The centre stops assigning goals to a robot it has not heard from in this many rounds."""

    _constraints = {
        "message_loss": Interval(0, 1, "left"),
        "comm_range_m": positive("metres", none="unlimited"),
        "silence_rounds": at_least(1),
    }

    def _validate(self) -> None:
        # YAML gives lists; the frozen config keeps tuples (hashable, and equal to the flags' value).
        given = self.robot_failures
        try:
            failures = tuple(tuple(f) for f in given)
        except TypeError:
            failures = ((-1,),)  # refused below with the value received
        require(
            isinstance(self.centre_restarts, list | tuple), "centre_restarts", "a list of steps", self.centre_restarts
        )
        object.__setattr__(self, "robot_failures", failures)
        object.__setattr__(self, "centre_restarts", tuple(self.centre_restarts))
        for f in failures:
            require(
                len(f) == 2 and all(is_integer(v) and v >= 0 for v in f),
                "robot_failures",
                "(robot >= 0, step >= 0) integer pairs",
                given,
            )
        require(len({r for r, _ in failures}) == len(failures), "robot_failures", "one entry per robot", failures)
        require(
            all(is_integer(s) and s >= 0 for s in self.centre_restarts),
            "centre_restarts",
            "integer steps >= 0",
            self.centre_restarts,
        )

    @property
    def any(self) -> bool:
        """Whether any fault is configured."""
        return bool(self.robot_failures or self.message_loss or self.centre_restarts or self.comm_range_m)


@dataclass(frozen=True)
class MissionConfig(Checked):
    """One exploration mission: replanning events and the step budget."""

    max_steps: int = 20000
    """Step budget; reaching it ends the mission as ``max_steps`` (truncated, never success)."""
    replan_every_steps: int = 25
    """A decision is taken at least this often, steps."""
    min_replan_steps: int = 10
    """A decision asked for by a robot whose goal stopped being a frontier waits until this many steps have
    passed since the last one (the robot drives on meanwhile), steps (1: at once). A robot left with
    no path, or a blocked one, is served at once. Replanning at once makes teams chase goals that vanish as
    they come into view."""
    transmission: Literal["delta", "full"] = "delta"
    """What the centre rebuilds its grid from: ``delta`` (changes since the last acknowledged sparse
    frontier map) or ``full`` (the whole sparse map every round, the paper's). Same grid, fewer bytes."""
    baseline_bytes: bool = True
    """Count what Table II's int8-grid baselines would have sent (``bytes_grid``, ``bytes_grid_zlib``,
    ``bytes_grid_delta_zlib``): every robot's known box and its changed cells, zlib-compressed every round,
    work neither a robot nor the centre does, and what the other ``transmission`` mode would have sent (the
    whole map, coded every round, is several ms on a large floor). False leaves those fields empty, for runs
    that want Table I alone: the missions are the same step for step, and the bytes of the messages sent
    are counted either way."""
    oscillation_radius_m: float = 2.0
    """A new goal within this distance of a goal the robot gave up before reaching it (still a frontier)
    is a return to it, metres."""
    oscillation_returns: int = 2
    """After this many returns without reaching a goal, the robot commits: it keeps its current goal until
    it reaches it, sees it resolved, or is blocked, whatever later decisions say."""
    stall_steps: int = 150
    """Progress watchdog: a robot that gained no new area for this many steps beyond the time its path to
    the goal needed drops that goal, and the cells within ``oscillation_radius_m`` / 4 of it stop being
    candidates, steps."""

    faults: FaultConfig = field(default_factory=FaultConfig)

    _constraints = {
        "max_steps": at_least(1),
        "replan_every_steps": at_least(1),
        "min_replan_steps": at_least(1),
        "transmission": OneOf(("delta", "full")),
        "oscillation_radius_m": positive("metres"),
        "oscillation_returns": at_least(1),
        "stall_steps": at_least(1),
    }
