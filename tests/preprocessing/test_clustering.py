"""Mean-Shift clustering: hand-checked clusters, the bandwidth rule, and equality with scikit-learn."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.distance import pdist
from sklearn.cluster import MeanShift, get_bin_seeds

from mrexplore.config import PreprocessConfig
from mrexplore.preprocessing.clustering import (
    Clusters,
    _disc_sum,
    _RowIndex,
    adaptive_bandwidth,
    bin_seeds,
    bounded_bandwidth,
    cluster_frontiers,
    linear_percentile,
    mean_shift,
    split_for_team,
)


def test_two_frontier_segments_and_a_stray_cell() -> None:
    # Two 5-cell segments far apart and one isolated cell: the stray forms a 1-member cluster, dropped.
    seg_a = [[2, c] for c in range(10, 15)]
    seg_b = [[r, 40] for r in range(20, 25)]
    pts = np.array(seg_a + seg_b + [[40, 5]])
    c = cluster_frontiers(pts, PreprocessConfig())
    assert c.centers_rc.tolist() == [[2, 12], [22, 40]]
    assert c.sizes.tolist() == [5, 5]
    assert c.members_of(0).tolist() == seg_a
    assert c.members_of(1).tolist() == seg_b


def test_min_cluster_size_one_keeps_singletons() -> None:
    c = cluster_frontiers(np.array([[0, 0], [0, 1], [30, 30]]), PreprocessConfig(min_cluster_size=1))
    assert c.sizes.tolist() == [2, 1]


def test_fewer_than_two_points() -> None:
    assert len(cluster_frontiers(np.zeros((0, 2), int), PreprocessConfig())) == 0
    assert len(cluster_frontiers(np.array([[3, 3]]), PreprocessConfig())) == 0


def test_bandwidth_is_percentile_of_pairwise_distances() -> None:
    pts = np.array([[0.0, 0.0], [0.0, 3.0], [4.0, 0.0]])  # distances 3, 4, 5
    assert adaptive_bandwidth(pts, 50, 100) == 4.0
    assert adaptive_bandwidth(pts, 15, 100) == pytest.approx(3.3)


def test_a_bandwidth_bound_keeps_pairs_apart_that_the_percentile_rule_joins() -> None:
    # Four pairs of cells 6 apart on a row: the 15th percentile of the 28 distances is 5, so the flat
    # kernel joins neighbouring pairs (3 clusters); bounded at 2 cells, each pair is a cluster of its own,
    # centred on its first cell (both are 0.5 from the mode).
    pts = np.array([[0, c] for s in (0, 6, 12, 18) for c in (s, s + 1)])
    assert adaptive_bandwidth(pts.astype(float), 15, 1000) == 5.0
    assert cluster_frontiers(pts, PreprocessConfig()).sizes.tolist() == [3, 2, 3]
    bounded = cluster_frontiers(pts, PreprocessConfig(), max_bandwidth_cells=2.0)
    assert bounded.centers_rc.tolist() == [[0, 0], [0, 6], [0, 12], [0, 18]]
    assert bounded.sizes.tolist() == [2, 2, 2, 2]
    # A bound above the rule's bandwidth changes nothing.
    assert cluster_frontiers(pts, PreprocessConfig(), max_bandwidth_cells=5.0).sizes.tolist() == [3, 2, 3]


@settings(max_examples=200, deadline=None)
@given(
    st.lists(st.tuples(st.integers(0, 30), st.integers(0, 30)), min_size=2, max_size=60),
    st.sampled_from([5.0, 15.0, 50.0, 100.0]),
    st.integers(2, 40),
    st.one_of(st.none(), st.integers(1, 40).map(float), st.floats(0.5, 45.0)),
)
def test_the_bounded_bandwidth_is_the_percentile_capped_by_the_bound(
    cells_: list[tuple[int, int]], percentile: float, max_sample: int, bound: float | None
) -> None:
    # Integer cells and whole-number bounds put pair distances exactly at the bound (5.0 for a 3-4-5 pair).
    pts = np.array(cells_, dtype=np.float64)
    expected = adaptive_bandwidth(pts, percentile, max_sample)
    if bound is not None:
        expected = min(expected, bound)
    assert bounded_bandwidth(pts, percentile, max_sample, bound) == expected


@pytest.mark.parametrize(("bound_m", "resolution_m", "clusters"), [(1.0, 0.5, 4), (None, 0.5, 3), (1.0, 0.1, 3)])
def test_a_pipeline_bounds_the_bandwidth_in_metres(bound_m: float | None, resolution_m: float, clusters: int) -> None:
    # The pairs above as frontier cells. 1 m is 2 cells at 0.5 m: the pairs stay apart. At 0.1 m it is 10
    # cells, above the rule's 5: the paper's clusters, as with no bound.
    from mrexplore.pipeline import CandidateQuery, make_strategy
    from mrexplore.preprocessing.frontiers import Frontiers

    un = np.zeros((3, 24), dtype=bool)
    for s in (0, 6, 12, 18):
        un[1, s : s + 2] = True
    pp = PreprocessConfig(bandwidth_max_m=bound_m)
    frontiers = Frontiers(un, np.zeros_like(un))
    q = CandidateQuery(
        np.zeros(un.shape, np.uint8), frontiers, None, np.zeros((1, 2), np.int32), list, None, resolution_m
    )
    assert len(make_strategy("utility", preprocess_cfg=pp).candidates(q).clusters) == clusters


@given(
    st.lists(st.floats(0, 1e4, allow_nan=False), min_size=1, max_size=60),
    st.one_of(st.integers(0, 100), st.floats(0, 100), st.sampled_from([15, 15.0, 50, 99.9])),
)
def test_linear_percentile_is_numpys_bit_for_bit(values: list[float], percentile: float) -> None:
    a = np.array(values)
    assert linear_percentile(a, percentile) == float(np.percentile(a, percentile))
    assert linear_percentile(np.round(a), percentile) == float(np.percentile(np.round(a), percentile))  # ties


@pytest.mark.filterwarnings("ignore:Binning data failed")
@settings(max_examples=40, deadline=None)
@given(st.integers(0, 10**6), st.integers(2, 300), st.integers(4, 120), st.booleans())
def test_mean_shift_equals_sklearn(seed: int, n: int, extent: int, tie_free: bool) -> None:
    rng = np.random.default_rng(seed)
    pts = np.unique(rng.integers(0, extent, (n, 2)), axis=0).astype(float)
    if len(pts) < 2:
        return
    bw = max(float(np.percentile(pdist(pts), 15)), 1.0) + (0.37 if tie_free else 0.0)
    ref = MeanShift(bandwidth=bw, bin_seeding=True).fit(pts)
    modes, labels = mean_shift(pts, bw)
    np.testing.assert_allclose(modes, ref.cluster_centers_)
    np.testing.assert_array_equal(labels, ref.labels_)


def test_disc_sums_by_hand() -> None:
    pts = np.array([[0, 0], [0, 1], [0, 2], [1, 0], [3, 3]], dtype=float)
    rows = _RowIndex(pts)
    # Radius 1 around (0, 0): itself, (0, 1) and (1, 0); (0, 2) is 2 away.
    assert _disc_sum(rows.starts, rows.cols, rows.prefix, rows.r0, 0.0, 0.0, 1.0) == (3, 1.0, 1.0)
    # Radius 2 around (0.5, 1): all but (3, 3) (distance sqrt(10.25)).
    assert _disc_sum(rows.starts, rows.cols, rows.prefix, rows.r0, 0.5, 1.0, 2.0) == (4, 1.0, 3.0)
    # Radius 2 around (3, 1): only (3, 3), exactly on the rim; (1, 0) is sqrt(5) away.
    assert _disc_sum(rows.starts, rows.cols, rows.prefix, rows.r0, 3.0, 1.0, 2.0) == (1, 3.0, 3.0)
    assert _disc_sum(rows.starts, rows.cols, rows.prefix, rows.r0, 9.0, 9.0, 2.0) == (0, 0.0, 0.0)


@settings(max_examples=60, deadline=None)
@given(st.integers(0, 10**6), st.integers(1, 120), st.floats(0.5, 12.0))
def test_disc_sums_equal_brute_force(seed: int, n: int, radius: float) -> None:
    rng = np.random.default_rng(seed)
    pts = rng.integers(-20, 20, (n, 2)).astype(float)  # repeats too
    rows = _RowIndex(pts)
    for y, x in rng.uniform(-25, 25, (10, 2)):
        inside = pts[(pts[:, 0] - y) ** 2 + (pts[:, 1] - x) ** 2 <= radius * radius]
        expected = (len(inside), float(inside[:, 0].sum()), float(inside[:, 1].sum()))
        assert _disc_sum(rows.starts, rows.cols, rows.prefix, rows.r0, y, x, radius) == expected


def test_mean_shift_needs_cells() -> None:
    with pytest.raises(ValueError, match="mean_shift needs points on integer coordinates"):
        mean_shift(np.array([[0.5, 0.0], [1.0, 1.0]]), 1.0)


@pytest.mark.filterwarnings("ignore:Binning data failed")
@settings(max_examples=60, deadline=None)
@given(st.integers(0, 10**6), st.integers(1, 200), st.integers(2, 80), st.floats(0.5, 30.0))
def test_bin_seeds_equal_sklearn(seed: int, n: int, extent: int, bin_size: float) -> None:
    pts = np.random.default_rng(seed).integers(0, extent, (n, 2)).astype(float)  # unsorted, with repeats
    ref = get_bin_seeds(pts, bin_size, 1)
    ours = bin_seeds(pts, bin_size)
    assert ours.dtype == ref.dtype
    np.testing.assert_array_equal(ours, ref)


def test_centres_are_members() -> None:
    rng = np.random.default_rng(0)
    ring = np.array([[int(20 + 15 * np.sin(a)), int(20 + 15 * np.cos(a))] for a in np.linspace(0, 6.2, 80)])
    pts = np.unique(np.vstack([ring, rng.integers(60, 90, (40, 2))]), axis=0)
    c = cluster_frontiers(pts, PreprocessConfig())
    members = {tuple(p) for p in pts.tolist()}
    assert all(tuple(ctr) in members for ctr in c.centers_rc.tolist())
    for k in range(len(c)):
        assert c.sizes[k] == len(c.members_of(k)) and tuple(c.centers_rc[k]) in map(tuple, c.members_of(k))


def _one_cluster(cells: list[tuple[int, int]], centre: int = 0) -> Clusters:
    pts = np.array(cells, dtype=np.int32)
    return Clusters(pts[centre : centre + 1], np.array([len(pts)], np.int32), pts, np.zeros(len(pts), np.int32))


def test_split_for_team_cuts_the_largest_cluster_along_its_axis() -> None:
    # An L: 8 cells down column 0 and 4 along row 7; two clusters already for 3 robots.
    ell = [(r, 0) for r in range(8)] + [(7, c) for c in range(1, 5)]
    far = [(20, 20), (20, 21)]
    pts = np.array(ell + far, dtype=np.int32)
    labels = np.array([0] * len(ell) + [1] * len(far), np.int32)
    two = Clusters(np.array([[7, 0], [20, 20]], np.int32), np.array([12, 2], np.int32), pts, labels)
    three = split_for_team(two, 3, 2)
    # The L's 12 members, projected on their principal axis, split 6 / 6: the top of the column and
    # the corner with the row; each half's centre is its member nearest its mean.
    assert three.sizes.tolist() == [6, 6, 2]
    assert three.centers_rc.tolist() == [[2, 0], [7, 2], [20, 20]]
    halves = [set(map(tuple, three.members_of(k).tolist())) for k in range(3)]
    assert halves[0] == {(r, 0) for r in range(6)}
    assert halves[2] == set(far)


def test_split_for_team_leaves_enough_clusters_and_small_ones_alone() -> None:
    one = _one_cluster([(0, c) for c in range(3)])
    assert split_for_team(one, 1, 2) is one  # clusters suffice
    assert split_for_team(one, 4, 2).sizes.tolist() == [3]  # 3 < 2 x 2 members: not split
    four = split_for_team(_one_cluster([(0, c) for c in range(8)]), 4, 2)
    assert four.sizes.tolist() == [2, 2, 2, 2] and four.centers_rc[:, 1].tolist() == [0, 2, 4, 6]


def test_split_for_team_cuts_no_cluster_shorter_than_min_members() -> None:
    line = _one_cluster([(0, c) for c in range(8)])
    assert split_for_team(line, 4, 2, min_members=9).sizes.tolist() == [8]  # 8 members < 9: kept whole
    # 8 >= 8: cut once; the halves' 4 members are under 8, so the cutting stops at 2 of the 4 clusters.
    assert split_for_team(line, 4, 2, min_members=8).sizes.tolist() == [4, 4]


@pytest.mark.parametrize(("resolution_m", "cut"), [(0.1, False), (2.0, True)])
def test_a_pipeline_splits_for_its_team_only_frontiers_long_enough(resolution_m: float, cut: bool) -> None:
    # A straight 30-cell frontier: Mean-Shift gives 5 clusters of 5-8 members, fewer than 7 robots. At
    # 0.1 m a cluster holds under 1 m of frontier, under the 12 m floor: the paper's clusters stay. At
    # 2 m the floor is 6 members: the largest clusters are cut until there is one per robot.
    from mrexplore.pipeline import CandidateQuery, make_strategy
    from mrexplore.preprocessing.frontiers import Frontiers

    un = np.zeros((5, 40), dtype=bool)
    un[2, 5:35] = True
    pp = PreprocessConfig(split_for_team=True, split_min_frontier_m=12.0)
    robots = np.zeros((7, 2), np.int32)
    frontiers = Frontiers(un, np.zeros_like(un))
    q = CandidateQuery(np.zeros(un.shape, np.uint8), frontiers, None, robots, list, None, resolution_m)
    paper = cluster_frontiers(frontiers.un_rc, pp)
    assert sorted(paper.sizes.tolist()) == [5, 5, 6, 6, 8]
    clusters = make_strategy("utility", preprocess_cfg=pp).candidates(q).clusters
    if cut:
        assert sorted(clusters.sizes.tolist()) == [3, 3, 4, 4, 5, 5, 6]  # 8 -> 4 + 4, 6 -> 3 + 3
    else:
        assert clusters.sizes.tolist() == paper.sizes.tolist()
