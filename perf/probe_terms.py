"""Does anything the edge features leave out move the shipped policy? Extra cost terms and one change to
layer 3, each on top of the shipped weights, paired on the probe's training episodes.

    python perf/probe_terms.py [--episodes 128] [--workers 2] [--seed 0]
                               [--variants '[{"isolation_geodesic": -0.3}, {"split_shared": 1}, ...]']
                               [--base '{"robots": 8}']

Each variant is a mapping of term name to weight. A term is an ``(R, C)`` array in metres (or a count)
added, times its weight, to the policy's cost (explore_lite's ``3 d - size`` less ``3 x`` the residual
``edges . w``), so a weight of 1 on a term of 1 makes the cluster one metre of cost dearer. Terms:

- ``isolation_geodesic``: the geodesic distance from the cluster's centre to the nearest other centre, m
  (capped at 20); the shipped isolation feature is its straight-line version.
- ``density``: the other clusters within 6 m (straight line) of the cluster's centre.
- ``size_over_5m``: the cluster's frontier metres beyond 5 m (explore_lite rewards size without bound).
- ``near_other_goal``: 1 where the cluster lies within 6 m (one sensor range) of the centre of another
  robot's current goal cluster, other than the robot's own.
- ``from_centroid``: the centre's straight-line distance from the team's centroid, m.
- ``second_robot``: the geodesic distance of the nearest other robot to the cluster, m (capped at 30).
- ``distance``, ``size``, ``advantage``: d, the cluster's frontier metres, and d less the nearest other
  robot's d (capped at ±30 m): the policy's own features, to move its weights by a team size.
- ``distance_squared``: d² / 10 m (long trips dearer than in proportion).
- ``distance_log``: log(1 + d).

Two keys are not terms: ``split_shared`` (any true value) makes robots that share a cluster divide its
members, each member to the sharer nearest it by geodesic distance, each robot routing through its own
part; ``robots`` fixes the team size instead of drawing 2-5. ``--base`` holds keys every run gets, the
reference among them. The episodes are ``perf/probe_residual.py``'s (training DungeonMaps and ``varied:`` plans
of training seeds, the same maps, seeds and starts for every variant; no dev or validation map).
"""

from __future__ import annotations

import argparse
import json
import multiprocessing
import sys
import types
from collections.abc import Callable
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
from numpy.typing import NDArray
from probe_residual import TRAIN, training_episodes

from mrexplore.bench.report import paired_bootstrap
from mrexplore.cli import run_script
from mrexplore.config import MissionConfig, SimConfig, TrainConfig
from mrexplore.global_planning.learned.checkpoint import default_policy_path
from mrexplore.global_planning.learned.policy import LearnedPlanner
from mrexplore.global_planning.learned.trainer import _map
from mrexplore.global_planning.protocol import UNASSIGNED, Assignment, AssignmentProblem
from mrexplore.mission import Mission
from mrexplore.strategies import _NO_ROUTE, Decision, ExplorationPipeline, PosedDecision, _decision, make_strategy
from mrexplore.types import MrExploreError

Term = Callable[[AssignmentProblem], NDArray[np.float64]]
TERMS: dict[str, Term] = {}
NOT_TERMS = ("split_shared", "robots")


def _term(f: Term) -> Term:
    TERMS[f.__name__] = f
    return f


def _per_cluster(p: AssignmentProblem, v: NDArray[np.float64]) -> NDArray[np.float64]:
    return np.broadcast_to(v[None, :], (p.n_robots, p.n_clusters)).astype(np.float64)


def _straight_gaps(p: AssignmentProblem) -> NDArray[np.float64]:
    c = p.clusters.centers_rc.astype(np.float64) * p.resolution_m
    gap = np.sqrt(((c[:, None] - c[None]) ** 2).sum(-1))
    np.fill_diagonal(gap, np.inf)
    return gap


@_term
def isolation_geodesic(p: AssignmentProblem) -> NDArray[np.float64]:
    if p.n_clusters < 2:
        return np.zeros((p.n_robots, p.n_clusters))
    d = p.cluster_dist_cells * p.resolution_m
    np.fill_diagonal(d, np.inf)
    return _per_cluster(p, np.minimum(d.min(axis=1), 20.0))


@_term
def density(p: AssignmentProblem) -> NDArray[np.float64]:
    if p.n_clusters < 2:
        return np.zeros((p.n_robots, p.n_clusters))
    return _per_cluster(p, (_straight_gaps(p) < 6.0).sum(axis=1).astype(np.float64))


@_term
def size_over_5m(p: AssignmentProblem) -> NDArray[np.float64]:
    return _per_cluster(p, np.maximum(p.clusters.sizes * p.resolution_m - 5.0, 0.0))


@_term
def near_other_goal(p: AssignmentProblem) -> NDArray[np.float64]:
    out = np.zeros((p.n_robots, p.n_clusters))
    cur = p.current_cluster
    if cur is None or p.n_robots < 2 or p.n_clusters < 2:
        return out
    gap = _straight_gaps(p)
    np.fill_diagonal(gap, 0.0)
    near = gap < 6.0  # near[k, l]: centres k and l within one sensor range
    for i in range(p.n_robots):
        others = [int(cur[j]) for j in range(p.n_robots) if j != i and cur[j] >= 0]
        if others:
            out[i] = near[:, others].any(axis=1)
            if cur[i] >= 0:
                out[i, cur[i]] = 0.0
    return out


@_term
def from_centroid(p: AssignmentProblem) -> NDArray[np.float64]:
    c = p.clusters.centers_rc.astype(np.float64) * p.resolution_m
    o = p.robots_rc.astype(np.float64).mean(axis=0) * p.resolution_m
    return _per_cluster(p, np.sqrt(((c - o) ** 2).sum(-1)))


def _others(p: AssignmentProblem) -> NDArray[np.float64]:
    """The nearest other robot's geodesic distance to each cluster, m (inf where none reaches it)."""
    order = np.sort(p.dist_m, axis=0)
    return np.where(p.dist_m <= order[0:1], order[1:2], order[0:1])


@_term
def second_robot(p: AssignmentProblem) -> NDArray[np.float64]:
    if p.n_robots < 2:
        return np.zeros((p.n_robots, p.n_clusters))
    other = _others(p)
    return np.minimum(np.where(np.isfinite(other), other, 30.0), 30.0)


@_term
def distance(p: AssignmentProblem) -> NDArray[np.float64]:
    return np.where(np.isfinite(p.dist_m), p.dist_m, 0.0)


@_term
def size(p: AssignmentProblem) -> NDArray[np.float64]:
    return _per_cluster(p, p.clusters.sizes * p.resolution_m)


@_term
def advantage(p: AssignmentProblem) -> NDArray[np.float64]:
    if p.n_robots < 2:
        return np.zeros((p.n_robots, p.n_clusters))
    d, other = p.dist_m, _others(p)
    both = np.isfinite(d) & np.isfinite(other)
    return np.clip(np.where(both, d, 0.0) - np.where(both, other, 0.0), -30.0, 30.0)


@_term
def distance_squared(p: AssignmentProblem) -> NDArray[np.float64]:
    d = p.dist_m
    return np.where(np.isfinite(d), d * d / 10.0, 0.0)


@_term
def distance_log(p: AssignmentProblem) -> NDArray[np.float64]:
    d = p.dist_m
    return np.where(np.isfinite(d), np.log1p(np.where(np.isfinite(d), d, 0.0)), 0.0)


@dataclass
class _TermsPlanner(LearnedPlanner):
    """The learned planner with extra cost terms (deterministic decoding)."""

    terms: dict[str, float] = field(default_factory=dict)

    def _cost(self, problem: AssignmentProblem) -> Any:
        g, cost, value = super()._cost(problem)
        for name, w in self.terms.items():
            cost = cost + w * TERMS[name](problem)
        return g, cost, value


def _split_shared_finish(self: ExplorationPipeline, posed: PosedDecision, assignment: Assignment) -> Decision:
    """:meth:`ExplorationPipeline.finish` where robots sharing a cluster divide its members."""
    p, w = posed.problem, posed.work
    assert p is not None and w is not None
    a = assignment.cluster_of_robot
    parts: dict[int, NDArray[np.int32]] = {}
    ks, counts = np.unique(a[a != UNASSIGNED], return_counts=True)
    for k in ks[counts > 1]:
        sharers = np.flatnonzero(a == k)
        members = p.clusters.members_of(int(k))
        owner = np.stack([np.asarray(w.fields[i].at(members), np.float64) for i in sharers]).argmin(axis=0)
        parts.update({int(i): members[owner == j] for j, i in enumerate(sharers)})

    def route(i: int, k: int) -> NDArray[np.int32]:
        if k == UNASSIGNED:
            return _NO_ROUTE
        part = parts.get(i)
        if part is None or len(part) == 0 or w.kept.get(i, (None,))[0] == k:
            return self.route(i, k, p, w)
        if self.local is not None and self.local.applies(len(part)):
            r = self.local.route(w.passable, tuple(p.robots_rc[i]), w.fields[i], part, p.resolution_m)
            if r is not None:
                return r.targets_rc
        mid = part.mean(axis=0)
        return part[np.argmin(((part - mid) ** 2).sum(axis=1))][None, :]

    routes = [route(i, int(k)) for i, k in enumerate(a)]
    return _decision(p.state, w.frontiers, p.clusters, assignment, routes, w.fields, w.passable, p.robots_rc)


def episode(args: tuple[dict[str, Any], str, int, int]) -> tuple[int, float, int]:
    """Steps, coverage and steps to 99% coverage (all its steps where it never gets there) of one episode
    of the shipped policy with the variant's terms."""
    variant, spec, robots, seed = args
    cfg = TrainConfig()
    pipeline = make_strategy("hier")
    shipped: LearnedPlanner = pipeline.planner  # type: ignore[assignment]
    terms = {k: float(v) for k, v in variant.items() if k not in NOT_TERMS}
    pipeline.planner = _TermsPlanner(shipped.net, shipped.heuristic, terms=terms)
    if variant.get("split_shared"):
        pipeline.finish = types.MethodType(_split_shared_finish, pipeline)  # type: ignore[method-assign]
    truth = _map(spec, cfg.resolution_m)
    sim = SimConfig(robots=int(variant.get("robots", robots)))
    m = Mission(truth, pipeline, sim, replace(MissionConfig(), max_steps=cfg.max_steps), seed, progress=False)
    while m.advance():
        m.decide()
    curve = np.asarray(m.curve)
    to99 = int(np.argmax(curve >= 0.99)) if (curve >= 0.99).any() else m.steps
    return m.steps, m.sim.coverage, to99


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--episodes", type=int, default=128)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--seed", type=int, default=0, help="draws the episodes (0: probe_residual's)")
    ap.add_argument("--variants", required=True, help="JSON list of {term: weight} mappings")
    ap.add_argument("--base", default="{}", help="JSON mapping every run gets, the reference among them")
    args = ap.parse_args()
    if not TRAIN.is_dir():
        print(f"skipped: training maps not found at {TRAIN}", file=sys.stderr)
        return 0
    try:
        variants, base = json.loads(args.variants), json.loads(args.base)
    except json.JSONDecodeError as exc:
        raise MrExploreError(f"--variants or --base is not JSON ({exc})") from None
    known = sorted([*TERMS, *NOT_TERMS])
    for v in [base, *variants] if isinstance(variants, list) else [variants]:
        if not isinstance(v, dict) or any(k not in known for k in v):
            raise MrExploreError(f"a variant must be a mapping of {', '.join(known)} to numbers, got {v!r}")
    eps = training_episodes(args.episodes, args.seed)
    print(f"policy {default_policy_path().name}, {len(eps)} episodes", flush=True)
    ctx = multiprocessing.get_context("spawn")
    with ProcessPoolExecutor(args.workers, mp_context=ctx) as pool:
        ref = list(pool.map(episode, [(base, *e) for e in eps]))
        ref_steps, ref99 = [r[0] for r in ref], [r[2] for r in ref]
        cov = np.mean([r[1] for r in ref])
        print(f"reference {base}: {np.mean(ref_steps):.1f} steps, {np.mean(ref99):.1f} to 99%, coverage {cov:.4f}")
        for v in variants:
            res = list(pool.map(episode, [({**base, **v}, *e) for e in eps]))
            steps, to99 = [r[0] for r in res], [r[2] for r in res]
            est, lo, hi = paired_bootstrap(steps, ref_steps)
            e99, l99, h99 = paired_bootstrap(to99, ref99)
            cov = np.mean([r[1] for r in res])
            print(
                f"{v}: {np.mean(steps):.1f} steps, {np.mean(to99):.1f} to 99%, coverage {cov:.4f}; fewer steps "
                f"{est:+.1f}% [{lo:+.1f}, {hi:+.1f}], to 99% {e99:+.1f}% [{l99:+.1f}, {h99:+.1f}]"
            )
            sys.stdout.flush()
    return 0


if __name__ == "__main__":
    sys.exit(run_script(main))
