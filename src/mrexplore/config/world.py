"""The world a mission runs in: how a map file becomes a grid, the robots' sensor and motion, the team reward."""

from __future__ import annotations

from dataclasses import dataclass, field

from mrexplore.config.schema import Checked, Interval, at_least, non_negative, positive

__all__ = ["MapConfig", "GridThresholds", "SensorConfig", "MotionConfig", "RewardConfig", "SimConfig"]


@dataclass(frozen=True)
class MapConfig(Checked):
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
        "resolution_m": positive("metres"),
        "pixel_size_m": positive("metres", none="the format's default"),
        "outside_opening_m": positive("metres"),
        "min_passage_m": non_negative("metres"),
        "max_cells": at_least(1),
        "max_image_pixels": at_least(1),
        "max_file_bytes": at_least(1),
    }


@dataclass(frozen=True)
class GridThresholds(Checked):
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
        "max_cells": at_least(1),
    }


@dataclass(frozen=True)
class SensorConfig(Checked):
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
        "range_m": positive("metres"),
        "ray_oversampling": at_least(1),
        "p_hit": Interval(0.5, 1, "neither"),
        "p_miss": Interval(0, 0.5, "neither"),
        "p_clamp_min": Interval(0, 0.5, "neither"),
        "p_clamp_max": Interval(0.5, 1, "neither"),
        "p_occupied": Interval(0, 1, "neither"),
        "range_noise_m": non_negative("metres"),
    }


@dataclass(frozen=True)
class MotionConfig(Checked):
    """How far a robot drives per simulation step."""

    step_m: float = 0.1
    """Distance driven per step along the path, metres (the mission's clock)."""

    _constraints = {"step_m": positive("metres")}


@dataclass(frozen=True)
class RewardConfig(Checked):
    """Team reward of paper eq. 9: R = R_time + lambda * R_area."""

    time_reward: float = -1.0
    """R_time, the fixed reward per step."""
    area_weight: float = 2.0
    """lambda, weight of newly known explorable area in m^2 (paper: 2)."""

    _constraints = {"time_reward": Interval(None, 0, "right"), "area_weight": non_negative()}


@dataclass(frozen=True)
class SimConfig(Checked):
    """The multi-robot simulator."""

    robots: int = 3
    """Team size (paper: 3)."""
    start_spread_m: float = 1.0
    """Drawn starts lie within this geodesic distance of the first robot, metres."""
    sensor: SensorConfig = field(default_factory=SensorConfig)
    motion: MotionConfig = field(default_factory=MotionConfig)
    reward: RewardConfig = field(default_factory=RewardConfig)

    _constraints = {"robots": at_least(1), "start_spread_m": non_negative("metres")}
