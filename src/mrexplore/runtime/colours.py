"""The robots' colours, one per robot, shared by the pictures (``--png``, ``--gif``) and the RViz markers, so
that a robot looks the same in both."""

from __future__ import annotations

__all__ = ["ROBOT_COLOURS", "robot_colour"]

ROBOT_COLOURS = (
    (0, 114, 178),
    (230, 159, 0),
    (204, 121, 167),
    (86, 180, 233),
    (213, 94, 0),
    (240, 228, 66),
    (140, 86, 75),
)
"""Okabe and Ito's colour-blind-safe palette without its bluish green (the frontiers' colour), and a brown,
as 0-255 RGB; a team of more than seven repeats them."""


def robot_colour(i: int) -> tuple[int, int, int]:
    """Robot ``i``'s colour, 0-255 RGB."""
    return ROBOT_COLOURS[i % len(ROBOT_COLOURS)]
