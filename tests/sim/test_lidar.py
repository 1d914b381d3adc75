"""LiDAR ray casting and the log-odds update (paper eq. 1), against plain references."""

from __future__ import annotations

import copy
import math

import numpy as np
import pytest
from conftest import bool_grid
from hypothesis import given, settings
from hypothesis import strategies as st

from mrexplore.config import SensorConfig
from mrexplore.sim.belief import logit
from mrexplore.sim.lidar import Beams, cast_ray, ray_count, ray_directions, scan_mark, scan_update


def reference_ray(occ: np.ndarray, sr: int, sc: int, dr: float, dc: float, rng: float) -> tuple[list, bool]:
    """Cells crossed by a beam, found by fine sampling along it (slow, obviously right)."""
    H, W = occ.shape
    out: list[tuple[int, int]] = []
    for k in range(int(rng * 2000) + 1):
        t = k / 2000
        y, x = sr + 0.5 + t * dr, sc + 0.5 + t * dc
        r, c = math.floor(y), math.floor(x)
        if not (0 <= r < H and 0 <= c < W):
            return out, False
        if not out or out[-1] != (r, c):
            out.append((r, c))
            if occ[r, c]:
                return out, True
    return out, False


@settings(max_examples=80, deadline=None)
@given(st.integers(0, 10**6), st.floats(0.013, 2 * math.pi - 0.013))
def test_cast_ray_matches_fine_sampling(seed: int, angle: float) -> None:
    rng = np.random.default_rng(seed)
    occ = rng.random((15, 15)) < 0.15
    occ[7, 7] = False
    dr, dc = -math.sin(angle), math.cos(angle)
    n = 64
    br, bc, bt = np.empty(n, np.int64), np.empty(n, np.int64), np.empty(n)
    count, hit = cast_ray(occ, 7, 7, dr, dc, 6.0, br, bc, bt)
    got = list(zip(br[:count].tolist(), bc[:count].tolist(), strict=True))
    want, want_hit = reference_ray(occ, 7, 7, dr, dc, 6.0)
    # Fine sampling can skip a cell the beam only grazes at a corner; the traversal never skips.
    assert set(want) <= set(got)
    assert hit == want_hit or (hit and got[-1] not in want)


def _scan(occ: np.ndarray, rc: tuple[int, int], range_cells: float, sensor: SensorConfig | None = None):
    sensor = sensor or SensorConfig()
    H, W = occ.shape
    lo = np.zeros((H, W), np.float32)
    observed = np.zeros((H, W), bool)
    team = np.zeros((H, W), bool)
    dirs = ray_directions(ray_count(range_cells, sensor.ray_oversampling))
    args = (logit(sensor.p_hit), logit(sensor.p_miss), logit(sensor.p_clamp_min), logit(sensor.p_clamp_max))
    everything = np.ones((H, W), bool)
    mark = np.zeros((H, W), np.int8)
    zero_noise = np.zeros(len(dirs))
    new = scan_update(occ, rc[0], rc[1], dirs, range_cells, zero_noise, lo, observed, team, everything, *args, mark)
    return lo, observed, team, new, dirs, args


def test_no_gaps_at_full_range() -> None:
    occ = np.zeros((61, 61), bool)
    _, observed, _, _, _, _ = _scan(occ, (30, 30), 25.0)
    rr, cc = np.mgrid[0:61, 0:61]
    dist = np.hypot(rr - 30, cc - 30)
    assert observed[dist <= 25.0 - 0.5].all()
    assert not observed[dist > 25.0 + 1.5].any()


def test_walls_block_and_log_odds_per_eq1() -> None:
    occ = bool_grid("""
        #######
        #.....#
        #.....#
        ###.###
        #.....#
        #######
    """)
    lo, observed, team, (robot_new, team_new), dirs, (l_hit, l_miss, _, _) = _scan(occ, (1, 1), 20.0)
    # One observation per cell per scan: free cells carry exactly logit(p_miss), walls logit(p_hit).
    assert lo[1, 3] == pytest.approx(logit(0.4))
    assert lo[0, 3] == pytest.approx(logit(0.7))
    # Behind the wall at row 3, only what the door at (3, 3) lets through is seen.
    assert not observed[4, 1]
    assert observed[3, 3]
    assert np.array_equal(observed, team) and robot_new == team_new == int(observed.sum())


def test_repeated_scans_accumulate_then_clamp() -> None:
    occ = bool_grid("""
        #####
        #...#
        #####
    """)
    sensor = SensorConfig()
    lo, observed, team, _, dirs, args = _scan(occ, (1, 1), 10.0)
    H, W = occ.shape
    mark = np.zeros((H, W), np.int8)
    scan_update(occ, 1, 1, dirs, 10.0, np.zeros(len(dirs)), lo, observed, team, np.ones_like(occ), *args, mark)
    assert lo[1, 2] == pytest.approx(2 * logit(0.4))
    for _ in range(20):
        scan_update(occ, 1, 1, dirs, 10.0, np.zeros(len(dirs)), lo, observed, team, np.ones_like(occ), *args, mark)
    assert lo[1, 2] == pytest.approx(logit(sensor.p_clamp_min))
    assert lo[0, 2] == pytest.approx(logit(sensor.p_clamp_max))
    assert not mark.any()


@settings(max_examples=120, deadline=None)
@given(st.integers(0, 10**6), st.floats(1.0, 9.0), st.sampled_from([1.0, 1.5]), st.sampled_from([0.0, 0.0, 1.5]))
def test_beams_walked_by_their_moves_mark_what_cast_beams_mark(
    seed: int, range_cells: float, oversampling: float, noise_sd: float
) -> None:
    # From anywhere, the grid's edges and corners included (and, on the larger grids, from cells no beam can
    # take off the grid, where the walk skips its bounds checks), with and without short readings.
    rng = np.random.default_rng(seed)
    h, w = int(rng.integers(1, 70)), int(rng.integers(1, 70))
    occ = rng.random((h, w)) < rng.choice([0.0, 0.1, 0.3])
    beams = Beams.of(range_cells, oversampling)
    assert len(beams.dirs) == ray_count(range_cells, oversampling)
    cast, walked = np.zeros((h, w), np.int8), np.zeros((h, w), np.int8)
    for sr, sc in [(0, 0), (h - 1, w - 1), (int(rng.integers(h)), int(rng.integers(w))), (h // 2, w // 2)]:
        noise = rng.normal(0.0, noise_sd, len(beams.dirs)) if noise_sd else np.zeros(len(beams.dirs))
        window = scan_mark(occ, sr, sc, beams.dirs, range_cells, noise, cast)
        assert beams.mark(occ, sr, sc, noise, walked) == window
        np.testing.assert_array_equal(walked, cast)
        cast[:], walked[:] = 0, 0


def test_beams_are_shared_by_a_snapshot() -> None:
    beams = Beams.of(4.0, 1.0)
    assert copy.deepcopy({"b": beams})["b"] is beams
