"""How flat is the heuristic's neighbourhood? ``hier`` with a linear residual on the mGNN's edge features,
against the untrained network (``hier-heuristic``), paired on training maps.

    python perf/probe_residual.py [--episodes 128] [--workers 2] [--variants '[[0,0,0,3,0], ...]']
                                  [--reference '[w1, ..., w5]'] [--settings '[{"preprocess": {...}}, ...]']

Each variant is a weight vector ``w`` over the five edge features of
:func:`~mrexplore.global_planning.learned.features.graph_inputs` (d_ik / 10 m, |C_k| m / 5 m, advantage
/ 10 m, current goal 0/1, isolation / 10 m); the affinity is E_rc = base + w . edge, in metres of detour
(base = -(3 d - size) / 3), decoded by the Hungarian algorithm: the learned planner with an untrained
network whose linear edge path holds ``w`` (what the trainer's policy search sets). ``[0, 0, 0, 3, 0]``,
for instance, offers each robot the cluster of its current goal 3 m nearer than it is. Variants are
compared with ``--reference`` (default the zero residual, i.e. ``hier-heuristic``; the shipped policy's
weights, say, to ask what a move from there does). With ``--settings`` the variants are instead settings
of the pipeline and the mission run with the reference's weights: each a mapping of ``--config``
sections (``preprocess``, ``global_planning``, ``local_planning``, ``mission``, or ``local: false`` for no
local layer), e.g. ``{"preprocess": {"bandwidth_percentile": 25}}``, checked as ``--config`` checks a
file. The episodes are the trainer's: training DungeonMaps (the trainer's split, never its validation maps) and
``varied:`` plans of training seeds, half each, 2-5 robots, 0.1 m, the same maps, seeds and starts for
every variant. It prints each variant's mean steps and coverage and its fewer steps than the
reference, % with a 95% paired bootstrap interval. Only training maps are read: no dev map.
"""

from __future__ import annotations

import argparse
import json
import multiprocessing
import sys
from concurrent.futures import ProcessPoolExecutor
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from mrexplore.bench.report import paired_bootstrap
from mrexplore.cli import run_script
from mrexplore.config import LearnedConfig, RunConfig, SimConfig, TrainConfig, config_from_dict
from mrexplore.global_planning.learned.features import EDGE_FEATURES
from mrexplore.global_planning.learned.network import MultiGraphNet
from mrexplore.global_planning.learned.policy import LearnedPlanner
from mrexplore.global_planning.learned.trainer import _map, split_maps
from mrexplore.mission import Mission
from mrexplore.strategies import make_strategy
from mrexplore.types import MrExploreError

TRAIN = Path(__file__).resolve().parents[2] / "shared" / "maps" / "train"
DEFAULT_VARIANTS = [
    [0, 0, 0, 5, 0],
    [0, 0, 0, -3, 0],
    [0, 2, 0, 0, 0],
    [0, -1, 0, 0, 0],
    [0, 0, -5, 0, 0],
    [0, 0, 5, 0, 0],
    [0, 0, 0, 0, 5],
    [0, 0, 0, 0, -5],
    [2, 0, 0, 0, 0],
]
"""One feature moved at a time, both ways where both are plausible."""


def _run_config(settings: dict[str, Any]) -> tuple[RunConfig, bool]:
    """The settings of a ``--settings`` variant as a checked :class:`RunConfig`, and whether the local
    layer stays."""
    sections = {k: v for k, v in settings.items() if k != "local"}
    local = settings.get("local", True)
    if not isinstance(local, bool):
        raise MrExploreError(f"a settings variant's 'local' must be true or false, got {local!r}")
    try:
        return config_from_dict(RunConfig, sections), local
    except MrExploreError as exc:
        raise MrExploreError(f"--settings {settings}: {exc}") from None


def episode(args: tuple[list[float], dict[str, Any], str, int, int]) -> tuple[int, float]:
    """Steps and coverage of one episode of ``hier`` with the residual ``w`` (all zero: hier-heuristic)
    under ``settings`` (a ``--settings`` variant; empty: the defaults)."""
    w, settings, spec, robots, seed = args
    cfg = TrainConfig()
    run, local = _run_config(settings)
    pipeline = make_strategy("hier-heuristic", run.global_planning, run.preprocess, run.local_planning, local=local)
    if any(w):
        net = MultiGraphNet(LearnedConfig())
        net.set_edge_weights(w)  # the untrained MLP adds zero: the residual is edges . w, as the search sets it
        pipeline.planner = LearnedPlanner(net)
    sim = SimConfig(robots=robots)
    truth = _map(spec, cfg.resolution_m)
    mission = replace(run.mission, max_steps=cfg.max_steps)
    m = Mission(truth, pipeline, sim, mission, seed, progress=False)
    while m.advance():
        m.decide()
    return m.steps, m.sim.coverage


def training_episodes(n: int, seed: int = 0) -> list[tuple[str, int, int]]:
    """``n`` episodes (map, robots, seed) of the trainer's: half training-split DungeonMaps (never its
    validation maps), half ``varied:`` plans of training seeds, 2-5 robots; ``seed`` draws them."""
    cfg = TrainConfig()
    dungeons, _ = split_maps(TRAIN, cfg.val_maps, cfg.plans)
    rng = np.random.default_rng(seed)
    maps = [dungeons[int(i)] for i in rng.choice(len(dungeons), n // 2, replace=False)]
    maps += [f"{cfg.plans}:{int(s)}" for s in rng.integers(0, 1_000_000, n - len(maps))]
    return [(m, int(rng.integers(cfg.robots_min, cfg.robots_max + 1)), int(rng.integers(0, 2**31 - 1))) for m in maps]


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--episodes", type=int, default=128)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--variants", default=None, help=f"JSON list of {EDGE_FEATURES}-weight lists (default: a sweep)")
    ap.add_argument("--reference", default=None, help=f"JSON list of {EDGE_FEATURES} weights (default: zeros)")
    ap.add_argument("--settings", default=None, help="JSON list of settings variants (instead of --variants)")
    args = ap.parse_args()
    if not TRAIN.is_dir():
        print(f"skipped: training maps not found at {TRAIN}", file=sys.stderr)
        return 0
    try:
        variants = json.loads(args.variants) if args.variants else DEFAULT_VARIANTS
        reference = json.loads(args.reference) if args.reference else [0.0] * EDGE_FEATURES
        settings = json.loads(args.settings) if args.settings else None
    except json.JSONDecodeError as exc:
        raise MrExploreError(f"--variants, --reference or --settings is not JSON ({exc})") from None
    for w in [reference, *variants]:
        if not isinstance(w, list) or len(w) != EDGE_FEATURES:
            n = EDGE_FEATURES
            raise MrExploreError(f"a weight vector needs {n} numbers, got {w!r}; pass lists of {n} numbers")
    if settings is not None:
        if not isinstance(settings, list) or not all(isinstance(v, dict) for v in settings):
            raise MrExploreError(f"--settings must be a JSON list of mappings, got {settings!r}")
        for v in settings:
            _run_config(v)  # a bad key fails here, before any episode runs
    runs = [(reference, v) for v in settings] if settings is not None else [(w, {}) for w in variants]
    eps = training_episodes(args.episodes)
    ctx = multiprocessing.get_context("spawn")
    with ProcessPoolExecutor(args.workers, mp_context=ctx) as pool:
        base = list(pool.map(episode, [(reference, {}, *e) for e in eps]))
        b_steps = [s for s, _ in base]
        cov = np.mean([c for _, c in base])
        print(f"reference w = {reference}: {np.mean(b_steps):.1f} steps, coverage {cov:.4f}", flush=True)
        for w, setting in runs:
            res = list(pool.map(episode, [(w, setting, *e) for e in eps]))
            steps = [s for s, _ in res]
            est, lo, hi = paired_bootstrap(steps, b_steps)
            print(
                f"{setting or f'w = {w}'}: {np.mean(steps):.1f} steps, coverage {np.mean([c for _, c in res]):.4f}, "
                f"{est:+.1f}% fewer [{lo:+.1f}, {hi:+.1f}]",
                flush=True,
            )
    return 0


if __name__ == "__main__":
    sys.exit(run_script(main))
