"""A whole mission's centre decisions by phase: median and mean time while the team's coverage is in each band.

    python perf/decision_phases.py --map ../shared/maps/kth_floorplans/50010535_PLAN1.yaml --robots 8
    python perf/decision_phases.py ... --config docs/results/far_threshold/far05.yaml   # other settings

The mission of ``mrexplore explore`` with the same settings (`hier`, the shipped policy, seed 0, 0.05 m by
default); the decision time is the mission's own (`plan_ms`: the centre's round and planning, the robots'
work and the byte accounting left out).
Set ``MREXPLORE_THREADS=1`` to time on one core. A whole KTH floor takes minutes.
"""

from __future__ import annotations

import argparse
import json
from dataclasses import replace
from pathlib import Path

import numpy as np

from mrexplore.config import RunConfig, read_config_file
from mrexplore.maps.loaders import load_map
from mrexplore.mission import Mission, MissionSpec
from mrexplore.pipeline import make_strategy

BANDS = (0.0, 0.15, 0.3, 0.5, 0.75, 0.95, 1.01)


def phases(map_path: str, robots: int, strategy: str, resolution_m: float, cfg: RunConfig, seed: int) -> dict:
    truth = load_map(map_path, replace(cfg.map, resolution_m=resolution_m))
    pipeline = make_strategy(strategy, cfg.global_planning, cfg.preprocess, cfg.local_planning, coscan_cfg=cfg.coscan)
    m = Mission(MissionSpec(truth, pipeline, replace(cfg.sim, robots=robots), cfg.mission, seed), progress=False)
    coverage = []
    while m.advance():
        m.decide()
        coverage.append(m.sim.coverage)
    ms, cov = np.array(m.record.plan_ms), np.array(coverage[: len(m.record.plan_ms)])
    rows = []
    for lo, hi in zip(BANDS[:-1], BANDS[1:], strict=True):
        sel = (cov >= lo) & (cov < hi)
        if sel.any():
            rows.append(
                {
                    "from": lo,
                    "to": min(hi, 1.0),
                    "decisions": int(sel.sum()),
                    "median_ms": float(np.median(ms[sel])),
                    "mean_ms": float(ms[sel].mean()),
                }
            )
    return {
        "steps": m.steps,
        "decisions": len(ms),
        "median_ms": float(np.median(ms)),
        "mean_ms": float(ms.mean()),
        "p95_ms": float(np.percentile(ms, 95)),
        "phases": rows,
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--map", required=True)
    ap.add_argument("--robots", type=int, default=8)
    ap.add_argument("--strategy", default="hier")
    ap.add_argument("--resolution", type=float, default=0.05)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--config", type=Path, help="a run config (YAML) whose planning settings to use")
    ap.add_argument("--json", type=Path, help="also write the figures here")
    args = ap.parse_args()
    cfg = read_config_file(args.config) if args.config else RunConfig()
    out = phases(args.map, args.robots, args.strategy, args.resolution, cfg, args.seed)
    name = Path(args.map).stem
    print(f"{name}, {args.strategy}, {args.robots} robots: {out['steps']} steps, {out['decisions']} decisions")
    print(f"decision median {out['median_ms']:.1f} ms, mean {out['mean_ms']:.1f}, p95 {out['p95_ms']:.1f}")
    print("coverage     decisions  median ms  mean ms")
    for r in out["phases"]:
        print(f"{r['from']:.2f}-{r['to']:.2f}  {r['decisions']:9d}  {r['median_ms']:9.1f}  {r['mean_ms']:7.1f}")
    if args.json:
        args.json.write_text(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
