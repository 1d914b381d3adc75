"""The three layers' settings: preprocessing and clustering, the global assigners (classical and learned), CoScan,
the local routing."""

from __future__ import annotations

from dataclasses import dataclass

from mrexplore.config.schema import Checked, Interval, Odd, ZeroOr, at_least, non_negative, positive

__all__ = ["PreprocessConfig", "GlobalPlanningConfig", "CoScanConfig", "LocalPlanningConfig", "LearnedConfig"]


@dataclass(frozen=True)
class PreprocessConfig(Checked):
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
        "min_cluster_size": at_least(1),
        "bandwidth_percentile": Interval(0, 100, "right"),
        "bandwidth_sample": at_least(2),
        "bandwidth_max_m": positive("metres", none="the percentile rule alone"),
        "split_min_frontier_m": non_negative("metres"),
    }


@dataclass(frozen=True)
class GlobalPlanningConfig(Checked):
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
    plan_service_weight: float = 0.0
    """``team-plan`` and ``hier-plan``: the time the team plan counts for exploring a cluster once there, in
    metres of driving per metre of its frontier (members x resolution). 0, chosen on 32 validation maps of
    training against 0.2, 0.5 and 1.5 (docs/learned.md, "A team plan")."""
    plan_sum_weight: float = 0.0
    """``team-plan`` and ``hier-plan``: the plan minimises its makespan plus this times the total of its
    routes' costs (0: the total only between plans of equal makespan; 0.1, 0.3 and 1 measured no better on
    the validation maps)."""
    plan_weight: float = 0.3
    """``hier-plan``: the learned cost of sending robot i to cluster k grows by this times ``distance_weight``
    per metre by which heading there first lengthens the team plan's makespan. 0.3, chosen on 32 validation
    maps of training at 2, 3 and 8 robots against 1 and 3 (docs/learned.md, "A team plan")."""
    search_horizon_steps: int = 400
    """``hier-search``: each candidate's rollout runs at most this many simulation steps (a rollout still
    running then adds the team plan's makespan over the clusters left to its steps)."""
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
        "distance_weight": non_negative(),
        "size_weight": non_negative(),
        "gain_weight": Interval(-100, 100),
        "gain_range_m": positive("metres"),
        "path_weight": Interval(-100, 100),
        "commitment": Interval(0, 1, none="the strategy's default"),
        "learned_min_robots": at_least(1),
        "plan_service_weight": non_negative(),
        "plan_sum_weight": non_negative(),
        "plan_weight": non_negative(),
        "search_horizon_steps": at_least(1),
        "far_above_cells": non_negative(),
        "exact_radius_m": positive("metres"),
        "coarse_cell_m": positive("metres"),
        "portal_sector_blocks": ZeroOr(2, None, "left"),
        "portal_spacing_blocks": at_least(1),
    }


@dataclass(frozen=True)
class CoScanConfig(Checked):
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
        "task_spacing_m": positive("metres"),
        "tasks_per_robot": at_least(1),
        "delta_m": positive("metres"),
        "max_iterations": at_least(1),
    }


@dataclass(frozen=True)
class LocalPlanningConfig(Checked):
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
        "theta_members": at_least(1),
        "k_g": positive(),
        "k_l": positive(),
        "upper_gain": positive(),
        "upper_cost": positive(),
        "c": non_negative(),
        "epsilon": positive(),
        "sub_bandwidth_m": positive("metres", none="the percentile rule of layer 1"),
        "max_candidates": at_least(1),
        "margin_m": non_negative("metres"),
    }


@dataclass(frozen=True)
class LearnedConfig(Checked):
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
    use_plan_regret: bool = False
    """Edge feature (after the predicted ones, for a policy trained with it): how much the team plan's makespan
    grows when robot i heads for cluster k first (``TeamPlan.first_regret``), metres / ``distance_scale_m``."""
    use_plan_position: bool = False
    """Edge feature (after the plan's regret where both are read): 1 / (1 + p) where cluster k is the p-th
    (from 0) on robot i's route of the team plan, 0 where it is on another robot's route or none."""

    @property
    def reads_plan(self) -> bool:
        """The network reads the team plan (its regret or its routes)."""
        return self.use_plan_regret or self.use_plan_position

    @property
    def reads_prediction(self) -> bool:
        """The network reads a map predictor's completion of the belief (gain or shortcut)."""
        return self.use_predicted_gain or self.use_predicted_path

    _constraints = {
        "hidden": Interval(4, 1024),
        "blocks": Interval(1, 16),
        "distance_scale_m": positive("metres"),
        "size_scale_m": positive("metres"),
        "base_scale": positive(),
        "gain_scale_m2": positive(),
    }
