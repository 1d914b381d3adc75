"""Episode measures, read the same way by the CLI, the benchmark and training logs."""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

__all__ = ["EpisodeMeasures", "steps_to_coverage", "COVERAGE_MILESTONES"]

COVERAGE_MILESTONES = (0.90, 0.95, 0.99)


def steps_to_coverage(curve: NDArray[np.float64], level: float) -> int | None:
    """First step at which the coverage curve reaches ``level`` (index = step), or None if never.

    Examples
    --------
    >>> steps_to_coverage(np.array([0.1, 0.5, 0.95, 1.0]), 0.9)
    2
    >>> steps_to_coverage(np.array([0.1, 0.5]), 0.9) is None
    True
    """
    hit = np.flatnonzero(curve >= level - 1e-12)
    return int(hit[0]) if len(hit) else None


@dataclass(frozen=True)
class EpisodeMeasures:
    """What one exploration mission achieved and cost."""

    steps: int
    """Simulation steps taken (the paper's time steps)."""
    coverage: float
    """Team coverage at the end: known explorable cells / explorable cells, in [0, 1]."""
    steps_to_90: int | None
    steps_to_95: int | None
    steps_to_99: int | None
    path_len_max_m: float
    """Longest distance driven by one robot, metres."""
    path_len_sum_m: float
    """Distance driven by the whole team, metres."""
    overlap: float
    """Sum of per-robot coverages minus team coverage: how much was seen twice (0 = no redundancy)."""
    decisions: int
    """Planning decisions taken at the centre."""
    plan_ms_mean: float
    plan_ms_p95: float
    wall_s: float
    done_reason: str
    """``no_frontiers`` / ``no_reachable_frontiers`` (explored), or ``max_steps`` (budget ran out)."""
    rounds: int = 0
    """Communication rounds: every robot sent its map to the centre once per round (one per decision)."""
    bytes_grid: int = 0
    """Bytes the paper's baseline sends: each robot's int8 occupancy grid over its known bounding box."""
    bytes_grid_zlib: int = 0
    """The same grids zlib-compressed (level 6)."""
    bytes_sparse: int = 0
    """Bytes of the sparse frontier maps (paper IV-A), whole every round."""
    bytes_sparse_delta: int = 0
    """Bytes of the incremental sparse maps (changes since the last acknowledged round)."""
    reconstruction_iou_min: float = 1.0
    """Smallest free-space IoU, over rounds, of the centre's rebuilt grid against the robots' own beliefs."""
    reconstruction_iou_mean: float = 1.0

    @classmethod
    def from_run(
        cls,
        curve: NDArray[np.float64],
        robot_coverage: NDArray[np.float64],
        path_len_m: NDArray[np.float64],
        plan_ms: list[float],
        wall_s: float,
        done_reason: str,
        transmission: dict[str, Any] | None = None,
    ) -> EpisodeMeasures:
        """Measures of a finished run; ``transmission`` holds the byte and IoU fields (see
        :meth:`~mrexplore.preprocessing.transmission.TransmissionTotals.as_measures`)."""
        team = float(curve[-1])
        s90, s95, s99 = (steps_to_coverage(curve, lv) for lv in COVERAGE_MILESTONES)
        ms = np.asarray(plan_ms, dtype=np.float64)
        return cls(
            steps=len(curve) - 1,
            coverage=round(team, 6),
            steps_to_90=s90,
            steps_to_95=s95,
            steps_to_99=s99,
            path_len_max_m=round(float(path_len_m.max()), 4),
            path_len_sum_m=round(float(path_len_m.sum()), 4),
            overlap=round(float(robot_coverage.sum()) - team, 6),
            decisions=len(plan_ms),
            plan_ms_mean=round(float(ms.mean()), 3) if len(ms) else 0.0,
            plan_ms_p95=round(float(np.percentile(ms, 95)), 3) if len(ms) else 0.0,
            wall_s=round(wall_s, 3),
            done_reason=done_reason,
            **(transmission or {}),
        )

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)
