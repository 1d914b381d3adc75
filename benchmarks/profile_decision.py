"""Where a mission's centre decisions spend their time: by coverage band, and by phase through the library's
timing hooks (the centre's round, candidates, distances, assignment, routes); optionally cProfile's top lines.

    python benchmarks/profile_decision.py --map ../shared/maps/kth_floorplans/50010535_PLAN1.yaml --robots 8
    python benchmarks/profile_decision.py --map MAP --from-coverage 0.5 --decisions 40 --cprofile

The mission of ``mrexplore explore`` with the same settings (``hier``, the shipped policy, seed 0, 0.05 m by
default; ``--config`` for others); the decision time is the mission's own (``plan_ms``: the centre's round
and planning, the robots' work and the byte accounting left out). ``--from-coverage`` runs the mission
untimed to that coverage first, ``--decisions`` stops after that many timed decisions. Set
``MREXPLORE_THREADS=1`` to time on one core. A whole KTH floor takes minutes.
"""

from __future__ import annotations

import argparse
import cProfile
import json
import pstats
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
from _common import run_script

from mrexplore.config import RunConfig, read_config_file
from mrexplore.maps.loaders import load_map
from mrexplore.mission import Mission, MissionSpec
from mrexplore.pipeline import make_strategy
from mrexplore.runtime.timing import PhaseTimes

BANDS = (0.0, 0.15, 0.3, 0.5, 0.75, 0.95, 1.01)
PHASES = ("round", "candidates", "distances", "assignment", "routes")
"""The decision's phases the hooks time, in order (``round``: decoding and rebuilding the team grid)."""


def profile(args: argparse.Namespace, cfg: RunConfig) -> dict:
    truth = load_map(args.map, replace(cfg.map, resolution_m=args.resolution))
    pipeline = make_strategy(
        args.strategy, cfg.global_planning, cfg.preprocess, cfg.local_planning, coscan_cfg=cfg.coscan
    )
    spec = MissionSpec(truth, pipeline, replace(cfg.sim, robots=args.robots), cfg.mission, args.seed)
    m = Mission(spec, progress=False)
    while args.from_coverage is not None and m.sim.coverage < args.from_coverage and m.advance():
        m.decide()
    first = len(m.record.plan_ms)
    pipeline.timer = times = PhaseTimes()
    profiler = cProfile.Profile() if args.cprofile else None
    coverage: list[float] = []
    while (args.decisions is None or len(coverage) < args.decisions) and m.advance():
        if profiler is not None:
            profiler.enable()
        m.decide()
        if profiler is not None:
            profiler.disable()
        coverage.append(m.sim.coverage)
    ms, cov = np.array(m.record.plan_ms[first:]), np.array(coverage[: len(m.record.plan_ms) - first])
    bands = []
    for lo, hi in zip(BANDS[:-1], BANDS[1:], strict=True):
        sel = (cov >= lo) & (cov < hi)
        if sel.any():
            bands.append(
                {
                    "from": lo,
                    "to": min(hi, 1.0),
                    "decisions": int(sel.sum()),
                    "median_ms": float(np.median(ms[sel])),
                    "mean_ms": float(ms[sel].mean()),
                }
            )
    if profiler is not None:
        pstats.Stats(profiler, stream=sys.stdout).sort_stats("cumulative").print_stats(25)
    return {
        "steps": m.steps,
        "decisions": len(ms),
        "median_ms": float(np.median(ms)),
        "mean_ms": float(ms.mean()),
        "p95_ms": float(np.percentile(ms, 95)),
        "bands": bands,
        "phases_ms_per_decision": {p: float(np.sum(times.ms[p])) / max(1, len(ms)) for p in PHASES if p in times.ms},
    }


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--map", required=True)
    ap.add_argument("--robots", type=int, default=8)
    ap.add_argument("--strategy", default="hier")
    ap.add_argument("--resolution", type=float, default=0.05)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--from-coverage", type=float, default=None, help="time only from this coverage (0-1) on")
    ap.add_argument("--decisions", type=int, default=None, help="stop after this many timed decisions")
    ap.add_argument("--cprofile", action="store_true", help="also print cProfile's top lines of the timed decisions")
    ap.add_argument("--config", type=Path, help="a run config (YAML) whose settings to use")
    ap.add_argument("--json", type=Path, help="also write the figures here")
    args = ap.parse_args()
    cfg = read_config_file(args.config) if args.config else RunConfig()
    out = profile(args, cfg)
    name = Path(args.map).stem
    print(f"{name}, {args.strategy}, {args.robots} robots: {out['steps']} steps, {out['decisions']} decisions timed")
    print(f"decision median {out['median_ms']:.1f} ms, mean {out['mean_ms']:.1f}, p95 {out['p95_ms']:.1f}")
    print("coverage     decisions  median ms  mean ms")
    for r in out["bands"]:
        print(f"{r['from']:.2f}-{r['to']:.2f}  {r['decisions']:9d}  {r['median_ms']:9.1f}  {r['mean_ms']:7.1f}")
    print("phase        ms per decision (mean)")
    for p, v in out["phases_ms_per_decision"].items():
        print(f"{p:11s}  {v:8.2f}")
    if args.json:
        args.json.write_text(json.dumps(out, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(run_script(main))
