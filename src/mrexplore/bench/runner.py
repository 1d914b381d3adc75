"""Run many (map, strategy, robots, seed) episodes in worker processes; one CSV row per finished episode.

Rows are appended as episodes finish, so a killed run loses only the episodes in flight; rerunning the
same command skips every episode already in the file.
"""

from __future__ import annotations

import csv
import multiprocessing
import os
import sys
from collections.abc import Iterable, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from tqdm import tqdm

from mrexplore.config import GlobalPlanningConfig, MapConfig, MissionConfig, SimConfig
from mrexplore.maps.loaders import load_map
from mrexplore.mission import run_mission
from mrexplore.strategies import make_strategy
from mrexplore.types import MrExploreError

__all__ = ["EpisodeSpec", "run_episode", "run_bench", "read_rows", "size_class", "COLUMNS", "MAP_SUFFIXES"]

MAP_SUFFIXES = (".yaml", ".yml", ".png", ".pgm", ".json")
SMALL_M2 = 100.0
LARGE_M2 = 300.0
COLUMNS = [
    "map", "map_path", "strategy", "robots", "seed", "size_class", "free_area_m2",
    "steps", "coverage", "steps_to_90", "steps_to_95", "steps_to_99", "path_len_max_m", "path_len_sum_m",
    "overlap", "decisions", "plan_ms_mean", "plan_ms_p95", "wall_s", "done_reason",
]  # fmt: skip


@dataclass(frozen=True)
class EpisodeSpec:
    """One episode of a benchmark."""

    map_path: str
    strategy: str
    robots: int
    seed: int
    resolution_m: float = 0.05
    max_steps: int = 20000
    commitment: float | None = None

    @property
    def key(self) -> tuple[str, str, int, int]:
        return (self.map_path, self.strategy, self.robots, self.seed)


def size_class(free_area_m2: float) -> str:
    """small < 100 m^2 <= middle <= 300 m^2 < large, by explorable free area."""
    if free_area_m2 < SMALL_M2:
        return "small"
    return "middle" if free_area_m2 <= LARGE_M2 else "large"


def run_episode(spec: EpisodeSpec) -> dict[str, Any]:
    """Run one episode and return its CSV row."""
    truth = load_map(spec.map_path, MapConfig(resolution_m=spec.resolution_m))
    result = run_mission(
        truth,
        make_strategy(spec.strategy, GlobalPlanningConfig(commitment=spec.commitment)),
        SimConfig(robots=spec.robots),
        MissionConfig(max_steps=spec.max_steps),
        seed=spec.seed,
        progress=False,
    )
    sim = result.sim
    free_m2 = float((sim.explorable & ~truth.occupied).sum()) * truth.resolution_m**2
    return {
        "map": truth.name,
        "map_path": spec.map_path,
        "strategy": spec.strategy,
        "robots": spec.robots,
        "seed": spec.seed,
        "size_class": size_class(free_m2),
        "free_area_m2": round(free_m2, 2),
        **result.measures.to_dict(),
    }


def read_rows(path: Path) -> list[dict[str, str]]:
    """Rows of a results CSV (empty when the file does not exist)."""
    if not path.exists():
        return []
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def _done_keys(rows: Iterable[dict[str, str]]) -> set[tuple[str, str, int, int]]:
    return {(r["map_path"], r["strategy"], int(r["robots"]), int(r["seed"])) for r in rows}


def _append(path: Path, row: dict[str, Any]) -> None:
    new = not path.exists()
    with open(path, "a", newline="") as f:
        w = csv.DictWriter(f, fieldnames=COLUMNS)
        if new:
            w.writeheader()
        w.writerow({k: ("" if row[k] is None else row[k]) for k in COLUMNS})
        f.flush()
        os.fsync(f.fileno())


def run_bench(specs: Sequence[EpisodeSpec], results_csv: Path, workers: int = 0, progress: bool | None = None) -> int:
    """Run the episodes not yet in ``results_csv``, ``workers`` at a time (0: one per core).

    Returns the number of episodes run now. Each finished episode is appended (and flushed) at once.
    """
    for s in specs:
        make_strategy(s.strategy)  # unknown names fail before any work starts
    results_csv.parent.mkdir(parents=True, exist_ok=True)
    done = _done_keys(read_rows(results_csv))
    todo = [s for s in specs if s.key not in done]
    show = sys.stderr.isatty() if progress is None else progress
    bar = tqdm(total=len(specs), initial=len(specs) - len(todo), unit="ep", disable=not show)
    workers = workers or os.cpu_count() or 1
    if workers == 1:
        for s in todo:
            _append(results_csv, run_episode(s))
            bar.update()
    else:
        # Spawned, not forked: a parent that already ran a mission holds thread pools, and a forked
        # child inherits their locks in whatever state they were.
        with ProcessPoolExecutor(max_workers=workers, mp_context=multiprocessing.get_context("spawn")) as pool:
            pending: set[Future[dict[str, Any]]] = {pool.submit(run_episode, s) for s in todo}
            while pending:
                finished, pending = wait(pending, return_when=FIRST_COMPLETED)
                for fut in finished:
                    _append(results_csv, fut.result())
                    bar.update()
    bar.close()
    return len(todo)


def expand_maps(items: Sequence[str]) -> list[str]:
    """Map files from paths and folders (folders: every map file below, sorted; DungeonMaps' and KTH's
    room-label images ``*_spaces.png`` and images that have a YAML beside them are skipped)."""
    out: list[str] = []
    for item in items:
        if item.startswith("generated"):
            out.append(item)
            continue
        p = Path(item)
        if p.is_dir():
            for f in sorted(p.rglob("*")):
                if f.suffix.lower() not in MAP_SUFFIXES or f.stem.endswith("_spaces"):
                    continue
                if f.suffix.lower() in (".png", ".pgm") and f.with_suffix(".yaml").exists():
                    continue
                out.append(str(f))
        elif p.exists():
            out.append(str(p))
        else:
            raise MrExploreError(f"map not found: {item}; pass map files or folders with --maps")
    if not out:
        raise MrExploreError(f"no map files in {', '.join(items)}; pass map files or folders with --maps")
    return out


def _mean_std(values: list[float]) -> str:
    a = np.asarray(values, dtype=np.float64)
    return f"{a.mean():.1f} ± {a.std():.1f}" if len(a) else "–"


def steps_table(rows: list[dict[str, str]], strategies: Sequence[str]) -> str:
    """Markdown table: per size class and strategy, coverage % and steps mean ± std (Table I's layout)."""
    classes = [c for c in ("small", "middle", "large") if any(r["size_class"] == c for r in rows)]
    head = "| strategy | " + " | ".join(f"{c} cov. % | {c} steps" for c in classes) + " |"
    lines = [head, "|" + " --- |" * (1 + 2 * len(classes))]
    for s in strategies:
        cells = []
        for c in classes:
            sel = [r for r in rows if r["strategy"] == s and r["size_class"] == c]
            cov = [100 * float(r["coverage"]) for r in sel]
            cells += [f"{np.mean(cov):.2f}" if cov else "–", _mean_std([float(r["steps"]) for r in sel])]
        lines.append(f"| {s} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def per_map_table(rows: list[dict[str, str]], strategies: Sequence[str]) -> str:
    """Markdown table: steps (mean over seeds) and the lowest coverage per map and strategy."""
    maps = sorted(
        {(r["size_class"], r["map"]) for r in rows}, key=lambda t: (("small", "middle", "large").index(t[0]), t[1])
    )
    lines = ["| map | class | " + " | ".join(strategies) + " |", "|" + " --- |" * (2 + len(strategies))]
    for cls, m in maps:
        cells = []
        for s in strategies:
            sel = [r for r in rows if r["map"] == m and r["strategy"] == s]
            if not sel:
                cells.append("–")
                continue
            steps = np.mean([float(r["steps"]) for r in sel])
            cov = min(100 * float(r["coverage"]) for r in sel)
            cells.append(f"{steps:.0f} ({cov:.1f}%)")
        lines.append(f"| {m[:16]} | {cls} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def write_report(results_csv: Path, report_md: Path, strategies: Sequence[str], command: str) -> None:
    """Write the markdown report of a results CSV (the tables above, with the command that made it)."""
    rows = [r for r in read_rows(results_csv) if r["strategy"] in strategies]
    n_maps = len({r["map"] for r in rows})
    seeds = sorted({int(r["seed"]) for r in rows})
    text = "\n\n".join(
        [
            "# Benchmark report",
            f"Made by: `{command}`",
            f"{len(rows)} episodes: {n_maps} maps, strategies {', '.join(strategies)}, seeds {seeds}. "
            "Size classes by explorable free area: small < 100 m², middle 100-300 m², large > 300 m². "
            "Steps: mean ± std over maps and seeds; coverage: mean.",
            "## Coverage and steps by size class (Table I layout)",
            steps_table(rows, strategies),
            "## Steps per map (mean over seeds; lowest coverage in brackets)",
            per_map_table(rows, strategies),
            "## Ends",
            "\n".join(
                f"- {s}: " + ", ".join(f"{k} {v}" for k, v in sorted(_count(rows, s).items())) for s in strategies
            ),
        ]
    )
    report_md.write_text(text + "\n")


def _count(rows: list[dict[str, str]], strategy: str) -> dict[str, int]:
    out: dict[str, int] = {}
    for r in rows:
        if r["strategy"] == strategy:
            out[r["done_reason"]] = out.get(r["done_reason"], 0) + 1
    return out
