"""Policy files side by side on maps no dev set holds, with the heuristic.

    python perf/compare_policies.py POLICY [POLICY ...] [--fresh N] [--robots R] [--workers 2] [--csv PER_MAP.csv]

The maps are those ``mrexplore train`` validates on with the default training config (64: half
held-out training DungeonMaps, half ``varied:`` plans of validation seeds), or with ``--fresh N`` N
``varied:`` plans of seeds no run trains or validates on (from 2,000,000): 3 robots (``--robots R``:
R, ``train.val_robots``; teams the dev set's Table I does not hold, read without its maps), 0.1 m,
deterministic decoding. For ``hier-heuristic`` (the untrained network) and each policy it prints the
mean steps to the end and to 99% coverage, the mean coverage, the score of ``train.score: relative``
(the geometric mean over maps of the ratio to the heuristic's; the heuristic scores 1), and fewer steps
than the first policy, % with a 95% paired bootstrap interval, at the end and to 99%. This is how two
training runs are compared without reading the dev maps: on the validation maps each run's kept stage
was chosen on (each figure optimistic by the same selection), or on fresh plans that neither saw.
``--csv`` writes every map's steps, steps to 99% and coverage per policy.
"""

from __future__ import annotations

import argparse
import csv
import sys
from pathlib import Path

import numpy as np

from mrexplore.bench.report import paired_bootstrap
from mrexplore.cli import run_script
from mrexplore.config import TrainConfig
from mrexplore.training.search import relative_score
from mrexplore.training.trainer import FRESH_SEED0, validate_policy
from mrexplore.types import MrExploreError

TRAIN = Path(__file__).resolve().parents[2] / "shared" / "maps" / "train"


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("policies", nargs="+", type=Path, help="policy files (.pt), the first is the yardstick")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--fresh", type=int, default=0, help="N fresh varied: plans instead of the validation maps")
    ap.add_argument("--csv", type=Path, default=None, help="write per-map results here")
    ap.add_argument("--robots", type=int, default=None, help="robots per episode (default: train.val_robots, 3)")
    args = ap.parse_args()
    if not TRAIN.is_dir():
        print(f"skipped: training maps not found at {TRAIN}", file=sys.stderr)
        return 0
    for p in args.policies:
        if not p.is_file():
            raise MrExploreError(f"policy file not found: {p}; pass a policy.pt that mrexplore train wrote")
    if args.fresh < 0:
        raise MrExploreError(f"--fresh must be >= 0, got {args.fresh}; pass a count of plans, or 0 for validation")
    cfg = TrainConfig() if args.robots is None else TrainConfig(val_robots=args.robots)
    fresh = [f"{cfg.plans}:{FRESH_SEED0 + i}" for i in range(args.fresh)] or None
    maps, ref, ref_cov = validate_policy(None, cfg, TRAIN, args.workers, fresh)
    print(f"{len(maps)} {'fresh' if fresh else 'validation'} maps, {cfg.val_robots} robots, {cfg.resolution_m} m")
    first: np.ndarray | None = None
    per_map: list[dict[str, object]] = []
    for name, policy in [("hier-heuristic", None), *[(str(p), p) for p in args.policies]]:
        steps, cov = (ref, ref_cov) if policy is None else validate_policy(policy, cfg, TRAIN, args.workers, fresh)[1:]
        per_map += [
            {"policy": name, "map": m, "steps": int(a), "steps_99": int(b), "coverage": float(c)}
            for m, a, b, c in zip(maps, steps[0], steps[1], cov, strict=True)
        ]
        score = float(relative_score(steps[0], steps[1], ref[0], ref[1]))
        line = (
            f"{name}: {steps[0].mean():.1f} steps, {steps[1].mean():.1f} to 99%, "
            f"coverage {cov.mean():.4f}, relative score {score:.4f}"
        )
        if policy is not None and first is None:
            first = steps
        elif policy is not None and first is not None:
            (e0, l0, h0), (e1, l1, h1) = (paired_bootstrap(list(steps[k]), list(first[k])) for k in (0, 1))
            line += f"; fewer steps than the first: {e0:+.1f}% [{l0:+.1f}, {h0:+.1f}] end,"
            line += f" {e1:+.1f}% [{l1:+.1f}, {h1:+.1f}] to 99%"
        print(line, flush=True)
    if args.csv is not None:
        with open(args.csv, "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=list(per_map[0]))
            w.writeheader()
            w.writerows(per_map)
    return 0


if __name__ == "__main__":
    sys.exit(run_script(main))
