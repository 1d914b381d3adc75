"""The learned strategies deciding with NumPy (no torch) against torch: every dev-set episode of ``hier``
and ``ncm`` at one seed, row for row, and their planning time side by side.

Run: python benchmarks/inference_parity.py --out docs/results/inference_parity [--workers 2]
It runs the bench twice on the same episodes, deciding on the NumPy networks (what the strategies run) and on
the torch ones (training's twins, which answer the same scoring protocol), in two folders under ``--out`` (each
resumable), then writes ``report.md``:
per strategy, the episodes whose results differ in any column but timings, each with its steps, and the
planning time of both runs summed.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from _common import run_script

from mrexplore.bench.compare import _NOT_RESULTS
from mrexplore.bench.runner import read_rows
from mrexplore.runtime.example_maps import maps_dir

BACKENDS = ("numpy", "torch")


def bench(backend: str, out: Path, maps: list[str], strategies: str, workers: int) -> None:
    from dataclasses import replace

    from mrexplore.bench.runner import EpisodeSpec, expand_maps, run_bench, run_episode
    from mrexplore.config import MapConfig, MissionConfig, RunConfig
    from mrexplore.training.twins import episode_deciding_with_torch

    run = RunConfig(map=MapConfig(resolution_m=0.1), mission=replace(MissionConfig(), max_steps=2000))
    names = [s for s in strategies.split(",") if s]
    specs = [EpisodeSpec(m, s, 3, 0, run) for m in expand_maps(maps) for s in names]
    print(f"{backend}: {len(specs)} episodes, 3 robots, seed 0, 0.1 m -> {out / backend}", flush=True)
    episode = episode_deciding_with_torch if backend == "torch" else run_episode
    run_bench(specs, out / backend / "results.csv", workers, None, None, episode)


def compare(out: Path, strategies: list[str]) -> str:
    runs = {b: read_rows(out / b / "results.csv") for b in BACKENDS}
    lines = [
        "| strategy | episodes | results differ | planning s, numpy | planning s, torch | numpy / torch |",
        "| --- | --- | --- | --- | --- | --- |",
    ]
    notes = []
    for s in strategies:
        by = {b: {r["map_path"]: r for r in runs[b] if r["strategy"] == s} for b in BACKENDS}
        shared = sorted(set(by["numpy"]) & set(by["torch"]))
        differ = [
            m
            for m in shared
            if any(by["numpy"][m][c] != by["torch"][m][c] for c in by["numpy"][m] if c not in _NOT_RESULTS)
        ]
        secs = {
            b: sum(float(by[b][m]["plan_ms_mean"]) * int(by[b][m]["decisions"]) / 1e3 for m in shared) for b in BACKENDS
        }
        ratio = secs["numpy"] / secs["torch"] if secs["torch"] else float("nan")
        lines.append(
            f"| {s} | {len(shared)} | {len(differ)} | {secs['numpy']:,.1f} | {secs['torch']:,.1f} | {ratio:.2f} |"
        )
        for m in differ:
            a, b = by["numpy"][m], by["torch"][m]
            notes.append(
                f"- {s}, `{Path(m).name}`: steps {a['steps']} (numpy) against {b['steps']} (torch), "
                f"coverage {float(a['coverage']):.4f} against {float(b['coverage']):.4f}"
            )
    return "\n".join(lines) + ("\n\nEpisodes that differ:\n\n" + "\n".join(notes) if notes else "") + "\n"


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", required=True, type=Path, help="folder for the two benches and report.md")
    ap.add_argument("--strategies", default="hier,ncm")
    ap.add_argument("--workers", type=int, default=2)
    args = ap.parse_args()
    maps = [maps_dir() / "houseexpo", maps_dir() / "dungeon"]
    if not all(m.is_dir() for m in maps):
        print(f"skipped: the dev maps not found under {maps_dir()}; set MREXPLORE_MAPS", file=sys.stderr)
        return 0
    strategies = [s for s in args.strategies.split(",") if s]
    for backend in BACKENDS:
        bench(backend, args.out, [str(m) for m in maps], args.strategies, args.workers)
    table = compare(args.out, strategies)
    command = "python benchmarks/inference_parity.py " + " ".join(sys.argv[1:])
    (args.out / "report.md").write_text(
        "# Deciding without torch: NumPy against torch on the dev set\n\n"
        f"Made by: `{command}` (3 robots, seed 0, 0.1 m, the shipped policies).\n\n{table}"
    )
    print(table)
    return 0


if __name__ == "__main__":
    sys.exit(run_script(main))
