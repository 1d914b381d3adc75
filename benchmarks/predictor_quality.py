"""How well the predictors that need no learning guess the unseen, on beliefs taken mid-mission on the dev maps:
per-cell accuracy and the IoU of predicted free space on the unknown cells within 3 m and 6 m of a frontier.
These are the yardsticks a learned map predictor has to beat.

Run: python benchmarks/predictor_quality.py --out docs/results/prediction_baselines [--maps 10] [--moments 3]
Missions: ``utility``, 3 robots, 0.1 m, seed 0; ``--moments`` beliefs a mission, at steps drawn at random
(seeded) among those with coverage between 10% and 90%. Scores pool the cells of every belief.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
from _common import run_script

from mrexplore.config import MapConfig, SimConfig
from mrexplore.example_maps import maps_dir
from mrexplore.maps.loaders import load_map
from mrexplore.mission import MissionSpec, run_mission
from mrexplore.pipeline import make_strategy
from mrexplore.prediction.baselines import predict_all_free, predict_extended_walls
from mrexplore.prediction.quality import near_frontier
from mrexplore.progress import Progress
from mrexplore.sim.belief import merge_beliefs

PREDICTORS = {"every unknown cell free": predict_all_free, "walls extended": predict_extended_walls}
RADII_M = (3.0, 6.0)


def beliefs(path: Path, moments: int, rng: np.random.Generator) -> tuple[list[np.ndarray], np.ndarray, float]:
    """The team's belief at ``moments`` random steps of a mission on ``path``, the truth's free cells, the
    cell size."""
    truth = load_map(path, MapConfig(resolution_m=0.1))
    kept: list[tuple[int, np.ndarray]] = []

    def observe(sim, decision, goals, status) -> None:  # noqa: ANN001 - the mission's observer
        if 0.1 <= sim.coverage <= 0.9 and sim.steps % 5 == 0:
            kept.append((sim.steps, merge_beliefs(sim.beliefs).state(sim.cfg.sensor)))

    run_mission(MissionSpec(truth, make_strategy("utility"), SimConfig(robots=3), seed=0), observe, progress=False)
    picks = rng.choice(len(kept), size=min(moments, len(kept)), replace=False).tolist() if kept else []
    return [kept[i][1] for i in sorted(picks)], ~truth.occupied, truth.frame.resolution_m


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", required=True, type=Path, help="folder for report.md")
    ap.add_argument("--maps", type=int, default=10, help="dev maps per dataset, the first by name (default 10)")
    ap.add_argument("--moments", type=int, default=3, help="beliefs taken per mission (default 3)")
    args = ap.parse_args()
    sets = {
        "HouseExpo": sorted((maps_dir() / "houseexpo" / "png").glob("*.png")),
        "DungeonMaps": sorted((maps_dir() / "dungeon").glob("*.png")),
    }
    if not all(sets.values()):
        print(f"skipped: the dev maps not found under {maps_dir()}; set MREXPLORE_MAPS", file=sys.stderr)
        return 0
    rng = np.random.default_rng(0)
    rows = []
    bar = Progress(sum(min(args.maps, len(v)) for v in sets.values()), "predictor quality", "maps")
    for dataset, files in sets.items():
        pooled = {(name, r): np.zeros(4) for name in PREDICTORS for r in RADII_M}  # cells, right, inter, union
        for path in files[: args.maps]:
            states, truth_free, res = beliefs(path, args.moments, rng)
            for state in states:
                for r in RADII_M:
                    band = near_frontier(state, res, r)
                    true = truth_free[band]
                    for name, predict in PREDICTORS.items():
                        pred = predict(state, res)[band] > 0.5
                        pooled[name, r] += (band.sum(), (pred == true).sum(), (pred & true).sum(), (pred | true).sum())
            bar.update()
        for (name, r), (n, right, inter, union) in pooled.items():
            rows.append(f"| {dataset} | {r:g} m | {name} | {int(n):,} | {right / n:.3f} | {inter / union:.3f} |")
    bar.close()
    table = "| dataset | band | predictor | cells | accuracy | IoU (free) |\n| --- | --- | --- | --- | --- | --- |\n"
    table += "\n".join(rows)
    command = "python benchmarks/predictor_quality.py " + " ".join(sys.argv[1:])
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "report.md").write_text(
        "# Predicting the unseen without learning: the yardsticks\n\n"
        f"Made by: `{command}`. Unknown cells within 3 m and 6 m of a frontier, in beliefs taken at random "
        "moments (coverage 10-90%) of `utility` missions, 3 robots, 0.1 m; pooled over every belief.\n\n"
        f"{table}\n"
    )
    print(table)
    return 0


if __name__ == "__main__":
    sys.exit(run_script(main))
