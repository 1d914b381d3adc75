"""Typed, frozen configuration: one dataclass per part, each field with its unit and range.

Every dataclass validates itself on construction and raises :class:`~mrexplore.types.MrExploreError`
with the parameter name, the value received and the allowed range, e.g.
``robots must be >= 1, got 0``.
"""

from __future__ import annotations

import functools
import math
import numbers
import types
import typing
from dataclasses import asdict, dataclass, field, fields, is_dataclass
from pathlib import Path
from typing import Any, ClassVar, Literal

from mrexplore.types import MrExploreError

__all__ = [
    "MapConfig",
    "GridThresholds",
    "SensorConfig",
    "MotionConfig",
    "SimConfig",
    "RewardConfig",
    "PreprocessConfig",
    "GlobalPlanningConfig",
    "LocalPlanningConfig",
    "CoScanConfig",
    "FaultConfig",
    "MissionConfig",
    "LearnedConfig",
    "TrainConfig",
    "NcmTrainConfig",
    "TRAINABLE",
    "RunConfig",
    "config_to_dict",
    "config_from_dict",
    "config_yaml",
    "read_config_file",
]


def _require(ok: bool, name: str, rule: str, value: object) -> None:
    if not ok:
        raise MrExploreError(f"{name} must be {rule}, got {value!r}")


class _Checked:
    """Base of every config: checks each field's type (numbers finite, bools not taken for numbers, nested
    configs of their class) before the class's own range rules, so that a YAML file or a flag with the
    wrong kind of value gets the same one-line error as one out of range."""

    _constraints: ClassVar[dict[str, Constraint]] = {}
    """Each field's allowed values (a field not named here takes any value of its type)."""

    def __post_init__(self) -> None:
        hints = _hints(type(self).__qualname__)
        for f in fields(self):  # type: ignore[arg-type]
            _check_type(f.name, getattr(self, f.name), hints[f.name])
        self._validate()
        for name, rule in self._constraints.items():
            value = getattr(self, name)
            if value is None and rule.none is not None:
                continue
            _require(value is not None and rule.holds(value, self), rule.name or name, rule.describe(self), value)

    def _validate(self) -> None:
        """Rules that are more than a field's range (normalising YAML's lists, for one)."""


@functools.cache
def _hints(class_name: str) -> dict[str, Any]:
    return typing.get_type_hints(globals()[class_name])


def _check_type(name: str, value: object, hint: Any) -> None:
    if typing.get_origin(hint) in (types.UnionType, typing.Union):
        options = [a for a in typing.get_args(hint) if a is not type(None)]
        if value is None:
            return
        hint = options[0]
        rule_none = " or None"
    else:
        rule_none = ""
    if hint is float:
        _require(_finite(value), name, f"a finite number{rule_none}", value)
    elif hint is int:
        _require(_integer(value), name, f"an integer{rule_none}", value)
    elif hint is bool:
        _require(isinstance(value, bool), name, "true or false", value)
    elif hint is str:
        _require(isinstance(value, str), name, f"a string{rule_none}", value)
    elif isinstance(hint, type) and is_dataclass(hint):
        _require(isinstance(value, hint), name, f"a {hint.__name__}", value)
    # tuples: the class checks their items (and takes lists from YAML)


def _finite(value: object) -> bool:
    """A real number that is neither NaN nor infinite (bools are refused: ``True`` is no distance)."""
    return isinstance(value, numbers.Real) and not isinstance(value, bool) and math.isfinite(value)


def _integer(value: object) -> bool:
    """An integer, NumPy's included, but not a bool."""
    return isinstance(value, numbers.Integral) and not isinstance(value, bool)


# -- constraints: each field's allowed values, declared once per class (scikit-learn's
# ``_parameter_constraints``); validation and ``mrexplore config``'s documentation both read them.
Bound = float | str
"""A number, or the name of another field of the same config (its value is the bound)."""


@dataclass(frozen=True)
class Interval:
    """Numbers between ``low`` and ``high`` (None: unbounded); ``closed``: which ends belong to it."""

    low: Bound | None = None
    high: Bound | None = None
    closed: str = "both"
    """``both``, ``left``, ``right`` or ``neither``."""
    unit: str = ""
    """Named after the bounds in messages and documentation (``metres``)."""
    none: str | None = None
    """Where the field may be None: what None means (``""``: nothing to say); None: not allowed."""
    name: str | None = None
    """The name messages give the field where it differs from the field's (the CLI flag's)."""

    def _bound(self, b: Bound | None, cfg: object) -> float | None:
        return float(getattr(cfg, b)) if isinstance(b, str) else b

    def holds(self, value: Any, cfg: object) -> bool:
        lo, hi = self._bound(self.low, cfg), self._bound(self.high, cfg)
        left, right = self.closed in ("both", "left"), self.closed in ("both", "right")
        return (lo is None or (value >= lo if left else value > lo)) and (
            hi is None or (value <= hi if right else value < hi)
        )

    def describe(self, cfg: object | None = None) -> str:
        """``> 0 metres``, ``in [0, 1)``, ``>= robots_min (2)``: the rule in words."""

        def show(b: Bound | None) -> str:
            if isinstance(b, str):
                return f"{b} ({getattr(cfg, b)})" if cfg is not None else b
            return f"{b:g}"

        left, right = self.closed in ("both", "left"), self.closed in ("both", "right")
        if self.high is None:
            text = f"{'>=' if left else '>'} {show(self.low)}"
        elif self.low is None:
            text = f"{'<=' if right else '<'} {show(self.high)}"
        else:
            text = f"in {'[' if left else '('}{show(self.low)}, {show(self.high)}{']' if right else ')'}"
        return text + (f" {self.unit}" if self.unit else "") + _none_text(self.none)


@dataclass(frozen=True)
class Odd(Interval):
    """Odd integers of an interval."""

    def holds(self, value: Any, cfg: object) -> bool:
        return value % 2 == 1 and super().holds(value, cfg)

    def describe(self, cfg: object | None = None) -> str:
        return "odd and " + super().describe(cfg)


@dataclass(frozen=True)
class ZeroOr(Interval):
    """0, or a number of an interval."""

    def holds(self, value: Any, cfg: object) -> bool:
        return value == 0 or super().holds(value, cfg)

    def describe(self, cfg: object | None = None) -> str:
        return "0 or " + super().describe(cfg)


@dataclass(frozen=True)
class OneOf:
    """One of a few words."""

    options: tuple[str, ...]
    name: str | None = None
    none: str | None = None

    def holds(self, value: Any, cfg: object) -> bool:
        return value in self.options

    def describe(self, cfg: object | None = None) -> str:
        words = [repr(o) for o in self.options]
        return (", ".join(words[:-1]) + " or " + words[-1] if len(words) > 1 else words[0]) + _none_text(self.none)


Constraint = Interval | OneOf


def _none_text(none: str | None) -> str:
    return "" if none is None else ", or null" + (f" for {none}" if none else "")


def _positive(unit: str = "", **kw: Any) -> Interval:
    return Interval(0, None, "neither", unit, **kw)


def _non_negative(unit: str = "", **kw: Any) -> Interval:
    return Interval(0, None, "left", unit, **kw)


def _at_least(low: Bound, **kw: Any) -> Interval:
    return Interval(low, None, "left", **kw)


@dataclass(frozen=True)
class MapConfig(_Checked):
    """How a map file becomes a ground-truth grid."""

    resolution_m: float = 0.05
    """Working cell size, metres per cell (paper: 0.05)."""
    pixel_size_m: float | None = None
    """Metres per pixel of an image with no YAML; None: 0.01 for grayscale, 0.1 for DungeonMaps."""
    outside_opening_m: float = 1.5
    """Free space reaching the border through passages wider than twice this is outside, metres."""
    min_passage_m: float = 0.1
    """Free passages narrower than this are closed: no robot fits (HouseExpo renders leave 1-6 cm slivers
    where walls meet), metres (0: keep every gap)."""
    max_cells: int = 60_000_000
    """A map whose working grid would hold more cells is refused before it is built (a 60 M-cell grid takes
    several GB across the simulator's layers)."""
    max_image_pixels: int = 400_000_000
    """A map image (or HouseExpo raster at 1 cm) with more pixels is refused before it is decoded."""
    max_file_bytes: int = 256_000_000
    """A map file (image, JSON) larger than this is refused before it is read."""

    _constraints = {
        "resolution_m": _positive("metres", name="resolution"),
        "pixel_size_m": _positive("metres", name="pixel-size", none="the format's default"),
        "outside_opening_m": _positive("metres"),
        "min_passage_m": _non_negative("metres"),
        "max_cells": _at_least(1),
        "max_image_pixels": _at_least(1),
        "max_file_bytes": _at_least(1),
    }


@dataclass(frozen=True)
class GridThresholds(_Checked):
    """How a robot's published occupancy grid (ROS values: -1 unknown, 0-100 occupied %) becomes cell states
    (map_server's defaults, 0.196 and 0.65), and how large a grid is read at all."""

    free_max: int = 19
    """Values from 0 up to this are free."""
    occupied_min: int = 65
    """Values from this up to 100 are occupied; between the two, and -1, unknown."""
    max_cells: int = 60_000_000
    """A grid with more cells is refused before anything is allocated for it."""

    _constraints = {
        "free_max": Interval(0, 99),
        "occupied_min": Interval("free_max", 100, "right"),
        "max_cells": _at_least(1),
    }


@dataclass(frozen=True)
class SensorConfig(_Checked):
    """360° 2D LiDAR and the log-odds belief it updates (paper eq. 1)."""

    range_m: float = 6.0
    """Maximum range, metres (paper: 6 m)."""
    ray_oversampling: float = 1.0
    """Beams per cell of circumference at full range; 1 already leaves no gap within range - 0.5 cell."""
    p_hit: float = 0.7
    """P(occupied | beam ends in cell) (OctoMap's default)."""
    p_miss: float = 0.4
    """P(occupied | beam passes through cell) (OctoMap's default)."""
    p_clamp_min: float = 0.12
    """Lower clamp of the occupancy probability (OctoMap's default)."""
    p_clamp_max: float = 0.97
    """Upper clamp of the occupancy probability (OctoMap's default)."""
    p_occupied: float = 0.5
    """An observed cell is occupied when its probability exceeds this; else free."""
    range_noise_m: float = 0.0
    """Standard deviation of Gaussian range noise, metres (0: noiseless)."""

    _constraints = {
        "range_m": _positive("metres"),
        "ray_oversampling": _at_least(1),
        "p_hit": Interval(0.5, 1, "neither"),
        "p_miss": Interval(0, 0.5, "neither"),
        "p_clamp_min": Interval(0, 0.5, "neither"),
        "p_clamp_max": Interval(0.5, 1, "neither"),
        "p_occupied": Interval(0, 1, "neither"),
        "range_noise_m": _non_negative("metres"),
    }


@dataclass(frozen=True)
class MotionConfig(_Checked):
    """How far a robot drives per simulation step."""

    step_m: float = 0.1
    """Distance driven per step along the path, metres (the mission's clock)."""

    _constraints = {"step_m": _positive("metres")}


@dataclass(frozen=True)
class RewardConfig(_Checked):
    """Team reward of paper eq. 9: R = R_time + lambda * R_area."""

    time_reward: float = -1.0
    """R_time, the fixed reward per step."""
    area_weight: float = 2.0
    """lambda, weight of newly known explorable area in m^2 (paper: 2)."""

    _constraints = {"time_reward": Interval(None, 0, "right"), "area_weight": _non_negative()}


@dataclass(frozen=True)
class SimConfig(_Checked):
    """The multi-robot simulator."""

    robots: int = 3
    """Team size (paper: 3)."""
    start_spread_m: float = 1.0
    """Drawn starts lie within this geodesic distance of the first robot, metres."""
    sensor: SensorConfig = field(default_factory=SensorConfig)
    motion: MotionConfig = field(default_factory=MotionConfig)
    reward: RewardConfig = field(default_factory=RewardConfig)

    _constraints = {"robots": _at_least(1), "start_spread_m": _non_negative("metres")}


@dataclass(frozen=True)
class PreprocessConfig(_Checked):
    """Layer 1: closing, frontier detection and Mean-Shift clustering (paper IV-A)."""

    closing_size_cells: int = 3
    """Side of the square structuring element of the closing (1: no closing)."""
    min_cluster_size: int = 2
    """Clusters with fewer members are dropped (paper: 2)."""
    bandwidth_percentile: float = 15.0
    """Mean-Shift bandwidth as this percentile of pairwise frontier distances (paper: 15)."""
    bandwidth_sample: int = 1000
    """At most this many frontier cells (an even stride over them) enter the percentile."""
    bandwidth_max_m: float | None = 6.0
    """Upper bound of the Mean-Shift bandwidth, metres; None: the percentile rule alone (the paper's).
    The rule scales with the frontier's extent: on a whole KTH floor it gives 7-10 m, so that 8 robots share
    a handful of clusters; one sensor range keeps clusters the size a robot sees at once (docs/performance.md,
    "Large floors and teams")."""
    drop_specks: bool = True
    """Before Mean-Shift, drop 8-connected pieces of F_un under ``min_cluster_size`` cells (the rule CoScan's
    and NCM's candidates follow), so every strategy ends on the same frontiers; False: the paper's rule
    alone (clusters under ``min_cluster_size`` members dropped after clustering), under which Mean-Shift
    gathers lone frontier cells near each other into clusters and robots chase them at the end of a
    mission."""
    split_for_team: bool = True
    """Where robots outnumber the Mean-Shift clusters, cut the largest while it holds ``split_min_frontier_m``
    of frontier or more, until there is one per robot
    (:func:`~mrexplore.preprocessing.clustering.split_for_team`); False: the paper's clusters, robots share.
    It matters to large teams on large floors (docs/performance.md, "Large floors and teams")."""
    split_min_frontier_m: float = 12.0
    """Under ``split_for_team``, a cluster is cut only while it holds this many metres of frontier (members
    x cell size) or more: at 12, each half keeps about a sensor range (6 m) of it; a shorter frontier
    is seen whole by the one robot already going there."""

    _constraints = {
        "closing_size_cells": Odd(1, None, "left"),
        "min_cluster_size": _at_least(1),
        "bandwidth_percentile": Interval(0, 100, "right"),
        "bandwidth_sample": _at_least(2),
        "bandwidth_max_m": _positive("metres", none="the percentile rule alone"),
        "split_min_frontier_m": _non_negative("metres"),
    }


@dataclass(frozen=True)
class GlobalPlanningConfig(_Checked):
    """Layer 2: weights of the classical assigners."""

    distance_weight: float = 3.0
    """explore_lite's potential_scale: cost per metre of geodesic distance."""
    size_weight: float = 1.0
    """explore_lite's gain_scale: reward per metre of frontier (members x resolution)."""
    gain_weight: float = -0.1
    """``hier-predict-heuristic``: reward per m^2 of the new free area a scan from a cluster's centre is
    predicted to see, on top of explore_lite's cost. Negative, as chosen on the 48 validation maps of
    training (-0.1 against 0.25, 0.1, 0.03 and -0.25): a cost, which sends robots first to the frontiers
    predicted to close soon, so that no pocket is left behind to come back for."""
    gain_range_m: float = 6.0
    """``hier-predict-heuristic``: range of the scan its predicted gain is cast with, metres (the sensor's
    default range)."""
    path_weight: float = 0.0
    """``hier-predict-heuristic``: cost per metre by which a cluster's path through predicted free space
    (known free cells and unknown ones predicted free) is shorter than its path through known free space:
    the predicted shortcut, a sign that the space behind the cluster also opens nearer the robot. 0: not
    computed (it costs one more distance field per robot at every decision). On the training's validation
    maps weights of -3 to 3 moved the steps by under 1%, every interval across zero (docs/prediction.md)."""
    commitment: float | None = None
    """Goal hysteresis at re-decisions: the cluster holding a robot's current goal is offered to it at this
    fraction of the distance to that goal, and a robot that keeps the cluster keeps its goal and route; 1: none
    (every decision starts afresh); None: the strategy's default (0.5 for strategies that go to cluster
    centres, 1 for hier, whose routes already commit)."""
    learned_min_robots: int = 2
    """``hier`` and ``hier-predict`` add their learned residual for teams of at least this many robots; a
    smaller team (a lone robot, or a team down to one) decides by the heuristic cost alone, as
    ``hier-heuristic`` (``hier-predict-heuristic``). The residual is a coordination policy, searched on
    teams of 2-5; with a lone robot it won nothing measurable on the training's validation maps (+2.0%
    [-1.3, +5.3] fewer steps than the heuristic with the 6 m sensor, +0.6% [-2.5, +3.6] with 8 m) and lost
    on held-out DungeonMaps (docs/learned.md). 1: the residual for every team."""
    far_above_cells: int = 2_000_000
    """Once the known passable cells' bounding box holds more cells than this, robot distances are exact
    only within ``exact_radius_m`` and estimated beyond it on a grid of ``coarse_cell_m`` blocks
    (:mod:`~mrexplore.paths.far_field`; paths driven stay exact); below it every distance is exact.
    Every dev map but the KTH floors is smaller than 2 M cells at 0.05 m (the largest, the ROS basement,
    has 1.44 M), so their results stay exact; a KTH floor at 0.05 m (up to 4.9 M) passes it."""
    exact_radius_m: float = 10.0
    """Path length from a robot within which its distances stay exact on large maps."""
    coarse_cell_m: float = 0.15
    """Side of the blocks that far distances are estimated on, metres (under two cells: all exact). Finer
    blocks reach cluster centres in ragged, ray-lit free space that coarser ones leave unreached (each then
    costs an exact search back from it)."""
    portal_sector_blocks: int = 24
    """Far distances are searched on a graph of portals between sectors of this many blocks a side
    (:mod:`~mrexplore.paths.portals`; 24 blocks of 0.15 m: 3.6 m), kept from decision to decision where
    the map did not change, instead of over every block; 0: over every block."""
    portal_spacing_blocks: int = 8
    """An opening between two sectors longer than this many blocks gets a portal per this many blocks
    (8 of 0.15 m: 1.2 m)."""

    _constraints = {
        "distance_weight": _non_negative(),
        "size_weight": _non_negative(),
        "gain_weight": Interval(-100, 100),
        "gain_range_m": _positive("metres"),
        "path_weight": Interval(-100, 100),
        "commitment": Interval(0, 1, none="the strategy's default"),
        "learned_min_robots": _at_least(1),
        "far_above_cells": _non_negative(),
        "exact_radius_m": _positive("metres"),
        "coarse_cell_m": _positive("metres"),
        "portal_sector_blocks": ZeroOr(2, None, "left"),
        "portal_spacing_blocks": _at_least(1),
    }


@dataclass(frozen=True)
class CoScanConfig(_Checked):
    """The CoScan-2D baseline (Dong et al. 2019): task sampling and geodesic Lloyd clustering."""

    task_spacing_m: float = 0.5
    """Frontier tasks are at least this far apart, metres."""
    tasks_per_robot: int = 6
    """At most this many tasks per robot; the farthest are dropped first."""
    delta_m: float = 2.0
    """A cluster reaching farther than this from its centroid is split; singletons this close merge, metres."""
    max_iterations: int = 10
    """Lloyd iterations at most."""

    _constraints = {
        "task_spacing_m": _positive("metres"),
        "tasks_per_robot": _at_least(1),
        "delta_m": _positive("metres"),
        "max_iterations": _at_least(1),
    }


@dataclass(frozen=True)
class LocalPlanningConfig(_Checked):
    """Layer 3: routing inside the assigned cluster (paper IV-C, eqs. 10-11)."""

    theta_members: int = 40
    """Route inside a cluster only when it has more members than this (paper's threshold theta; the paper
    gives no value: 40 members is 2 m of frontier at 0.05 m)."""
    k_g: float = 1.0
    """Rate of the gain normalisation of eq. 11 (paper: 1)."""
    k_l: float = 1.0
    """Rate of the cost normalisation of eq. 11 (paper: 1)."""
    upper_gain: float = 5.0
    """U_G, upper limit of the normalised gain (paper: 5)."""
    upper_cost: float = 5.0
    """U_L, upper limit scale of the normalised cost (paper: 5)."""
    c: float = 1.0
    """Balance factor of eq. 10 between gain and accumulated travel cost (paper: 1)."""
    epsilon: float = 1e-6
    """Guard against division by zero in eq. 11."""
    sub_bandwidth_m: float | None = None
    """Mean-Shift bandwidth of the sub-clustering, metres; None: the 15th-percentile rule of layer 1."""
    max_candidates: int = 30
    """At most this many sub-clusters (the largest) enter the route."""
    margin_m: float = 2.0
    """Distances between candidates are computed on the box around robot and cluster grown by this, m."""

    _constraints = {
        "theta_members": _at_least(1),
        "k_g": _positive(),
        "k_l": _positive(),
        "upper_gain": _positive(),
        "upper_cost": _positive(),
        "c": _non_negative(),
        "epsilon": _positive(),
        "sub_bandwidth_m": _positive("metres", none="the percentile rule of layer 1"),
        "max_candidates": _at_least(1),
        "margin_m": _non_negative("metres"),
    }


@dataclass(frozen=True)
class FaultConfig(_Checked):
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
        "comm_range_m": _positive("metres", none="unlimited"),
        "silence_rounds": _at_least(1),
    }

    def _validate(self) -> None:
        # YAML gives lists; the frozen config keeps tuples (hashable, and equal to the flags' value).
        given = self.robot_failures
        try:
            failures = tuple(tuple(f) for f in given)
        except TypeError:
            failures = ((-1,),)  # refused below with the value received
        _require(
            isinstance(self.centre_restarts, list | tuple), "centre_restarts", "a list of steps", self.centre_restarts
        )
        object.__setattr__(self, "robot_failures", failures)
        object.__setattr__(self, "centre_restarts", tuple(self.centre_restarts))
        for f in failures:
            _require(
                len(f) == 2 and all(_integer(v) and v >= 0 for v in f),
                "robot_failures",
                "(robot >= 0, step >= 0) integer pairs",
                given,
            )
        _require(len({r for r, _ in failures}) == len(failures), "robot_failures", "one entry per robot", failures)
        _require(
            all(_integer(s) and s >= 0 for s in self.centre_restarts),
            "centre_restarts",
            "integer steps >= 0",
            self.centre_restarts,
        )

    @property
    def any(self) -> bool:
        """Whether any fault is configured."""
        return bool(self.robot_failures or self.message_loss or self.centre_restarts or self.comm_range_m)


@dataclass(frozen=True)
class MissionConfig(_Checked):
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
        "max_steps": _at_least(1, name="max-steps"),
        "replan_every_steps": _at_least(1),
        "min_replan_steps": _at_least(1),
        "transmission": OneOf(("delta", "full")),
        "oscillation_radius_m": _positive("metres"),
        "oscillation_returns": _at_least(1),
        "stall_steps": _at_least(1),
    }


@dataclass(frozen=True)
class LearnedConfig(_Checked):
    """Layer 2, learned: the multi-graph network's inputs and size (paper IV-B, eqs. 4-8)."""

    hidden: int = 32
    """Width of node features, queries, keys and values (paper: 32)."""
    blocks: int = 2
    """Operation blocks of [self-graph, cross-graph] attention (paper: l)."""
    distance_scale_m: float = 10.0
    """Distances and coordinates are divided by this before entering the network, metres."""
    size_scale_m: float = 5.0
    """Cluster sizes (members x resolution) are divided by this, metres."""
    base_scale: float = 3.0
    """The heuristic part of the affinity is -(utility cost) / base_scale (one nat per metre of detour at
    explore_lite's weights)."""
    use_advantage: bool = True
    """Edge feature: d_ik - min over j != i of d_jk (how much nearer robot i is than its team-mates)."""
    use_current_goal: bool = True
    """Edge feature: cluster k holds robot i's current goal (learned hysteresis)."""
    use_isolation: bool = True
    """Edge feature: distance from cluster k to its nearest other cluster centre (straight line: a
    geodesic per centre costs more than the rest of a decision on large maps)."""
    use_predicted_gain: bool = False
    """Edge feature (a sixth, for a policy trained with it): the new free area a scan from cluster k's centre
    is predicted to see on the map predictor's completion of the belief, m^2 / ``gain_scale_m2``."""
    gain_scale_m2: float = 10.0
    """The predicted gain is divided by this before entering the network, m^2."""
    use_predicted_path: bool = False
    """Edge feature (after the predicted gain where both are read, for a policy trained with it): robot i's
    predicted shortcut to cluster k, how much shorter its path is through predicted free space (known free
    cells and unknown ones predicted free) than through known free space, metres / ``distance_scale_m``."""

    @property
    def reads_prediction(self) -> bool:
        """The network reads a map predictor's completion of the belief (gain or shortcut)."""
        return self.use_predicted_gain or self.use_predicted_path

    _constraints = {
        "hidden": Interval(4, 1024),
        "blocks": Interval(1, 16),
        "distance_scale_m": _positive("metres"),
        "size_scale_m": _positive("metres"),
        "base_scale": _positive(),
        "gain_scale_m2": _positive(),
    }


@dataclass(frozen=True)
class NcmTrainConfig(_Checked):
    """PPO of the NeuralCoMapping baseline, with its public code's settings (Ye, Dong et al., CVPR 2022)."""

    ppo_iterations: int = 40
    """PPO iterations (stages ppo0...)."""
    ppo_episodes: int = 8
    """Episodes collected per iteration."""
    ppo_epochs: int = 4
    """Passes over a batch."""
    lr: float = 5e-4
    """Adam learning rate of the actor."""
    critic_lr_ratio: float = 1.0
    """The critic's learning rate is the actor's times this. NCM's is 0.05 for its CNN critic over the maps;
    ours (:class:`~mrexplore.global_planning.learned.ncm_network.NcmCritic`) is a small MLP, which at 0.05
    would barely move from its start in a run of this project's length."""
    gamma: float = 0.99
    """Discount per 25 simulation steps (NCM's decision; a decision of k steps discounts by gamma^(k/25))."""
    gae_lambda: float = 0.95
    """GAE tau."""
    clip: float = 0.2
    """PPO ratio clip."""
    value_coef: float = 3.0
    """Weight of the value loss."""
    entropy_coef: float = 1e-4
    """Weight of the entropy bonus."""
    area_reward: float = 5e-3
    """Reward per newly explored m^2."""
    area_offset_m2: float = 4.0
    """m^2 subtracted from a 25-step decision's new area (in proportion for other lengths)."""
    select: str = "sampled"
    """Which validation keeps a checkpoint (both are logged): ``sampled`` (NCM's own evaluation, each robot
    drawing its node; seeded, so repeatable) or ``argmax``. A PPO policy is trained as a sampler, and its
    argmax decoding can lag the untrained network's while its sampled episodes improve."""

    _constraints = {
        "ppo_iterations": _at_least(1),
        "ppo_episodes": _at_least(1),
        "ppo_epochs": _at_least(1),
        "lr": _positive(),
        "critic_lr_ratio": _positive(),
        "gamma": Interval(0, 1, "right"),
        "gae_lambda": Interval(0, 1),
        "clip": _positive(),
        "value_coef": _non_negative(),
        "entropy_coef": _non_negative(),
        "area_reward": _positive(),
        "area_offset_m2": _non_negative(),
        "select": OneOf(("sampled", "argmax")),
    }


TRAINABLE = ("hier", "ncm")
"""Strategies ``mrexplore train`` trains."""


@dataclass(frozen=True)
class TrainConfig(_Checked):
    """Training of a learned global layer: for ``hier``, imitation of a lookahead expert (DAgger), then PPO
    on eq. 9; for ``ncm``, NeuralCoMapping's PPO (:class:`NcmTrainConfig`). Both share the map split,
    episode settings, validation and checkpoints."""

    strategy: str = "hier"
    """What is trained: ``hier`` (the paper's mGNN) or ``ncm`` (the NeuralCoMapping baseline)."""
    learned: LearnedConfig = field(default_factory=LearnedConfig)
    ncm: NcmTrainConfig = field(default_factory=NcmTrainConfig)
    resolution_m: float = 0.1
    """Cell size of training maps, metres."""
    robots_min: int = 2
    """Fewest robots of a training episode."""
    robots_max: int = 5
    """Most robots of a training episode."""
    max_steps: int = 1500
    """Step budget of a training episode."""
    generated_share: float = 0.5
    """Share of training episodes on procedural floor plans (the rest on training DungeonMaps)."""
    plans: str = "varied"
    """Procedural floor plans of training and validation: ``varied`` (``varied:SEED``, whose size, outline,
    rooms, corridor, doors and clutter the seed draws, spread like HouseExpo's: ``benchmarks/plan_stats.py``)
    or ``generated`` (``generated:SEED``, the 16 x 12 m built-in plan)."""
    val_maps: int = 64
    """Validation episodes per evaluation: half held-out training DungeonMaps, half held-out floor plans.
    Too few let a stage win validation by chance."""
    val_robots: int = 3
    """Robots in every validation episode: the team of the dev set's Table I (training draws
    ``robots_min`` to ``robots_max``)."""
    score: str = "steps"
    """How the policy search ranks its vectors and validation picks the stage kept: ``steps`` (mean steps
    to the end, the largest maps weighing most) or ``relative`` (every episode weighing the same: the
    geometric mean over episodes of its steps to the end plus to 99% coverage, over those of the
    generation's current weights in the search and of the heuristic in validation; see
    :func:`~mrexplore.training.search.relative_score`)."""
    # -- policy search on the linear edge path (cross-entropy method)
    search_generations: int = 6
    """Generations of the cross-entropy search over the residual's linear edge weights (one per edge
    feature), before imitation: each draws ``search_population`` weight vectors around the current
    ones (the current ones among them), runs every vector on the same ``search_episodes`` training
    episodes, and moves to the mean and spread of the ``search_elites`` that score best (``score``)."""
    search_population: int = 8
    """Weight vectors tried per generation (the current mean is one of them)."""
    search_elites: int = 3
    """Vectors with the best score (fewest mean steps by default) that set the next mean and spread."""
    search_episodes: int = 48
    """Training episodes each vector of a generation runs (the same ones for every vector)."""
    search_sigma: float = 5.0
    """Spread of the first generation, per weight (a weight of 5 on the isolation feature, in tenths of
    metres, offers an isolated cluster 0.5 m nearer per metre to its nearest other cluster)."""
    search_sigma_min: float = 0.5
    """The spread never falls below this (keeps a noisy ranking from freezing the search)."""
    # -- imitation of the lookahead expert
    dagger_rounds: int = 2
    """Rounds of (collect on the student's own states, fit); round 0's student is the policy the
    search left (the heuristic when it ran none)."""
    episodes_per_round: int = 10
    """Training episodes collected per DAgger round."""
    label_every: int = 4
    """Every this many decisions of an episode the expert labels (the others just move it on)."""
    horizon_steps: int = 400
    """Each expert candidate is run this many simulation steps forward. Short horizons are myopic:
    candidates that grab open area and leave pockets behind rank first."""
    expert_world: str = "truth"
    """Where the expert runs its candidates forward: ``truth`` (the simulator's map, scored by eq. 9's
    return over ``horizon_steps``) or ``known`` (the world the team has observed, every unseen cell a
    wall, scored by minus the steps until no frontier is left; labels a student could learn from what it
    sees: :func:`~mrexplore.training.expert.known_world_returns`)."""
    noisy_candidates: int = 4
    """Noisy utility assignments among the expert's candidates."""
    noise_m: float = 4.0
    """Gumbel scale of the noise on the utility cost of noisy candidates, metres of detour."""
    return_temperature: float = 10.0
    """Target of the listwise loss: softmax(candidate return / this)."""
    imitation_epochs: int = 8
    """Passes over the aggregated expert data per round (too many overfit single-rollout labels)."""
    lr: float = 1e-3
    """Adam learning rate of imitation."""
    weight_decay: float = 1e-4
    """Adam weight decay."""
    residual_l2: float = 0.01
    """Weight of the mean squared residual in the imitation loss: the network departs from the heuristic
    only where the expert's data insist."""
    # -- PPO on eq. 9
    ppo_iterations: int = 0
    """PPO iterations after imitation (none in the shipped recipe: its sampled policy explores worse than
    the decoded one, and no PPO iteration has beaten the best imitation stage on validation)."""
    ppo_episodes: int = 12
    """Episodes collected per PPO iteration."""
    ppo_epochs: int = 4
    """Passes over a PPO batch."""
    ppo_lr: float = 3e-4
    """Adam learning rate of PPO."""
    gamma: float = 0.995
    """Discount per simulation step (a decision spanning k steps discounts by gamma^k)."""
    gae_lambda: float = 0.95
    """GAE lambda."""
    clip: float = 0.2
    """PPO ratio clip."""
    value_coef: float = 0.5
    """Weight of the value loss."""
    entropy_coef: float = 0.01
    """Weight of the entropy bonus."""
    reward_scale: float = 0.01
    """Rewards of eq. 9 are multiplied by this for the critic's sake."""
    imitation_coef: float = 1.0
    """Weight of the listwise expert loss kept during PPO on the aggregated data (keeps the policy near
    the expert while RL fine-tunes)."""

    _constraints = {
        "strategy": OneOf(TRAINABLE),
        "resolution_m": _positive("metres"),
        "robots_min": _at_least(1),
        "robots_max": _at_least("robots_min"),
        "max_steps": _at_least(1),
        "generated_share": Interval(0, 1),
        "plans": OneOf(("varied", "generated")),
        "val_maps": _at_least(1),
        "val_robots": _at_least(1),
        "score": OneOf(("steps", "relative")),
        "search_generations": _non_negative(),
        "search_population": _at_least(2),
        "search_elites": Interval(1, "search_population"),
        "search_episodes": _at_least(1),
        "search_sigma": _positive(),
        "search_sigma_min": _positive(),
        "dagger_rounds": _non_negative(),
        "episodes_per_round": _at_least(1),
        "label_every": _at_least(1),
        "horizon_steps": _at_least(1),
        "expert_world": OneOf(("truth", "known")),
        "noisy_candidates": _non_negative(),
        "noise_m": _positive(),
        "return_temperature": _positive(),
        "imitation_epochs": _at_least(1),
        "lr": _positive(),
        "weight_decay": _non_negative(),
        "residual_l2": _non_negative(),
        "ppo_iterations": _non_negative(),
        "ppo_episodes": _at_least(1),
        "ppo_epochs": _at_least(1),
        "ppo_lr": _positive(),
        "gamma": Interval(0, 1, "right"),
        "gae_lambda": Interval(0, 1),
        "clip": _positive(),
        "value_coef": _non_negative(),
        "entropy_coef": _non_negative(),
        "reward_scale": _positive(),
        "imitation_coef": _non_negative(),
    }


@dataclass(frozen=True)
class PredictorTrainConfig(_Checked):
    """The learned map predictor and its training (``mrexplore train --predictor``): the team's belief taken
    at random decisions of missions on the training maps (never the dev maps), the ground truth as the label;
    the loss and the scores count the unknown cells near a frontier."""

    cell_m: float = 0.2
    """Side of the predictor's cells, metres: the belief is pooled onto them (0.1 m planning cells two by
    two) and the prediction repeated back onto the planning cells."""
    width: int = 8
    """Channels of the U-Net's finest level (doubled at each of its two coarser levels)."""
    resolution_m: float = 0.1
    """Cell size of the collection missions, metres."""
    collector: str = "hier-heuristic"
    """Strategy of the collection missions (whose beliefs the predictor learns to complete)."""
    missions: int = 480
    """Training missions collected, each on a training DungeonMap or a procedural plan."""
    val_missions: int = 48
    """Validation missions: half on held-out training DungeonMaps, half on held-out procedural plans."""
    moments: int = 4
    """Beliefs kept per mission, drawn at random among its decisions within the coverage range."""
    min_coverage: float = 0.1
    """Beliefs are drawn from decisions with at least this coverage."""
    max_coverage: float = 0.9
    """... and at most this coverage."""
    robots_min: int = 1
    """Fewest robots of a collection mission."""
    robots_max: int = 5
    """Most robots of a collection mission."""
    max_steps: int = 1500
    """Step budget of a collection mission."""
    generated_share: float = 0.5
    """Share of collection missions on procedural floor plans (the rest on training DungeonMaps)."""
    plans: str = "varied"
    """Procedural floor plans of collection and validation (see :class:`TrainConfig`)."""
    band_m: float = 6.0
    """The loss and the validation scores count the unknown cells within this distance of a frontier."""
    crop_cells: int = 64
    """Side of a training crop, predictor cells (a multiple of 4), around a random cell of the band."""
    batch: int = 32
    """Crops per gradient step."""
    epochs: int = 60
    """Epochs at most (the minutes budget may stop it first); the epoch of least validation loss is kept."""
    steps_per_epoch: int = 200
    """Gradient steps per epoch, each on fresh random crops."""
    lr: float = 2e-3
    """Adam learning rate."""
    weight_decay: float = 1e-5
    """Adam weight decay."""

    _constraints = {
        "cell_m": _positive("metres"),
        "width": Interval(1, 256),
        "resolution_m": _positive("metres"),
        "collector": OneOf(("hier-heuristic", "utility", "nearest")),
        "missions": _at_least(1),
        "val_missions": _at_least(1),
        "moments": _at_least(1),
        "min_coverage": Interval(0, 1),
        "max_coverage": Interval("min_coverage", 1),
        "robots_min": _at_least(1),
        "robots_max": _at_least("robots_min"),
        "max_steps": _at_least(1),
        "generated_share": Interval(0, 1),
        "plans": OneOf(("varied", "generated")),
        "band_m": _positive("metres"),
        "crop_cells": _at_least(8),
        "batch": _at_least(1),
        "epochs": _at_least(1),
        "steps_per_epoch": _at_least(1),
        "lr": _positive(),
        "weight_decay": _non_negative(),
    }

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.crop_cells % 4:
            raise MrExploreError(f"predictor.crop_cells must be a multiple of 4, got {self.crop_cells}")


@dataclass(frozen=True)
class RunConfig(_Checked):
    """Every setting of a run, one section per part: the YAML file that ``--config`` reads on explore,
    bench and train (``mrexplore config`` prints the defaults). A section or field left out keeps its
    default; flags given on the command line override the file."""

    map: MapConfig = field(default_factory=MapConfig)
    sim: SimConfig = field(default_factory=SimConfig)
    mission: MissionConfig = field(default_factory=MissionConfig)
    preprocess: PreprocessConfig = field(default_factory=PreprocessConfig)
    global_planning: GlobalPlanningConfig = field(default_factory=GlobalPlanningConfig)
    local_planning: LocalPlanningConfig = field(default_factory=LocalPlanningConfig)
    coscan: CoScanConfig = field(default_factory=CoScanConfig)
    train: TrainConfig = field(default_factory=TrainConfig)
    """Training only (``mrexplore train``), which also reads ``sim`` and ``mission`` (its faults and
    replanning; the step budget is ``train.max_steps``)."""
    predictor: PredictorTrainConfig = field(default_factory=PredictorTrainConfig)
    """The map predictor's training only (``mrexplore train --predictor``), which also reads ``sim``."""


def config_from_dict(cls: type[Any], data: dict[str, Any], where: str = "") -> Any:
    """Rebuild a config dataclass from :func:`config_to_dict` output (nested configs too); unknown keys
    are refused by name (``where`` prefixes the names in messages, e.g. ``sim.``)."""
    import dataclasses

    if not isinstance(data, dict):
        raise MrExploreError(
            f"{where.rstrip('.') or 'the config'} must be a mapping of {cls.__name__} fields, got {data!r}"
        )
    names = {f.name: f for f in dataclasses.fields(cls)}
    unknown = sorted(str(k) for k in set(data) - set(names))
    if unknown:
        raise MrExploreError(
            f"unknown {cls.__name__} keys {', '.join(where + k for k in unknown)}; known: {', '.join(names)}"
        )
    kwargs: dict[str, Any] = {}
    for k, v in data.items():
        factory = names[k].default_factory
        sub = type(factory()) if callable(factory) else None
        if sub is not None and dataclasses.is_dataclass(sub):
            kwargs[k] = config_from_dict(sub, v, f"{where}{k}.")
        else:
            kwargs[k] = v
    try:
        return cls(**kwargs)
    except MrExploreError as exc:
        raise MrExploreError(f"{where}{exc}" if where else str(exc)) from None


def read_config_file(path: str | Path, max_bytes: int = 1 << 20) -> RunConfig:
    """The :class:`RunConfig` of a YAML file; any problem is one :class:`MrExploreError` naming the file.

    Only plain YAML is read (no tags, no aliases), at most ``max_bytes``."""
    from mrexplore.safe_yaml import load_yaml_file

    p = Path(path)
    if not p.is_file():
        raise MrExploreError(f"--config file {p} not found; 'mrexplore config > {p.name}' writes the defaults")
    data = load_yaml_file(p, f"--config file {p}", max_bytes)
    if data is None:
        return RunConfig()
    try:
        return config_from_dict(RunConfig, data)
    except MrExploreError as exc:
        raise MrExploreError(f"--config file {p}: {exc}") from None


def config_yaml(cfg: Any) -> str:
    """A config as YAML, each field with its documentation as a comment: what ``mrexplore config`` prints
    and ``--config`` reads back (tuples are written as lists)."""
    docs = _field_docs()
    lines: list[str] = []

    def emit(obj: Any, indent: int) -> None:
        pad = "  " * indent
        for f in fields(obj):
            value = getattr(obj, f.name)
            doc = docs.get((type(obj).__name__, f.name), "")
            rule = obj._constraints.get(f.name)
            if rule is not None:
                doc = f"{doc} Allowed: {rule.describe()}.".strip()
            if doc:
                lines.append(f"{pad}# {doc}")
            if is_dataclass(value):
                lines.append(f"{pad}{f.name}:")
                emit(value, indent + 1)
            else:
                lines.append(f"{pad}{f.name}: {_yaml_scalar(value)}")

    emit(cfg, 0)
    return "\n".join(lines) + "\n"


def _yaml_scalar(value: Any) -> str:
    import yaml

    plain = [list(v) if isinstance(v, tuple) else v for v in value] if isinstance(value, tuple) else value
    return str(yaml.safe_dump(plain, default_flow_style=True, width=10**6)).strip().removesuffix("...").strip()


@functools.cache
def _field_docs() -> dict[tuple[str, str], str]:
    """``{(class, field): first sentence of its docstring}`` read from this module's source."""
    import ast
    import inspect
    import sys

    tree = ast.parse(inspect.getsource(sys.modules[__name__]))
    out: dict[tuple[str, str], str] = {}
    for node in tree.body:
        if not isinstance(node, ast.ClassDef):
            continue
        body = node.body
        for a, b in zip(body, body[1:], strict=False):
            if (
                isinstance(a, ast.AnnAssign)
                and isinstance(a.target, ast.Name)
                and isinstance(b, ast.Expr)
                and isinstance(b.value, ast.Constant)
                and isinstance(b.value.value, str)
            ):
                out[(node.name, a.target.id)] = " ".join(b.value.value.split())
    return out


def config_to_dict(cfg: Any) -> dict[str, Any]:
    """Plain ``dict`` of a config dataclass (nested), for result files and checkpoints."""
    return asdict(cfg)
