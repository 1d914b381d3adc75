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
from typing import Any

from mrexplore.types import MrExploreError

__all__ = [
    "MapConfig",
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

    def __post_init__(self) -> None:
        hints = _hints(type(self).__qualname__)
        for f in fields(self):  # type: ignore[arg-type]
            _check_type(f.name, getattr(self, f.name), hints[f.name])
        self._validate()

    def _validate(self) -> None:
        """The class's range rules."""


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


@dataclass(frozen=True)
class MapConfig(_Checked):
    """How a map file becomes a ground-truth grid."""

    resolution_m: float = 0.05
    """Working cell size, metres per cell, > 0 (paper: 0.05)."""
    pixel_size_m: float | None = None
    """Metres per pixel of an image with no YAML, > 0; None: 0.01 for grayscale, 0.1 for DungeonMaps."""
    outside_opening_m: float = 1.5
    """Free space reaching the border through passages wider than twice this is outside, metres, > 0."""
    min_passage_m: float = 0.1
    """Free passages narrower than this are closed: no robot fits (HouseExpo renders leave 1-6 cm slivers
    where walls meet), metres, >= 0 (0: keep every gap)."""
    max_cells: int = 60_000_000
    """A map whose working grid would hold more cells is refused before it is built (a 60 M-cell grid takes
    several GB across the simulator's layers), >= 1."""
    max_image_pixels: int = 400_000_000
    """A map image (or HouseExpo raster at 1 cm) with more pixels is refused before it is decoded, >= 1."""
    max_file_bytes: int = 256_000_000
    """A map file (image, JSON) larger than this is refused before it is read, >= 1."""

    def _validate(self) -> None:
        _require(self.resolution_m > 0, "resolution", "> 0 metres", self.resolution_m)
        _require(self.outside_opening_m > 0, "outside_opening_m", "> 0 metres", self.outside_opening_m)
        _require(self.min_passage_m >= 0, "min_passage_m", ">= 0 metres", self.min_passage_m)
        for name in ("max_cells", "max_image_pixels", "max_file_bytes"):
            _require(getattr(self, name) >= 1, name, ">= 1", getattr(self, name))
        if self.pixel_size_m is not None:
            _require(self.pixel_size_m > 0, "pixel-size", "> 0 metres", self.pixel_size_m)


@dataclass(frozen=True)
class SensorConfig(_Checked):
    """360° 2D LiDAR and the log-odds belief it updates (paper eq. 1)."""

    range_m: float = 6.0
    """Maximum range, metres, > 0 (paper: 6 m)."""
    ray_oversampling: float = 1.0
    """Beams per cell of circumference at full range, >= 1; 1 already leaves no gap within range - 0.5 cell."""
    p_hit: float = 0.7
    """P(occupied | beam ends in cell), in (0.5, 1) (OctoMap's default)."""
    p_miss: float = 0.4
    """P(occupied | beam passes through cell), in (0, 0.5) (OctoMap's default)."""
    p_clamp_min: float = 0.12
    """Lower clamp of the occupancy probability, in (0, 0.5) (OctoMap's default)."""
    p_clamp_max: float = 0.97
    """Upper clamp of the occupancy probability, in (0.5, 1) (OctoMap's default)."""
    p_occupied: float = 0.5
    """An observed cell is occupied when its probability exceeds this, in (0, 1); else free."""
    range_noise_m: float = 0.0
    """Standard deviation of Gaussian range noise, metres, >= 0 (0: noiseless)."""

    def _validate(self) -> None:
        _require(self.range_m > 0, "range_m", "> 0 metres", self.range_m)
        _require(self.ray_oversampling >= 1, "ray_oversampling", ">= 1", self.ray_oversampling)
        _require(0.5 < self.p_hit < 1, "p_hit", "in (0.5, 1)", self.p_hit)
        _require(0 < self.p_miss < 0.5, "p_miss", "in (0, 0.5)", self.p_miss)
        _require(0 < self.p_clamp_min < 0.5, "p_clamp_min", "in (0, 0.5)", self.p_clamp_min)
        _require(0.5 < self.p_clamp_max < 1, "p_clamp_max", "in (0.5, 1)", self.p_clamp_max)
        _require(0 < self.p_occupied < 1, "p_occupied", "in (0, 1)", self.p_occupied)
        _require(self.range_noise_m >= 0, "range_noise_m", ">= 0 metres", self.range_noise_m)


@dataclass(frozen=True)
class MotionConfig(_Checked):
    """How far a robot drives per simulation step."""

    step_m: float = 0.1
    """Distance driven per step along the path, metres, > 0 (the mission's clock)."""

    def _validate(self) -> None:
        _require(self.step_m > 0, "step_m", "> 0 metres", self.step_m)


@dataclass(frozen=True)
class RewardConfig(_Checked):
    """Team reward of paper eq. 9: R = R_time + lambda * R_area."""

    time_reward: float = -1.0
    """R_time, the fixed reward per step, <= 0."""
    area_weight: float = 2.0
    """lambda, weight of newly known explorable area in m^2, >= 0 (paper: 2)."""

    def _validate(self) -> None:
        _require(self.time_reward <= 0, "time_reward", "<= 0", self.time_reward)
        _require(self.area_weight >= 0, "area_weight", ">= 0", self.area_weight)


@dataclass(frozen=True)
class SimConfig(_Checked):
    """The multi-robot simulator."""

    robots: int = 3
    """Team size, >= 1 (paper: 3)."""
    start_spread_m: float = 1.0
    """Drawn starts lie within this geodesic distance of the first robot, metres, >= 0."""
    sensor: SensorConfig = field(default_factory=SensorConfig)
    motion: MotionConfig = field(default_factory=MotionConfig)
    reward: RewardConfig = field(default_factory=RewardConfig)

    def _validate(self) -> None:
        _require(self.robots >= 1, "robots", ">= 1", self.robots)
        _require(self.start_spread_m >= 0, "start_spread_m", ">= 0 metres", self.start_spread_m)


@dataclass(frozen=True)
class PreprocessConfig(_Checked):
    """Layer 1: closing, frontier detection and Mean-Shift clustering (paper IV-A)."""

    closing_size_cells: int = 3
    """Side of the square structuring element of the closing, odd, >= 1 (1: no closing)."""
    min_cluster_size: int = 2
    """Clusters with fewer members are dropped (paper: 2), >= 1."""
    bandwidth_percentile: float = 15.0
    """Mean-Shift bandwidth as this percentile of pairwise frontier distances (paper: 15), in (0, 100]."""
    bandwidth_sample: int = 1000
    """At most this many frontier cells (an even stride over them) enter the percentile, >= 2."""
    bandwidth_max_m: float | None = 6.0
    """Upper bound of the Mean-Shift bandwidth, metres, > 0; None: the percentile rule alone (the paper's).
    The rule scales with the frontier's extent: on a whole KTH floor it gives 7-10 m, so 8 robots share
    6-9 clusters of the whole floor. At one sensor range (6 m) learned ``hier`` took 29% fewer steps on
    PLAN1-3 (9 paired episodes) and 4% fewer on the seven smaller KTH floors, and changed the dev set's
    HouseExpo and DungeonMaps episodes at 0.1 m by under 1% (docs/speed.md, "A bound on the Mean-Shift
    bandwidth")."""
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
    On a whole KTH floor at 0.05 m it took 16 robots to 99% coverage in 5,521 steps instead of 8,698; on
    the dev set it changed none of 408 episodes with 3 robots (docs/speed.md, "Large floors and teams")."""
    split_min_frontier_m: float = 12.0
    """Under ``split_for_team``, a cluster is cut only while it holds this many metres of frontier (members
    x cell size) or more, >= 0: at 12, each half keeps about a sensor range (6 m) of it; a shorter frontier
    is seen whole by the one robot already going there."""

    def _validate(self) -> None:
        _require(
            self.closing_size_cells >= 1 and self.closing_size_cells % 2 == 1,
            "closing_size_cells",
            "odd and >= 1",
            self.closing_size_cells,
        )
        _require(self.min_cluster_size >= 1, "min_cluster_size", ">= 1", self.min_cluster_size)
        _require(0 < self.bandwidth_percentile <= 100, "bandwidth_percentile", "in (0, 100]", self.bandwidth_percentile)
        _require(self.bandwidth_sample >= 2, "bandwidth_sample", ">= 2", self.bandwidth_sample)
        _require(
            self.bandwidth_max_m is None or (math.isfinite(self.bandwidth_max_m) and self.bandwidth_max_m > 0),
            "bandwidth_max_m",
            "> 0 metres, or null for the percentile rule alone",
            self.bandwidth_max_m,
        )
        _require(
            math.isfinite(self.split_min_frontier_m) and self.split_min_frontier_m >= 0,
            "split_min_frontier_m",
            ">= 0 metres",
            self.split_min_frontier_m,
        )


@dataclass(frozen=True)
class GlobalPlanningConfig(_Checked):
    """Layer 2: weights of the classical assigners."""

    distance_weight: float = 3.0
    """explore_lite's potential_scale: cost per metre of geodesic distance, >= 0."""
    size_weight: float = 1.0
    """explore_lite's gain_scale: reward per metre of frontier (members x resolution), >= 0."""
    commitment: float | None = None
    """Goal hysteresis at re-decisions: the cluster holding a robot's current goal is offered to it at this
    fraction of the distance to that goal, and a robot that keeps the cluster keeps its goal and route,
    in [0, 1]; 1: none (every decision starts afresh); None: the strategy's default (0.5 for strategies
    that go to cluster centres, 1 for hier, whose routes already commit)."""
    far_above_cells: int = 2_000_000
    """Once the known passable cells' bounding box holds more cells than this, robot distances are exact
    only within ``exact_radius_m`` and estimated beyond it on a grid of ``coarse_cell_m`` blocks
    (:mod:`~mrexplore.paths.far_field`; paths driven stay exact), >= 0; below it every distance is exact.
    Every dev map but the KTH floors is smaller than 2 M cells at 0.05 m (the largest, the ROS basement,
    has 1.44 M), so their results stay exact; a KTH floor at 0.05 m (up to 4.9 M) passes it."""
    exact_radius_m: float = 10.0
    """Path length from a robot within which its distances stay exact on large maps, > 0 metres."""
    coarse_cell_m: float = 0.15
    """Side of the blocks that far distances are estimated on, > 0 metres (under two cells: all exact).
    Late on a KTH floor at 0.05 m, blocks of 0.2 m left cluster centres in ragged, ray-lit free space
    unreached (each then costs an exact search back from it); 0.15 m reached all of them
    (``perf/bench_far_fields.py``)."""
    portal_sector_blocks: int = 24
    """Far distances are searched on a graph of portals between sectors of this many blocks a side
    (:mod:`~mrexplore.paths.portals`; 24 blocks of 0.15 m: 3.6 m), kept from decision to decision where
    the map did not change, instead of over every block; 0: over every block. 0 or >= 2."""
    portal_spacing_blocks: int = 8
    """An opening between two sectors longer than this many blocks gets a portal per this many blocks
    (8 of 0.15 m: 1.2 m), >= 1."""

    def _validate(self) -> None:
        _require(self.distance_weight >= 0, "distance_weight", ">= 0", self.distance_weight)
        _require(
            self.portal_sector_blocks == 0 or self.portal_sector_blocks >= 2,
            "portal_sector_blocks",
            "0 or >= 2",
            self.portal_sector_blocks,
        )
        _require(self.portal_spacing_blocks >= 1, "portal_spacing_blocks", ">= 1", self.portal_spacing_blocks)
        _require(self.size_weight >= 0, "size_weight", ">= 0", self.size_weight)
        _require(self.far_above_cells >= 0, "far_above_cells", ">= 0", self.far_above_cells)
        _require(
            math.isfinite(self.exact_radius_m) and self.exact_radius_m > 0,
            "exact_radius_m",
            "> 0 metres",
            self.exact_radius_m,
        )
        _require(
            math.isfinite(self.coarse_cell_m) and self.coarse_cell_m > 0,
            "coarse_cell_m",
            "> 0 metres",
            self.coarse_cell_m,
        )
        if self.commitment is not None:
            _require(0 <= self.commitment <= 1, "commitment", "in [0, 1] or None", self.commitment)


@dataclass(frozen=True)
class CoScanConfig(_Checked):
    """The CoScan-2D baseline (Dong et al. 2019): task sampling and geodesic Lloyd clustering."""

    task_spacing_m: float = 0.5
    """Frontier tasks are at least this far apart, metres, > 0."""
    tasks_per_robot: int = 6
    """At most this many tasks per robot; the farthest are dropped first, >= 1."""
    delta_m: float = 2.0
    """A cluster reaching farther than this from its centroid is split; singletons this close merge, metres, > 0."""
    max_iterations: int = 10
    """Lloyd iterations at most, >= 1."""

    def _validate(self) -> None:
        _require(self.task_spacing_m > 0, "task_spacing_m", "> 0 metres", self.task_spacing_m)
        _require(self.tasks_per_robot >= 1, "tasks_per_robot", ">= 1", self.tasks_per_robot)
        _require(self.delta_m > 0, "delta_m", "> 0 metres", self.delta_m)
        _require(self.max_iterations >= 1, "max_iterations", ">= 1", self.max_iterations)


@dataclass(frozen=True)
class LocalPlanningConfig(_Checked):
    """Layer 3: routing inside the assigned cluster (paper IV-C, eqs. 10-11)."""

    theta_members: int = 40
    """Route inside a cluster only when it has more members than this (paper's threshold theta; the paper
    gives no value: 40 members is 2 m of frontier at 0.05 m), >= 1."""
    k_g: float = 1.0
    """Rate of the gain normalisation of eq. 11 (paper: 1), > 0."""
    k_l: float = 1.0
    """Rate of the cost normalisation of eq. 11 (paper: 1), > 0."""
    upper_gain: float = 5.0
    """U_G, upper limit of the normalised gain (paper: 5), > 0."""
    upper_cost: float = 5.0
    """U_L, upper limit scale of the normalised cost (paper: 5), > 0."""
    c: float = 1.0
    """Balance factor of eq. 10 between gain and accumulated travel cost (paper: 1), >= 0."""
    epsilon: float = 1e-6
    """Guard against division by zero in eq. 11, > 0."""
    sub_bandwidth_m: float | None = None
    """Mean-Shift bandwidth of the sub-clustering, metres; None: the 15th-percentile rule of layer 1."""
    max_candidates: int = 30
    """At most this many sub-clusters (the largest) enter the route, >= 1."""
    margin_m: float = 2.0
    """Distances between candidates are computed on the box around robot and cluster grown by this, m, >= 0."""

    def _validate(self) -> None:
        _require(self.theta_members >= 1, "theta_members", ">= 1", self.theta_members)
        for name in ("k_g", "k_l", "upper_gain", "upper_cost", "epsilon"):
            _require(getattr(self, name) > 0, name, "> 0", getattr(self, name))
        _require(self.c >= 0, "c", ">= 0", self.c)
        if self.sub_bandwidth_m is not None:
            _require(self.sub_bandwidth_m > 0, "sub_bandwidth_m", "> 0 metres or None", self.sub_bandwidth_m)
        _require(self.max_candidates >= 1, "max_candidates", ">= 1", self.max_candidates)
        _require(self.margin_m >= 0, "margin_m", ">= 0 metres", self.margin_m)


@dataclass(frozen=True)
class FaultConfig(_Checked):
    """Faults injected into a mission: lost robots, lost messages, a restarting centre, limited radio range."""

    robot_failures: tuple[tuple[int, int], ...] = ()
    """``(robot, step)`` pairs: at that simulation step the robot stops driving, scanning and sending for
    good; robot ids count from 0, steps >= 0. A robot id beyond the team is refused by the mission."""
    message_loss: float = 0.0
    """Probability that one robot-to-centre message, or one centre-to-robot acknowledgement, is lost
    (independent draws from the mission's seed), in [0, 1)."""
    centre_restarts: tuple[int, ...] = ()
    """Simulation steps at which the centre loses all its state (robot maps, what it acknowledged, its
    blacklist); it rebuilds from the next messages, steps >= 0."""
    comm_range_m: float | None = None
    """A robot farther than this straight-line distance from the relay (the first robot's start) cannot
    send; it keeps exploring on its own grid and syncs when back in range, metres, > 0; None: unlimited."""
    silence_rounds: int = 3
    """The centre stops assigning goals to a robot it has not heard from in this many rounds, >= 1."""

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
        _require(0 <= self.message_loss < 1, "message_loss", "in [0, 1)", self.message_loss)
        if self.comm_range_m is not None:
            _require(self.comm_range_m > 0, "comm_range_m", "> 0 metres", self.comm_range_m)
        _require(self.silence_rounds >= 1, "silence_rounds", ">= 1", self.silence_rounds)

    @property
    def any(self) -> bool:
        """Whether any fault is configured."""
        return bool(self.robot_failures or self.message_loss or self.centre_restarts or self.comm_range_m)


@dataclass(frozen=True)
class MissionConfig(_Checked):
    """One exploration mission: replanning events and the step budget."""

    max_steps: int = 20000
    """Step budget, >= 1; reaching it ends the mission as ``max_steps`` (truncated, never success)."""
    replan_every_steps: int = 25
    """A decision is taken at least this often, steps, >= 1."""
    min_replan_steps: int = 10
    """A decision asked for by a robot whose goal stopped being a frontier waits until this many steps have
    passed since the last one (the robot drives on meanwhile), steps, >= 1 (1: at once). A robot left with
    no path, or a blocked one, is served at once. Replanning at once made teams chase goals that vanish as
    they come into view: 18-37% more steps for hier, nearest and utility on 20 maps, 2.7-7.7 times the time."""
    transmission: str = "delta"
    """What the centre rebuilds its grid from: ``delta`` (changes since the last acknowledged sparse
    frontier map) or ``full`` (the whole sparse map every round, the paper's). Same grid, fewer bytes."""
    baseline_bytes: bool = True
    """Count what Table II's int8-grid baselines would have sent (``bytes_grid``, ``bytes_grid_zlib``,
    ``bytes_grid_delta_zlib``): every robot's known box and its changed cells, zlib-compressed every round,
    work neither a robot nor the centre does. False leaves those fields empty, for runs that want Table I
    alone: the missions are the same step for step, and the sparse maps' bytes are counted either way."""
    oscillation_radius_m: float = 2.0
    """A new goal within this distance of a goal the robot gave up before reaching it (still a frontier)
    is a return to it, metres, > 0."""
    oscillation_returns: int = 2
    """After this many returns without reaching a goal, the robot commits: it keeps its current goal until
    it reaches it, sees it resolved, or is blocked, whatever later decisions say, >= 1."""
    stall_steps: int = 150
    """Progress watchdog: a robot that gained no new area for this many steps beyond the time its path to
    the goal needed drops that goal, and the cells within ``oscillation_radius_m`` / 4 of it stop being
    candidates, steps, >= 1."""

    faults: FaultConfig = field(default_factory=FaultConfig)

    def _validate(self) -> None:
        _require(self.max_steps >= 1, "max-steps", ">= 1", self.max_steps)
        _require(self.replan_every_steps >= 1, "replan_every_steps", ">= 1", self.replan_every_steps)
        _require(self.min_replan_steps >= 1, "min_replan_steps", ">= 1", self.min_replan_steps)
        _require(self.transmission in ("delta", "full"), "transmission", "'delta' or 'full'", self.transmission)
        _require(self.oscillation_radius_m > 0, "oscillation_radius_m", "> 0 metres", self.oscillation_radius_m)
        _require(self.oscillation_returns >= 1, "oscillation_returns", ">= 1", self.oscillation_returns)
        _require(self.stall_steps >= 1, "stall_steps", ">= 1", self.stall_steps)


@dataclass(frozen=True)
class LearnedConfig(_Checked):
    """Layer 2, learned: the multi-graph network's inputs and size (paper IV-B, eqs. 4-8)."""

    hidden: int = 32
    """Width of node features, queries, keys and values (paper: 32), in [4, 1024]."""
    blocks: int = 2
    """Operation blocks of [self-graph, cross-graph] attention (paper: l), in [1, 16]."""
    distance_scale_m: float = 10.0
    """Distances and coordinates are divided by this before entering the network, metres, > 0."""
    size_scale_m: float = 5.0
    """Cluster sizes (members x resolution) are divided by this, metres, > 0."""
    base_scale: float = 3.0
    """The heuristic part of the affinity is -(utility cost) / base_scale (one nat per metre of detour at
    explore_lite's weights), > 0."""
    use_advantage: bool = True
    """Edge feature: d_ik - min over j != i of d_jk (how much nearer robot i is than its team-mates)."""
    use_current_goal: bool = True
    """Edge feature: cluster k holds robot i's current goal (learned hysteresis)."""
    use_isolation: bool = True
    """Edge feature: distance from cluster k to its nearest other cluster centre (straight line: a
    geodesic per centre costs more than the rest of a decision on large maps)."""

    def _validate(self) -> None:
        _require(4 <= self.hidden <= 1024, "hidden", "in [4, 1024]", self.hidden)
        _require(1 <= self.blocks <= 16, "blocks", "in [1, 16]", self.blocks)
        _require(self.distance_scale_m > 0, "distance_scale_m", "> 0 metres", self.distance_scale_m)
        _require(self.size_scale_m > 0, "size_scale_m", "> 0 metres", self.size_scale_m)
        _require(self.base_scale > 0, "base_scale", "> 0", self.base_scale)


@dataclass(frozen=True)
class NcmTrainConfig(_Checked):
    """PPO of the NeuralCoMapping baseline, with its public code's settings (Ye, Dong et al., CVPR 2022)."""

    ppo_iterations: int = 40
    """PPO iterations (stages ppo0...), >= 1."""
    ppo_episodes: int = 8
    """Episodes collected per iteration, >= 1."""
    ppo_epochs: int = 4
    """Passes over a batch, >= 1."""
    lr: float = 5e-4
    """Adam learning rate of the actor, > 0."""
    critic_lr_ratio: float = 1.0
    """The critic's learning rate is the actor's times this, > 0. NCM's is 0.05 for its CNN critic over
    the maps; ours (:class:`~mrexplore.global_planning.learned.ncm_network.NcmCritic`) is a small MLP, and
    a 60-minute run makes about 1,500 updates: at 0.05 x 5e-4 it would barely move from its start, leaving
    the advantages to the returns alone."""
    gamma: float = 0.99
    """Discount per 25 simulation steps (NCM's decision; a decision of k steps discounts by gamma^(k/25)), in (0, 1]."""
    gae_lambda: float = 0.95
    """GAE tau, in [0, 1]."""
    clip: float = 0.2
    """PPO ratio clip, > 0."""
    value_coef: float = 3.0
    """Weight of the value loss, >= 0."""
    entropy_coef: float = 1e-4
    """Weight of the entropy bonus, >= 0."""
    area_reward: float = 5e-3
    """Reward per newly explored m^2, > 0."""
    area_offset_m2: float = 4.0
    """m^2 subtracted from a 25-step decision's new area (in proportion for other lengths), >= 0."""
    select: str = "sampled"
    """Which validation keeps a checkpoint (both are logged): ``sampled`` (NCM's own evaluation, each robot
    drawing its node; seeded, so repeatable) or ``argmax``. A PPO policy is trained as a sampler: in a
    50-minute run with ``argmax`` no checkpoint's argmax beat the untrained network's (508.8 validation
    steps; 524-646 after), so the run kept the untrained network, while its sampled training episodes fell
    from 1,132 steps (mean of the first 10 iterations) to 781 (last 10; docs/results/train/ncm_argmax/)."""

    def _validate(self) -> None:
        for name in ("ppo_iterations", "ppo_episodes", "ppo_epochs"):
            _require(getattr(self, name) >= 1, name, ">= 1", getattr(self, name))
        for name in ("lr", "critic_lr_ratio", "clip", "area_reward"):
            _require(getattr(self, name) > 0, name, "> 0", getattr(self, name))
        for name in ("value_coef", "entropy_coef", "area_offset_m2"):
            _require(getattr(self, name) >= 0, name, ">= 0", getattr(self, name))
        _require(0 < self.gamma <= 1, "gamma", "in (0, 1]", self.gamma)
        _require(0 <= self.gae_lambda <= 1, "gae_lambda", "in [0, 1]", self.gae_lambda)
        _require(self.select in ("sampled", "argmax"), "select", "'sampled' or 'argmax'", self.select)


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
    """Cell size of training maps, metres, > 0."""
    robots_min: int = 2
    """Fewest robots of a training episode, >= 1."""
    robots_max: int = 5
    """Most robots of a training episode, >= robots_min."""
    max_steps: int = 1500
    """Step budget of a training episode, >= 1."""
    generated_share: float = 0.5
    """Share of training episodes on procedural floor plans (the rest on training DungeonMaps), in [0, 1]."""
    plans: str = "varied"
    """Procedural floor plans of training and validation: ``varied`` (``varied:SEED``, whose size, outline,
    rooms, corridor, doors and clutter the seed draws: they spread like HouseExpo's, see
    ``perf/plan_stats.py``) or ``generated`` (``generated:SEED``, the 16 x 12 m built-in plan, which the
    first shipped policies trained on)."""
    val_maps: int = 64
    """Validation episodes per evaluation: half held-out training DungeonMaps, half held-out floor plans, >= 1
    (32 in the first shipped run: the stage it kept was 9.7% ahead there and tied the heuristic on the dev
    set, so selection needs more maps)."""
    val_robots: int = 3
    """Robots in every validation episode, >= 1: the team of the dev set's Table I (training draws
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
    feature), before imitation, >= 0: each draws ``search_population`` weight vectors around the current
    ones (the current ones among them), runs every vector on the same ``search_episodes`` training
    episodes, and moves to the mean and spread of the ``search_elites`` that score best (``score``)."""
    search_population: int = 8
    """Weight vectors tried per generation, >= 2 (the current mean is one of them)."""
    search_elites: int = 3
    """Vectors with the best score (fewest mean steps by default) that set the next mean and spread, in [1,
    search_population]."""
    search_episodes: int = 48
    """Training episodes each vector of a generation runs (the same ones for every vector), >= 1."""
    search_sigma: float = 5.0
    """Spread of the first generation, per weight (a weight of 5 on the isolation feature, in tenths of
    metres, offers an isolated cluster 0.5 m nearer per metre to its nearest other cluster), > 0."""
    search_sigma_min: float = 0.5
    """The spread never falls below this, > 0 (keeps a noisy ranking from freezing the search)."""
    # -- imitation of the lookahead expert
    dagger_rounds: int = 2
    """Rounds of (collect on the student's own states, fit), >= 0; round 0's student is the policy the
    search left (the heuristic when it ran none). 2: the shipped runs of five rounds peaked at the second."""
    episodes_per_round: int = 10
    """Training episodes collected per DAgger round, >= 1."""
    label_every: int = 4
    """Every this many decisions of an episode the expert labels (the others just move it on), >= 1."""
    horizon_steps: int = 400
    """Each expert candidate is run this many simulation steps forward, >= 1. Short horizons are myopic:
    with 120, candidates that grab open area and leave pockets behind ranked first, and the student got
    worse round after round (validation 482 -> 620 steps over 6 rounds; 470 -> 487 over 3 with 400)."""
    expert_world: str = "truth"
    """Where the expert runs its candidates forward: ``truth`` (the simulator's map, scored by eq. 9's
    return over ``horizon_steps``) or ``known`` (the world the team has observed, every unseen cell a
    wall, scored by minus the steps until no frontier is left; labels a student could learn from what it
    sees: :func:`~mrexplore.training.expert.known_world_returns`)."""
    noisy_candidates: int = 4
    """Noisy utility assignments among the expert's candidates, >= 0."""
    noise_m: float = 4.0
    """Gumbel scale of the noise on the utility cost of noisy candidates, metres of detour, > 0."""
    return_temperature: float = 10.0
    """Target of the listwise loss: softmax(candidate return / this), > 0."""
    imitation_epochs: int = 8
    """Passes over the aggregated expert data per round, >= 1 (30 overfitted single-rollout labels: the
    validation steps rose round after round)."""
    lr: float = 1e-3
    """Adam learning rate of imitation, > 0."""
    weight_decay: float = 1e-4
    """Adam weight decay, >= 0."""
    residual_l2: float = 0.01
    """Weight of the mean squared residual in the imitation loss: the network departs from the heuristic
    only where the expert's data insist, >= 0."""
    # -- PPO on eq. 9
    ppo_iterations: int = 0
    """PPO iterations after imitation, >= 0 (0 in the shipped recipe: in two runs no PPO iteration came
    near the best imitation stage's validation steps; its sampled policy explores far worse than the
    decoded one)."""
    ppo_episodes: int = 12
    """Episodes collected per PPO iteration, >= 1."""
    ppo_epochs: int = 4
    """Passes over a PPO batch, >= 1."""
    ppo_lr: float = 3e-4
    """Adam learning rate of PPO, > 0."""
    gamma: float = 0.995
    """Discount per simulation step (a decision spanning k steps discounts by gamma^k), in (0, 1]."""
    gae_lambda: float = 0.95
    """GAE lambda, in [0, 1]."""
    clip: float = 0.2
    """PPO ratio clip, > 0."""
    value_coef: float = 0.5
    """Weight of the value loss, >= 0."""
    entropy_coef: float = 0.01
    """Weight of the entropy bonus, >= 0."""
    reward_scale: float = 0.01
    """Rewards of eq. 9 are multiplied by this for the critic's sake, > 0."""
    imitation_coef: float = 1.0
    """Weight of the listwise expert loss kept during PPO on the aggregated data (keeps the policy near
    the expert while RL fine-tunes), >= 0."""

    def _validate(self) -> None:
        _require(self.strategy in TRAINABLE, "strategy", "'hier' or 'ncm'", self.strategy)
        _require(self.resolution_m > 0, "resolution_m", "> 0 metres", self.resolution_m)
        _require(self.robots_min >= 1, "robots_min", ">= 1", self.robots_min)
        _require(
            self.robots_max >= self.robots_min, "robots_max", f">= robots_min ({self.robots_min})", self.robots_max
        )
        _require(self.max_steps >= 1, "max_steps", ">= 1", self.max_steps)
        _require(0 <= self.generated_share <= 1, "generated_share", "in [0, 1]", self.generated_share)
        _require(self.plans in ("varied", "generated"), "plans", "'varied' or 'generated'", self.plans)
        _require(self.val_maps >= 1, "val_maps", ">= 1", self.val_maps)
        _require(self.val_robots >= 1, "val_robots", ">= 1", self.val_robots)
        _require(self.score in ("steps", "relative"), "score", "'steps' or 'relative'", self.score)
        _require(self.expert_world in ("truth", "known"), "expert_world", "'truth' or 'known'", self.expert_world)
        for name in ("search_generations", "dagger_rounds", "noisy_candidates", "ppo_iterations"):
            _require(getattr(self, name) >= 0, name, ">= 0", getattr(self, name))
        for name in (
            "episodes_per_round",
            "search_episodes",
            "label_every",
            "horizon_steps",
            "imitation_epochs",
            "ppo_episodes",
            "ppo_epochs",
        ):
            _require(getattr(self, name) >= 1, name, ">= 1", getattr(self, name))
        _require(self.search_population >= 2, "search_population", ">= 2", self.search_population)
        _require(
            1 <= self.search_elites <= self.search_population,
            "search_elites",
            f"in [1, search_population ({self.search_population})]",
            self.search_elites,
        )
        for name in ("search_sigma", "search_sigma_min", "noise_m", "return_temperature", "lr", "ppo_lr", "clip"):
            _require(getattr(self, name) > 0, name, "> 0", getattr(self, name))
        _require(self.reward_scale > 0, "reward_scale", "> 0", self.reward_scale)
        _require(0 < self.gamma <= 1, "gamma", "in (0, 1]", self.gamma)
        _require(0 <= self.gae_lambda <= 1, "gae_lambda", "in [0, 1]", self.gae_lambda)
        for name in ("value_coef", "entropy_coef", "imitation_coef", "weight_decay", "residual_l2"):
            _require(getattr(self, name) >= 0, name, ">= 0", getattr(self, name))


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
            doc = docs.get((type(obj).__name__, f.name))
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
