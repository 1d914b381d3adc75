"""Episode measures, read the same way by the CLI, the benchmark and training logs."""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mrexplore.config import SimConfig
from mrexplore.paths.distance_field import distance_fields
from mrexplore.types import BoolGrid

__all__ = ["EpisodeMeasures", "steps_to_coverage", "lower_bound_steps", "COVERAGE_MILESTONES", "OCTILE_OVER_EUCLID"]

COVERAGE_MILESTONES = (0.90, 0.95, 0.99)
OCTILE_OVER_EUCLID = math.sqrt(4 - 2 * math.sqrt(2))
"""Largest ratio of the octile (8-connected) length of a straight segment to its Euclidean length."""


def lower_bound_steps(
    passable: BoolGrid, explorable: BoolGrid, starts_rc: NDArray[np.integer], resolution_m: float, sim: SimConfig
) -> int:
    """Steps no planner can beat: over explorable free cells, the largest of the smallest (over robots)
    geodesic distance from the starts, less what the sensor reaches, at ``step_m`` per step.

    A cell is seen from a viewpoint within ``range_m`` in a straight free line, whose 8-connected length is
    at most ``range_m`` x :data:`OCTILE_OVER_EUCLID`; so some robot drives at least the geodesic distance
    less that much. Cells seen from the starts count 0.

    Examples
    --------
    >>> corridor = np.ones((1, 200), bool)
    >>> lower_bound_steps(corridor, corridor, np.array([[0, 0]]), 0.05, SimConfig(robots=1))  # 9.95 - 6.49 m
    35
    """
    fields = distance_fields(passable, np.asarray(starts_rc))
    nearest = np.minimum.reduce([f.full() for f in fields])
    cells = nearest[explorable & passable]
    cells = cells[np.isfinite(cells)]
    if len(cells) == 0:
        return 0
    far_m = float(cells.max()) * resolution_m - sim.sensor.range_m * OCTILE_OVER_EUCLID
    return max(0, math.ceil(far_m / sim.motion.step_m - 1e-9))


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
    """``no_frontiers`` / ``no_reachable_frontiers`` (explored), ``plan_done`` (the oracle finished its
    viewpoints), or ``max_steps`` (budget ran out)."""
    rounds: int = 0
    """Communication rounds: every robot sent its map to the centre once per round (one per decision)."""
    bytes_grid: int | None = 0
    """Bytes the paper's baseline sends: each robot's int8 occupancy grid over its known bounding box (None
    for a mission that did not count the grid baselines, ``mission.baseline_bytes: false``; the same for the
    next two)."""
    bytes_grid_zlib: int | None = 0
    """The same grids zlib-compressed (level 6)."""
    bytes_sparse: int | None = 0
    """Bytes of the sparse frontier maps (paper IV-A), whole every round (None for a mission that sent deltas
    and did not count the baselines)."""
    bytes_sparse_delta: int | None = 0
    """Bytes of the incremental sparse maps (changes since the last acknowledged round; None for a mission
    that sent whole maps and did not count the baselines)."""
    bytes_grid_delta_zlib: int | None = 0
    """The generic competitor of the sparse delta: the int8 grid's cells changed since the last
    acknowledged round (index gaps and values), zlib-compressed."""
    messages_sent: int = 0
    """Map messages robots sent to the centre, resends included."""
    messages_lost: int = 0
    messages_resent: int = 0
    """Whole maps resent because the centre lacked a delta's base (a lost acknowledgement, a restart)."""
    acks_lost: int = 0
    """Acknowledgements and whole-map requests from the centre that were lost."""
    bytes_lost: int = 0
    bytes_resent: int = 0
    centre_restarts: int = 0
    robots_failed: int = 0
    """Robots that broke down during the mission (``--robot-failure``)."""
    reconstruction_iou_min: float = 1.0
    """Smallest free-space IoU, over rounds, of the centre's rebuilt grid against the robots' own beliefs."""
    reconstruction_iou_mean: float = 1.0
    lower_bound_steps: int = 0
    """Steps no planner could beat from these starts (see :func:`lower_bound_steps`)."""
    peak_mb: float = 0.0
    """Peak resident memory of the process during the mission, MB (see :mod:`mrexplore.runtime.memory`)."""
    onboard_ms_median: float = 0.0
    """One robot's on-board work in a round (its grid brought up to date, closed and coded, its messages
    built), ms: the median over the robots and rounds that sent a map."""
    onboard_ms_p95: float = 0.0

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
        lower_bound: int = 0,
        robots_failed: int = 0,
        peak_mb: float = 0.0,
        onboard_ms: list[float] | None = None,
    ) -> EpisodeMeasures:
        """Measures of a finished run; ``transmission`` holds the byte and IoU fields (see
        :meth:`~mrexplore.preprocessing.transmission.TransmissionTotals.as_measures`)."""
        team = float(curve[-1])
        s90, s95, s99 = (steps_to_coverage(curve, lv) for lv in COVERAGE_MILESTONES)
        ms = np.asarray(plan_ms, dtype=np.float64)
        robot = np.asarray(onboard_ms or [], dtype=np.float64)
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
            lower_bound_steps=lower_bound,
            robots_failed=robots_failed,
            peak_mb=round(peak_mb, 1),
            onboard_ms_median=round(float(np.median(robot)), 3) if len(robot) else 0.0,
            onboard_ms_p95=round(float(np.percentile(robot, 95)), 3) if len(robot) else 0.0,
        )

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)
