"""Encode, decode and reconstruct times of sparse frontier maps, and how much the paper's fill loses.

Run: python benchmarks/transmission.py [--every 25] [--map PATH]
Target on the 2-core dev machine: encode + decode + reconstruct <= 10 ms per robot per round on the
largest HouseExpo map. A hier mission with 3 robots is replayed; every ``--every`` steps each robot's
closed grid is encoded, decoded and rebuilt, timed, and compared with the paper's reconstruction
(scan-line fill from the robot's cell fenced by F_un and F_occ, no neighbour codes; started from the
interior cell nearest the robot, which is generous to it).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np
from _common import houseexpo_dir, largest_houseexpo, run_script
from scipy import ndimage

from mrexplore.config import MissionConfig
from mrexplore.maps.loaders import load_map
from mrexplore.mission import MissionSpec, run_mission
from mrexplore.pipeline import make_strategy
from mrexplore.preprocessing.frontiers import close_unknown_holes, closing_reach
from mrexplore.preprocessing.reconstruction import fill_paper, free_iou, reconstruct
from mrexplore.preprocessing.sparse_codec import decode, encode
from mrexplore.preprocessing.sparse_map import sparse_frontier_map
from mrexplore.types import CellState


def nearest_interior(boundary: np.ndarray, free: np.ndarray, rc: tuple[int, int]) -> tuple[int, int]:
    interior = free & ~boundary
    if not interior.any():
        return rc
    _, (rr, cc) = ndimage.distance_transform_edt(~interior, return_indices=True)
    return int(rr[rc]), int(cc[rc])


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--every", type=int, default=25, help="steps between measured rounds")
    ap.add_argument("--map", type=Path, default=None, help="map file (default: the largest HouseExpo map)")
    ap.add_argument("--max-steps", type=int, default=20000, help="step budget of the replayed mission")
    args = ap.parse_args()
    if args.map is None and not houseexpo_dir().is_dir():
        print(f"skipped: HouseExpo maps not found at {houseexpo_dir()}", file=sys.stderr)
        return 0
    path = args.map or largest_houseexpo()
    truth = load_map(path)
    strategy = make_strategy("hier")
    times: dict[str, list[float]] = {"encode": [], "decode": [], "reconstruct": []}
    iou_exact: list[float] = []
    iou_paper: list[float] = []
    sizes: list[int] = []
    on_fence: list[bool] = []

    def observe(sim, decision, goals, status) -> None:
        if sim.steps % args.every:
            return
        size = strategy.preprocess.closing_size_cells
        for i, belief in enumerate(sim.beliefs):
            closed = close_unknown_holes(belief.state(sim.cfg.sensor), size)
            pos = (int(sim.positions_rc[i, 0]), int(sim.positions_rc[i, 1]))
            # As the robots do in TeamLink: the message built on the box of the robot's observed cells.
            window = belief.window(closing_reach(size) + 1)
            origin = (window[0].start, window[1].start)
            t0 = time.perf_counter()
            data = encode(sparse_frontier_map(closed[window], i, sim.steps, pos, origin, closed.shape))
            t1 = time.perf_counter()
            message = decode(data)
            t2 = time.perf_counter()
            rebuilt = reconstruct(message.code_grid(), message.seeds, message.cells)
            t3 = time.perf_counter()
            for key, dt in zip(times, (t1 - t0, t2 - t1, t3 - t2), strict=True):
                times[key].append(dt * 1e3)
            sizes.append(len(data))
            free = closed == CellState.FREE
            codes_boundary = message.code_grid() != 0
            on_fence.append(bool(codes_boundary[pos]))
            paper = fill_paper(codes_boundary, nearest_interior(codes_boundary, free, pos))
            iou_exact.append(free_iou(rebuilt == CellState.FREE, free))
            iou_paper.append(free_iou(paper, free))

    run_mission(MissionSpec(load_map("generated:0"), strategy))  # compile the numba kernels outside the timings
    spec = MissionSpec(truth, strategy, mission_cfg=MissionConfig(max_steps=args.max_steps))
    result = run_mission(spec, observer=observe)
    total = np.add(np.add(times["encode"], times["decode"]), times["reconstruct"])
    print(f"map {path.stem} ({truth.shape[0]}x{truth.shape[1]} cells), hier, 3 robots, {len(total)} robot-rounds")
    print(f"mission: {result.measures.steps} steps, coverage {result.measures.coverage:.5f}")
    for key, values in times.items():
        print(f"{key:12s} ms median {np.median(values):6.2f}   p95 {np.percentile(values, 95):6.2f}")
    print(f"{'total':12s} ms median {np.median(total):6.2f}   p95 {np.percentile(total, 95):6.2f}   (target <= 10)")
    print(f"message bytes median {np.median(sizes):.0f}, max {max(sizes)}")
    print(f"free-space IoU vs the robot's grid: codes+seeds min {min(iou_exact):.6f} mean {np.mean(iou_exact):.6f}")
    print(f"                                    paper's fill min {min(iou_paper):.6f} mean {np.mean(iou_paper):.6f}")
    print(
        f"robot on F_un/F_occ (the paper's seed has no interior start): {100 * np.mean(on_fence):.1f}% of robot-rounds"
    )
    return 0


if __name__ == "__main__":
    sys.exit(run_script(main))
