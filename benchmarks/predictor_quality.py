"""How well the map predictor guesses the unseen, on beliefs taken mid-mission on the dev maps (never trained
on), against two predictors that need no learning: per-cell accuracy and the IoU of predicted free space on
the unknown cells within 3 m and 6 m of a frontier; and a figure of belief, prediction and truth side by side,
one map of each dataset.

Run: python benchmarks/predictor_quality.py --out docs/results/prediction [--maps 100] [--moments 3]
     [--predictor FILE]
Missions: ``utility``, 3 robots, 0.1 m, seed 0; ``--moments`` beliefs a mission, at decisions drawn at random
(seeded) among those with coverage between 10% and 90%. Scores pool the cells of every belief.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable
from pathlib import Path

import numpy as np
from _common import run_script

from mrexplore.config import MapConfig, SimConfig
from mrexplore.maps.loaders import load_map
from mrexplore.mission import MissionSpec, run_mission
from mrexplore.pipeline import make_strategy
from mrexplore.prediction.baselines import predict_all_free, predict_extended_walls
from mrexplore.prediction.network import load_predictor
from mrexplore.prediction.quality import near_frontier
from mrexplore.runtime.example_maps import maps_dir
from mrexplore.runtime.progress import Progress
from mrexplore.types import CellState

RADII_M = (3.0, 6.0)
RESOLUTION_M = 0.1


def beliefs(path: Path, moments: int, rng: np.random.Generator) -> tuple[list[np.ndarray], np.ndarray]:
    """The centre's grid at ``moments`` random decisions of a mission on ``path``, and the truth's free cells."""
    truth = load_map(path, MapConfig(resolution_m=RESOLUTION_M))
    kept: list[np.ndarray] = []
    last: list[object] = [None]

    def observe(sim, decision, goals, status) -> None:  # noqa: ANN001 - the mission's observer
        if decision is not None and decision is not last[0]:
            last[0] = decision
            if 0.1 <= sim.coverage <= 0.9:
                kept.append(decision.state)

    run_mission(MissionSpec(truth, make_strategy("utility"), SimConfig(robots=3), seed=0), observe, progress=False)
    picks = rng.choice(len(kept), size=min(moments, len(kept)), replace=False).tolist() if kept else []
    return [kept[i] for i in sorted(picks)], ~truth.occupied


def figure(panels: list[tuple[str, np.ndarray, np.ndarray, np.ndarray]], png: Path) -> None:
    """One row per dataset: belief, the learned prediction of the unknown cells near a frontier, the truth."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(len(panels), 3, figsize=(12, 3.4 * len(panels)), squeeze=False)
    for row, (title, state, p_free, truth_free) in zip(axes, panels, strict=True):
        belief = np.where(state == CellState.FREE, 1.0, np.where(state == CellState.OCCUPIED, 0.0, 0.6))
        row[0].imshow(belief, cmap="gray", vmin=0, vmax=1, interpolation="nearest")
        row[0].set_title(f"{title}: belief (grey unknown)", fontsize=9)
        shown = np.ma.masked_where(~near_frontier(state, RESOLUTION_M, RADII_M[-1]), p_free)
        row[1].imshow(belief, cmap="gray", vmin=0, vmax=1, interpolation="nearest")
        im = row[1].imshow(shown, cmap="RdYlGn", vmin=0, vmax=1, interpolation="nearest")
        row[1].set_title(f"prediction: P(free) within {RADII_M[-1]:g} m of a frontier", fontsize=9)
        row[2].imshow(truth_free.astype(float), cmap="gray", vmin=0, vmax=1, interpolation="nearest")
        row[2].set_title("truth", fontsize=9)
        for ax in row:
            ax.set_xticks([])
            ax.set_yticks([])
        fig.colorbar(im, ax=row[1], fraction=0.03)
    fig.tight_layout()
    fig.savefig(png, dpi=100)
    plt.close(fig)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", required=True, type=Path, help="folder for report.md and figure.png")
    ap.add_argument("--maps", type=int, default=10, help="dev maps per dataset, the first by name (default 10)")
    ap.add_argument("--moments", type=int, default=3, help="beliefs taken per mission (default 3)")
    ap.add_argument("--predictor", default=None, help="predictor file (default: the shipped one)")
    args = ap.parse_args()
    sets = {
        "HouseExpo": sorted((maps_dir() / "houseexpo" / "png").glob("*.png")),
        "DungeonMaps": sorted((maps_dir() / "dungeon").glob("*.png")),
    }
    if not all(sets.values()):
        print(f"skipped: the dev maps not found under {maps_dir()}; set MREXPLORE_MAPS", file=sys.stderr)
        return 0
    learned = load_predictor(args.predictor)
    predictors: dict[str, Callable[[np.ndarray, float], np.ndarray]] = {
        "every unknown cell free": predict_all_free,
        "walls extended": predict_extended_walls,
        "learned": learned.p_free,
    }
    rng = np.random.default_rng(0)
    rows: list[str] = []
    panels: list[tuple[str, np.ndarray, np.ndarray, np.ndarray]] = []
    bar = Progress(sum(min(args.maps, len(v)) for v in sets.values()), "predictor quality", "maps")
    for dataset, files in sets.items():
        pooled = {(name, r): np.zeros(4) for name in predictors for r in RADII_M}  # cells, right, inter, union
        for path in files[: args.maps]:
            states, truth_free = beliefs(path, args.moments, rng)
            for k, state in enumerate(states):
                predicted = {name: predict(state, RESOLUTION_M) for name, predict in predictors.items()}
                if (not panels or panels[-1][0] != dataset) and k == len(states) // 2:  # a mid-mission belief
                    panels.append((dataset, state, predicted["learned"], truth_free))
                for r in RADII_M:
                    band = near_frontier(state, RESOLUTION_M, r)
                    true = truth_free[band]
                    for name, p in predicted.items():
                        pred = p[band] > 0.5
                        pooled[name, r] += (band.sum(), (pred == true).sum(), (pred & true).sum(), (pred | true).sum())
            bar.update()
        for (name, r), (n, right, inter, union) in sorted(pooled.items(), key=lambda kv: kv[0][1]):
            rows.append(f"| {dataset} | {r:g} m | {name} | {int(n):,} | {right / n:.3f} | {inter / union:.3f} |")
    bar.close()
    table = "| dataset | band | predictor | cells | accuracy | IoU (free) |\n| --- | --- | --- | --- | --- | --- |\n"
    table += "\n".join(rows)
    command = "python benchmarks/predictor_quality.py " + " ".join(sys.argv[1:])
    args.out.mkdir(parents=True, exist_ok=True)
    figure(panels, args.out / "figure.png")
    (args.out / "report.md").write_text(
        "# Predicting the unseen: the learned map predictor against two rules\n\n"
        f"Made by: `{command}`. Predictor: `{learned.path.name}` (sha256 `{learned.sha256[:16]}…`). Unknown "
        "cells within 3 m and 6 m of a frontier, in the centre's grid at random decisions (coverage 10-90%) of "
        "`utility` missions, 3 robots, 0.1 m, on the dev maps (the predictor trained on the training maps "
        "alone); pooled over every belief. A cell is predicted free where P(free) > 0.5.\n\n"
        f"{table}\n\n![belief, prediction and truth](figure.png)\n"
    )
    print(table)
    return 0


if __name__ == "__main__":
    sys.exit(run_script(main))
