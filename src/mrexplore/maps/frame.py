"""The one place where grid indices ``(row, col)`` and map-frame metres ``(x, y)`` are converted."""

from __future__ import annotations

import math
from dataclasses import dataclass

from mrexplore.types import GridRC, WorldXY

__all__ = ["GridFrame"]


@dataclass(frozen=True)
class GridFrame:
    """Geometry of a grid in the map frame (ROS map_server convention).

    Row 0 is the top of the image; ``origin_xy`` is the map-frame position of the lower-left corner of
    the lower-left cell ``(height - 1, 0)``, as in a map_server YAML.

    Examples
    --------
    >>> f = GridFrame(height=5, width=5, resolution_m=0.1, origin_xy=(0.0, 0.0))
    >>> f.rc_to_xy((4, 0))
    (0.05, 0.05)
    >>> f.xy_to_rc((0.05, 0.45))
    (0, 0)
    """

    height: int
    width: int
    resolution_m: float
    origin_xy: WorldXY = (0.0, 0.0)

    def rc_to_xy(self, rc: GridRC) -> WorldXY:
        """Centre of cell ``rc`` in metres."""
        r, c = rc
        x = self.origin_xy[0] + (c + 0.5) * self.resolution_m
        y = self.origin_xy[1] + (self.height - 1 - r + 0.5) * self.resolution_m
        return (round(x, 9), round(y, 9))

    def xy_to_rc(self, xy: WorldXY) -> GridRC:
        """Cell containing the point ``xy`` (may lie outside the grid; see :meth:`contains`)."""
        c = math.floor((xy[0] - self.origin_xy[0]) / self.resolution_m)
        r = self.height - 1 - math.floor((xy[1] - self.origin_xy[1]) / self.resolution_m)
        return (int(r), int(c))

    def contains(self, rc: GridRC) -> bool:
        """Whether ``rc`` indexes a cell of the grid."""
        return 0 <= rc[0] < self.height and 0 <= rc[1] < self.width
