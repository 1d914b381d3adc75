"""Run many (map, strategy, robots, seed) episodes in worker processes; one CSV row per finished episode.

Rows are appended as episodes finish, so a killed run loses only the episodes in flight; rerunning the
same command skips every episode already in the file.
"""

from __future__ import annotations

import csv
import functools
import multiprocessing
import os
import sys
from collections.abc import Iterable, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import yaml
from PIL import Image
from tqdm import tqdm

from mrexplore.config import GlobalPlanningConfig, MapConfig, MissionConfig, SimConfig
from mrexplore.maps.ground_truth import GroundTruthMap
from mrexplore.maps.loaders import load_map
from mrexplore.mission import run_mission
from mrexplore.strategies import make_strategy
from mrexplore.threads import THREADS_ENV
from mrexplore.types import MrExploreError

__all__ = [
    "EpisodeSpec",
    "run_episode",
    "run_bench",
    "read_rows",
    "size_class",
    "dataset_of",
    "parse_curve",
    "expand_maps",
    "COLUMNS",
    "MAP_SUFFIXES",
]

MAP_SUFFIXES = (".yaml", ".yml", ".png", ".pgm", ".json")
SMALL_M2 = 100.0
LARGE_M2 = 300.0
CURVE_EVERY_STEPS = 50
"""The coverage curve is kept in the CSV every this many steps (and at the last step)."""
COLUMNS = [
    "map", "map_path", "dataset", "strategy", "robots", "seed", "size_class", "free_area_m2",
    "steps", "coverage", "steps_to_90", "steps_to_95", "steps_to_99", "lower_bound_steps",
    "path_len_max_m", "path_len_sum_m", "overlap", "decisions", "plan_ms_mean", "plan_ms_p95", "wall_s",
    "done_reason", "rounds", "bytes_grid", "bytes_grid_zlib", "bytes_grid_delta_zlib", "bytes_sparse",
    "bytes_sparse_delta", "reconstruction_iou_min", "reconstruction_iou_mean", "messages_sent", "messages_lost",
    "messages_resent", "acks_lost", "bytes_lost", "bytes_resent", "centre_restarts", "robots_failed",
    "coverage_curve",
]  # fmt: skip
_DATASETS = ("houseexpo", "kth", "ros", "dungeon")


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
    min_replan_steps: int = MissionConfig.min_replan_steps
    policy: str | None = None
    """Weights of a learned strategy (None: the shipped policy)."""

    @property
    def key(self) -> tuple[str, str, int, int]:
        return (self.map_path, self.strategy, self.robots, self.seed)


def size_class(free_area_m2: float) -> str:
    """small < 100 m^2 <= middle <= 300 m^2 < large, by explorable free area."""
    if free_area_m2 < SMALL_M2:
        return "small"
    return "middle" if free_area_m2 <= LARGE_M2 else "large"


def dataset_of(map_path: str) -> str:
    """The collection a map comes from, by a folder name on its path (``generated`` for built-in maps)."""
    if map_path.startswith("generated"):
        return "generated"
    parts = [p.lower() for p in Path(map_path).parts[:-1]]
    for name in _DATASETS:
        if any(p.startswith(name) for p in parts):
            return name
    return Path(map_path).parent.name or "other"


def _curve_text(curve: np.ndarray) -> str:
    idx = list(range(0, len(curve), CURVE_EVERY_STEPS))
    if idx[-1] != len(curve) - 1:
        idx.append(len(curve) - 1)
    return " ".join(f"{i}:{curve[i]:.4f}" for i in idx)


def parse_curve(text: str) -> tuple[np.ndarray, np.ndarray]:
    """``(steps, coverage)`` arrays of a row's ``coverage_curve`` field."""
    pairs = [item.split(":") for item in text.split()]
    return np.array([int(a) for a, _ in pairs]), np.array([float(b) for _, b in pairs])


@functools.lru_cache(maxsize=2)
def _load_shared(map_path: str, resolution_m: float) -> GroundTruthMap:
    """A worker runs the episodes of one map one after another: load it once (read-only, as missions
    never write the ground truth)."""
    truth = load_map(map_path, MapConfig(resolution_m=resolution_m))
    truth.occupied.flags.writeable = False
    return truth


def run_episode(spec: EpisodeSpec) -> dict[str, Any]:
    """Run one episode and return its CSV row."""
    truth = _load_shared(spec.map_path, spec.resolution_m)
    result = run_mission(
        truth,
        make_strategy(spec.strategy, GlobalPlanningConfig(commitment=spec.commitment), policy=spec.policy),
        SimConfig(robots=spec.robots),
        MissionConfig(max_steps=spec.max_steps, min_replan_steps=spec.min_replan_steps),
        seed=spec.seed,
        progress=False,
    )
    sim = result.sim
    free_m2 = float((sim.explorable & ~truth.occupied).sum()) * truth.resolution_m**2
    return {
        "map": truth.name,
        "map_path": spec.map_path,
        "dataset": dataset_of(spec.map_path),
        "strategy": spec.strategy,
        "robots": spec.robots,
        "seed": spec.seed,
        "size_class": size_class(free_m2),
        "free_area_m2": round(free_m2, 2),
        **result.measures.to_dict(),
        "coverage_curve": _curve_text(result.coverage_curve),
    }


def read_rows(path: Path) -> list[dict[str, str]]:
    """Rows of a results CSV (empty when the file does not exist)."""
    if not path.exists():
        return []
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def _done_keys(rows: Iterable[dict[str, str]]) -> set[tuple[str, str, int, int]]:
    return {(r["map_path"], r["strategy"], int(r["robots"]), int(r["seed"])) for r in rows}


def _check_columns(path: Path) -> None:
    if not path.exists():
        return
    with open(path, newline="") as f:
        header = next(csv.reader(f), None)
    if header is not None and header != COLUMNS:
        raise MrExploreError(
            f"{path} has other columns than this version writes; pass a new --out folder to start afresh"
        )


def _append(path: Path, row: dict[str, Any]) -> None:
    new = not path.exists()
    with open(path, "a", newline="") as f:
        w = csv.DictWriter(f, fieldnames=COLUMNS)
        if new:
            w.writeheader()
        w.writerow({k: ("" if row[k] is None else row[k]) for k in COLUMNS})
        f.flush()
        os.fsync(f.fileno())


def run_bench(
    specs: Sequence[EpisodeSpec],
    results_csv: Path,
    workers: int = 0,
    progress: bool | None = None,
    ray_address: str | None = None,
) -> int:
    """Run the episodes not yet in ``results_csv``, ``workers`` at a time (0: one per core), in local
    worker processes, or as Ray tasks when ``ray_address`` is given (``local`` starts a Ray instance on
    this machine; ``auto`` or ``HOST:PORT`` joins a running cluster).

    Returns the number of episodes run now. Each finished episode is appended (and flushed) at once.
    """
    for name, policy in {(s.strategy, s.policy) for s in specs}:
        make_strategy(name, policy=policy)  # unknown names and unreadable policies fail before any work starts
    results_csv.parent.mkdir(parents=True, exist_ok=True)
    _check_columns(results_csv)
    done = _done_keys(read_rows(results_csv))
    todo = list({s.key: s for s in specs if s.key not in done}.values())  # a spec given twice runs once
    # Largest maps first, so that no long episode starts last and leaves the other workers idle.
    todo.sort(key=lambda s: -_area_hint(s.map_path))
    show = sys.stderr.isatty() if progress is None else progress
    total = len({s.key for s in specs})
    bar = tqdm(total=total, initial=total - len(todo), unit="ep", disable=not show)
    workers = workers or os.cpu_count() or 1
    if ray_address is not None:
        _run_ray(todo, results_csv, workers, ray_address, bar)
    elif workers == 1:
        for s in todo:
            _append(results_csv, run_episode(s))
            bar.update()
    else:
        # Spawned, not forked: a parent that already ran a mission holds thread pools, and a forked
        # child inherits their locks in whatever state they were.
        # Episodes already fill the cores: each worker's kernels run on as many threads as are left over.
        threads = max(1, (os.cpu_count() or 1) // workers)
        with ProcessPoolExecutor(
            max_workers=workers,
            mp_context=multiprocessing.get_context("spawn"),
            initializer=_set_threads,
            initargs=(threads,),
        ) as pool:
            pending: set[Future[dict[str, Any]]] = {pool.submit(run_episode, s) for s in todo}
            while pending:
                finished, pending = wait(pending, return_when=FIRST_COMPLETED)
                for fut in finished:
                    _append(results_csv, fut.result())
                    bar.update()
    bar.close()
    return len(todo)


def _area_hint(map_path: str) -> float:
    """Square metres a map's image covers, read from its header alone (0 when unknown): a cheap proxy
    for an episode's length."""
    p = Path(map_path)
    try:
        if p.suffix.lower() in (".yaml", ".yml"):
            meta = yaml.safe_load(p.read_text())
            with Image.open(p.parent / str(meta["image"])) as img:
                return float(img.width * img.height) * float(meta["resolution"]) ** 2
        if p.suffix.lower() in (".png", ".pgm"):
            pixel_m = 0.01 if dataset_of(map_path) == "houseexpo" else 0.1  # the loader's defaults
            with Image.open(p) as img:
                return float(img.width * img.height) * pixel_m**2
    except (OSError, KeyError, TypeError, ValueError, yaml.YAMLError):
        pass
    return 0.0


def _set_threads(threads: int) -> None:
    os.environ[THREADS_ENV] = str(threads)


def _run_ray(todo: list[EpisodeSpec], results_csv: Path, workers: int, address: str, bar: tqdm) -> None:
    try:
        import ray
    except ImportError:
        raise MrExploreError("--ray-address needs Ray; install it with: pip install 'mrexplore[ray]'") from None
    started = not ray.is_initialized()
    if started:
        kwargs: dict[str, Any] = {"num_cpus": workers} if address == "local" else {"address": address}
        ray.init(include_dashboard=False, log_to_driver=False, **kwargs)
    try:
        # One CPU per task: the task's kernels run on one thread.
        remote = ray.remote(num_cpus=1, runtime_env={"env_vars": {THREADS_ENV: "1"}})(run_episode)
        pending = [remote.remote(s) for s in todo]
        while pending:
            finished, pending = ray.wait(pending, num_returns=1)
            for ref in finished:
                _append(results_csv, ray.get(ref))
                bar.update()
    finally:
        if started:
            ray.shutdown()


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
    return list(dict.fromkeys(out))  # a map named twice (a file and its folder, overlapping globs) runs once
