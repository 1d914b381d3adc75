"""Whether a team moves as one, and what its frontier is worth: why a strategy crawls on a cluttered map.

    python perf/convoy.py --map ../shared/maps/ros/willow-2010-02-18-0.10.yaml --strategy nearest
    python perf/convoy.py --map ../shared/maps/ros/willow-2010-02-18-0.10.yaml --strategy utility --at 0.9

Runs one mission (0.05 m, seed 0, the strategy's own decisions) until the team's coverage reaches ``--at``
or ``--steps`` run out. It prints the first step at which every robot stood on one cell (robots pass
through one another in the simulator, so nothing keeps a team that chose the same goals apart) and at
what share of the decisions after it they did so. Then it sorts the centre's F_un cells by what lies behind them in
the ground truth: unknown cells that are all walls, or unknown free space in pieces of a given size. A
frontier cell behind which lie walls only, or a few free cells, opens almost nothing when a robot goes
to it.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
from scipy import ndimage

from mrexplore.cli import run_script
from mrexplore.config import MapConfig, MissionConfig, SimConfig
from mrexplore.maps.loaders import load_map
from mrexplore.mission import Mission
from mrexplore.preprocessing.frontiers import detect_frontiers
from mrexplore.strategies import make_strategy
from mrexplore.types import CellState

SIZES = ((1, 10), (10, 100), (100, 1_000), (1_000, 10_000), (10_000, 10**12))
"""Bounds of the free pieces' sizes, in cells, [low, high)."""


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--map", type=Path, required=True)
    ap.add_argument("--strategy", default="nearest")
    ap.add_argument("--robots", type=int, default=3)
    ap.add_argument("--at", type=float, default=0.9, help="stop at this coverage (0-1)")
    ap.add_argument("--steps", type=int, default=20_000)
    args = ap.parse_args()
    truth = load_map(args.map, MapConfig(resolution_m=0.05))
    m = Mission(truth, make_strategy(args.strategy), SimConfig(robots=args.robots), MissionConfig(args.steps), 0)
    together: list[bool] = []
    when: list[int] = []
    while m.advance():  # on to the next decision
        p = m.sim.positions_rc
        together.append(bool((p == p[0]).all()))
        when.append(m.steps)
        m.decide()
        if m.curve[-1] >= args.at:
            break
    one = np.asarray(together)
    first = int(np.argmax(one)) if one.any() else None
    print(f"{truth.name}, {args.strategy}, {args.robots} robots: step {m.steps}, coverage {m.curve[-1]:.4f}")
    if first is None:
        print("the robots never stood on one cell together")
    else:
        share = 100 * one[first:].mean()
        print(f"on one cell from step {when[first]} on, then at {share:.1f}% of the decisions after it")
    unknown = m.state == CellState.UNKNOWN
    hidden = unknown & ~truth.occupied
    labels, _ = ndimage.label(hidden)
    size = np.bincount(labels.ravel())
    size[0] = 0
    un = detect_frontiers(m.state).un_rc
    H, W = unknown.shape
    behind = np.zeros(len(un), dtype=np.int64)  # the largest free piece behind each F_un cell (0: walls only)
    for dr in (-1, 0, 1):
        for dc in (-1, 0, 1):
            r, c = un[:, 0] + dr, un[:, 1] + dc
            ok = (r >= 0) & (r < H) & (c >= 0) & (c < W)
            behind[ok] = np.maximum(behind[ok], size[labels[r[ok], c[ok]]])
    print(f"{len(un)} F_un cells at the centre; behind them in the ground truth:")
    print(f"  walls only: {int((behind == 0).sum())}")
    for lo, hi in SIZES:
        n = int(((behind >= lo) & (behind < hi)).sum())
        print(f"  a free piece of {lo:,}-{hi - 1:,} cells: {n}" if hi < 10**12 else f"  {lo:,} cells or more: {n}")
    return 0


if __name__ == "__main__":
    raise SystemExit(run_script(main))
