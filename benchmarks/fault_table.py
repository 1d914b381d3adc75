"""Exploration under faults: one bench per fault setting on the same maps, seeds and starts, and a table of
steps and coverage against the fault-free run (paired differences with bootstrap intervals).

    python benchmarks/fault_table.py --out runs/faults

Each setting is an ordinary ``mrexplore bench`` run into its own folder (resumable); the table goes to
OUT/report.md.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
from _common import run_script, skip

from mrexplore.bench.report import paired_bootstrap
from mrexplore.bench.runner import read_rows
from mrexplore.cli import main as cli
from mrexplore.runtime.example_maps import maps_dir

SHARED = maps_dir()
SETTINGS = {
    "none": [],
    "robot 1 lost at step 100": ["--robot-failure", "1@100"],
    "10% message loss": ["--message-loss", "0.1"],
    "30% message loss": ["--message-loss", "0.3"],
    "centre restart at step 100": ["--centre-restart", "100"],
    "radio range 10 m": ["--comm-range", "10"],
}


def _maps() -> list[str]:
    hx = sorted((SHARED / "houseexpo" / "png").glob("*.png"))[:10]
    dungeon = sorted((SHARED / "dungeon").glob("*.png"))[:5]
    return [str(p) for p in [*hx, *dungeon]]


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="runs/faults")
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--strategies", default="hier,utility")
    ap.add_argument("--workers", type=int, default=0)
    args = ap.parse_args()
    if not SHARED.is_dir():
        return skip("the example maps", SHARED)
    out = Path(args.out)
    common = ["--maps", *_maps(), "--strategies", args.strategies, "--robots", "3", "--seeds", str(args.seeds)]
    common += ["--resolution", "0.1", "--max-steps", "6000", "--workers", str(args.workers), "--no-progress"]
    for i, (name, flags) in enumerate(SETTINGS.items()):
        code = cli(["bench", *common, *flags, "--out", str(out / f"setting{i}")])
        if code:
            sys.exit(f"bench for {name!r} failed ({code})")
    base = {_key(r): r for r in read_rows(out / "setting0" / "results.csv")}
    lines = [
        "# Exploration under faults",
        "",
        f"Made by: `python benchmarks/fault_table.py --out {args.out} --seeds {args.seeds} "
        f"--strategies {args.strategies}`",
        f"({len(_maps())} dev maps: 10 HouseExpo, 5 DungeonMaps; 3 robots; 0.1 m; seeds 0..{args.seeds - 1}; the",
        "same starts in every setting). Steps: mean over episodes; Δ: paired difference against no fault in % of",
        "its mean steps (positive: more steps), with a 95% bootstrap interval; coverage: the lowest of any",
        "episode; msgs lost / resent: per episode.",
        "",
        "| strategy | fault | episodes | steps | Δ steps vs none, % [95% CI] | min coverage | ended by budget "
        "| msgs lost | msgs resent |",
        "|---|---|---:|---:|---|---:|---:|---:|---:|",
    ]
    for strategy in args.strategies.split(","):
        for i, name in enumerate(SETTINGS):
            rows = [r for r in read_rows(out / f"setting{i}" / "results.csv") if r["strategy"] == strategy]
            pairs = [(float(r["steps"]), float(base[_key(r)]["steps"])) for r in rows if _key(r) in base]
            fewer, lo, hi = paired_bootstrap([a for a, _ in pairs], [b for _, b in pairs])
            steps = np.mean([float(r["steps"]) for r in rows])
            lines.append(
                f"| {strategy} | {name} | {len(rows)} | {steps:.1f} | {_pct(-fewer)}% [{_pct(-hi)}, {_pct(-lo)}] "
                f"| {min(float(r['coverage']) for r in rows):.4f} "
                f"| {sum(r['done_reason'] == 'max_steps' for r in rows)} "
                f"| {np.mean([int(r['messages_lost']) for r in rows]):.1f} "
                f"| {np.mean([int(r['messages_resent']) for r in rows]):.1f} |"
            )
    (out / "report.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))
    return 0


def _pct(x: float) -> str:
    return f"{x + 0.0:+.1f}".replace("-0.0", "+0.0")  # no negative zero


def _key(r: dict[str, str]) -> tuple[str, str, str]:
    return (r["map_resolved"], r["strategy"], r["seed"])


if __name__ == "__main__":
    sys.exit(run_script(main))
