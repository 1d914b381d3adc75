"""Run many (map, strategy, robots, seed) episodes in worker processes; one CSV row per finished episode.

Rows are appended as episodes finish, each with one write of a whole line, so a killed run loses only
the episodes in flight; a line cut short by a kill is dropped on the next run and its episode rerun.
Rerunning the same command skips every episode already in the file. An episode is known by its map
(resolved path), strategy, team size, seed, the hash of every other setting that changes a result (the
whole :class:`~mrexplore.config.RunConfig` but for training) and, for learned strategies, the policy's
sha256. A folder holds one set of settings (``settings.yaml``): a rerun with others is refused, naming
what differs. Workers exit with the run (:mod:`mrexplore.runtime.workers`).
"""

from __future__ import annotations

import csv
import functools
import hashlib
import json
import os
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np
import yaml
from PIL import Image

from mrexplore.config import RunConfig, TrainConfig, config_to_dict
from mrexplore.config.safe_yaml import load_yaml_file
from mrexplore.maps.loaders import is_generator_spec, load_map_shared
from mrexplore.mission import MissionSpec, run_mission
from mrexplore.pipeline import make_strategy, policy_for, strategy_for_run, strategy_spec
from mrexplore.runtime.csv_append import append_row, drop_partial_tail
from mrexplore.runtime.progress import Progress
from mrexplore.runtime.threads import THREADS_ENV
from mrexplore.runtime.workers import JobRunner
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
    "settings_hash",
    "drop_partial_tail",
    "COLUMNS",
    "MAP_SUFFIXES",
]

MAP_SUFFIXES = (".yaml", ".yml", ".png", ".pgm", ".json")
SMALL_M2 = 100.0
LARGE_M2 = 300.0
CURVE_EVERY_STEPS = 50
"""The coverage curve is kept in the CSV every this many steps (and at the last step)."""
COLUMNS = [
    "map", "map_path", "map_resolved", "settings", "policy_sha256", "dataset", "strategy", "robots", "seed",
    "size_class", "free_area_m2",
    "steps", "coverage", "steps_to_90", "steps_to_95", "steps_to_99", "lower_bound_steps",
    "path_len_max_m", "path_len_sum_m", "overlap", "decisions", "plan_ms_mean", "plan_ms_p95", "wall_s",
    "peak_mb", "onboard_ms_median", "onboard_ms_p95", "done_reason", "rounds", "bytes_grid", "bytes_grid_zlib",
    "bytes_grid_delta_zlib", "bytes_sparse",
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
    run: RunConfig = field(default_factory=RunConfig)
    """Every setting but the team size (``robots`` overrides ``run.sim.robots``); ``run.train`` is unused."""
    policy: str | None = None
    """Weights of a learned strategy (None: the shipped policy)."""
    predictor: str | None = None
    """Map predictor of a predictive strategy (a file, ``none``; None: the shipped one)."""

    @property
    def map_resolved(self) -> str:
        """The map as the resume key knows it: the real path of a file, the spec of a generated map."""
        return self.map_path if is_generator_spec(self.map_path) else os.path.realpath(self.map_path)

    @property
    def settings(self) -> str:
        """Hash of every setting that changes a result, apart from map, strategy, team size and seed."""
        return settings_hash(self.run)

    @property
    def policy_sha256(self) -> str:
        """sha256 of the weights a strategy runs: a learned strategy's policy, a predictive one's map predictor
        (``none`` where it runs without one), both joined by ``+`` where it reads both; '' for the others."""
        spec = strategy_spec(self.strategy)
        kind = spec.policy_kind
        if kind is None:
            return _predictor_sha(self.predictor) if spec.predictive else ""
        policy = policy_for(self.strategy, self.policy)
        sha = _policy_sha(kind, policy)
        if spec.predictive or _reads_prediction(kind, policy):  # the predictor is part of it
            sha += "+" + _predictor_sha(self.predictor)
        return sha

    @property
    def key(self) -> tuple[str, str, int, int, str, str]:
        return (self.map_resolved, self.strategy, self.robots, self.seed, self.settings, self.policy_sha256)


@functools.lru_cache(maxsize=16)
def _policy_sha(kind: str, policy: str | None) -> str:
    from mrexplore.global_planning.learned.methods import learned_method
    from mrexplore.global_planning.learned.policy_file import file_sha256

    path = Path(policy) if policy else learned_method(kind).default_weights()
    return file_sha256(path) if path.is_file() else ""


@functools.lru_cache(maxsize=16)
def _reads_prediction(kind: str, policy: str | None) -> bool:
    """Whether a learned method's policy file reads a prediction (False where it cannot be read: the bench's
    start refuses it then)."""
    from mrexplore.global_planning.learned.methods import learned_method

    return learned_method(kind).file_reads_prediction(Path(policy) if policy else None)


@functools.lru_cache(maxsize=16)
def _predictor_sha(predictor: str | None) -> str:
    from mrexplore.pipeline.registry import NO_PREDICTOR
    from mrexplore.prediction.network import default_predictor_path
    from mrexplore.runtime.weights_archive import file_sha256

    if predictor == NO_PREDICTOR:
        return NO_PREDICTOR
    path = Path(predictor) if predictor else default_predictor_path()
    return file_sha256(path) if path.is_file() else ""


_ADDED_LATER: tuple[tuple[str, str, object], ...] = (
    ("preprocess", "bandwidth_max_m", None),
    ("mission", "baseline_bytes", True),
    ("global_planning", "plan_service_weight", 0.0),  # the team plan's settings change no other strategy
    ("global_planning", "plan_sum_weight", 0.0),
    ("global_planning", "plan_weight", 0.3),
    ("global_planning", "search_horizon_steps", 400),
)
"""Settings added after benches were kept, as (section, key, value): at that value, which gives the results
of before, a setting is left out of the hash, so those benches' rows keep theirs."""


def _settings_dict(run: RunConfig) -> dict[str, Any]:
    d = config_to_dict(replace(run, train=TrainConfig()))
    del d["train"]
    del d["runtime"]  # how the process runs, never what it finds
    del d["sim"]["robots"]  # a column of its own
    # The predictor's training settings were one flat section before their episodes had a section of their
    # own; flat again (the hash sorts keys), so that benches kept before keep their hashes.
    d["predictor"].update(d["predictor"].pop("episodes"))
    for section, key, before in _ADDED_LATER:
        if d[section].get(key, before) == before:
            d[section].pop(key, None)
    return d


def settings_hash(run: RunConfig) -> str:
    """16 hex digits of the sha256 of a run's result-changing settings (see :class:`EpisodeSpec`)."""
    text = json.dumps(_settings_dict(run), sort_keys=True, default=list)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def size_class(free_area_m2: float) -> str:
    """small < 100 m^2 <= middle <= 300 m^2 < large, by explorable free area."""
    if free_area_m2 < SMALL_M2:
        return "small"
    return "middle" if free_area_m2 <= LARGE_M2 else "large"


def dataset_of(map_path: str) -> str:
    """The collection a map comes from, by a folder name on its path (``generated`` for procedural plans)."""
    if map_path.startswith(("generated", "varied:")):
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


def run_episode(spec: EpisodeSpec) -> dict[str, Any]:
    """Run one episode and return its CSV row."""
    run = spec.run
    truth = load_map_shared(spec.map_path, run.map)
    strategy = strategy_for_run(spec.strategy, run, policy=spec.policy, predictor=spec.predictor)
    result = run_mission(
        MissionSpec(truth, strategy, replace(run.sim, robots=spec.robots), run.mission, seed=spec.seed), progress=False
    )
    sim = result.sim
    free_m2 = float((sim.explorable & ~truth.occupied).sum()) * truth.resolution_m**2
    return {
        "map": truth.name,
        "map_path": spec.map_path,
        "map_resolved": spec.map_resolved,
        "settings": spec.settings,
        "policy_sha256": spec.policy_sha256,
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


def _row_key(r: dict[str, str]) -> tuple[str, str, int, int, str, str]:
    return (r["map_resolved"], r["strategy"], int(r["robots"]), int(r["seed"]), r["settings"], r["policy_sha256"])


def _check_columns(path: Path) -> None:
    if not path.exists() or path.stat().st_size == 0:
        return
    with open(path, newline="") as f:
        header = next(csv.reader(f), None)
    if header is not None and header != COLUMNS:
        raise MrExploreError(
            f"{path} has other columns than this version writes; pass a new --out folder to start afresh"
        )


def _check_settings(folder: Path, specs: Sequence[EpisodeSpec], rows: list[dict[str, str]]) -> None:
    """One folder, one set of settings: refuse others, naming the fields that differ; write settings.yaml."""
    wanted = {s.settings for s in specs}
    if len(wanted) > 1:
        raise MrExploreError("one bench run must use one set of settings; split it into several --out folders")
    mine = next(iter(wanted))
    saved = folder / "settings.yaml"
    current = _plain(_settings_dict(specs[0].run))
    if any(r["settings"] != mine for r in rows):
        before = load_yaml_file(saved, f"{saved}") if saved.exists() else None
        differ = ", ".join(_diff(before, current)) if isinstance(before, dict) else "see settings.yaml"
        raise MrExploreError(
            f"{folder} holds episodes run with other settings ({differ}); pass a new --out folder, "
            "or rerun with the same settings"
        )
    policies: dict[str, set[str]] = {}
    for r in rows:
        policies.setdefault(r["strategy"], set()).add(r["policy_sha256"])
    for s in specs:
        old = policies.get(s.strategy, set()) - {s.policy_sha256}
        if old:
            raise MrExploreError(
                f"{folder} holds {s.strategy} episodes run with another policy (sha256 {sorted(old)[0][:12]}...); "
                "pass a new --out folder, or the same --policy"
            )
    if not saved.exists():
        tmp = saved.with_name(saved.name + ".tmp")
        tmp.write_text(f"# settings of every episode in this folder (hash {mine})\n" + yaml.safe_dump(current))
        tmp.replace(saved)


def _diff(a: Any, b: Any, where: str = "") -> list[str]:
    """Dotted names of the fields where two settings dicts differ."""
    if isinstance(a, dict) and isinstance(b, dict):
        out: list[str] = []
        for k in sorted(set(a) | set(b), key=str):
            out += _diff(a.get(k), b.get(k), f"{where}{k}.")
        return out
    return [] if a == b else [f"{where.rstrip('.')} {a!r} there, {b!r} now"]


def _plain(value: Any) -> Any:
    """Settings as YAML gives them back: tuples as lists, nested."""
    if isinstance(value, dict):
        return {k: _plain(v) for k, v in value.items()}
    if isinstance(value, tuple | list):
        return [_plain(v) for v in value]
    return value


def run_bench(
    specs: Sequence[EpisodeSpec],
    results_csv: Path,
    workers: int = 0,
    progress: bool | None = None,
    ray_address: str | None = None,
    episode: Callable[[EpisodeSpec], dict[str, Any]] | None = None,
) -> int:
    """Run the episodes not yet in ``results_csv``, ``workers`` at a time (0: one per core), in local
    worker processes, or as Ray tasks when ``ray_address`` is given (``local`` starts a Ray instance on
    this machine; ``auto`` or ``HOST:PORT`` joins a running cluster). ``episode`` runs one (default
    :func:`run_episode`; a module-level function, so that workers can import it).

    Returns the number of episodes run now. Each finished episode is appended (and synced) at once.
    """
    if not specs:
        return 0
    for name, policy, predictor in {(s.strategy, s.policy, s.predictor) for s in specs}:
        make_strategy(name, policy=policy, predictor=predictor)  # unknown names, unreadable files: fail before work
    results_csv.parent.mkdir(parents=True, exist_ok=True)
    _check_columns(results_csv)
    drop_partial_tail(results_csv)
    rows = read_rows(results_csv)
    _check_settings(results_csv.parent, specs, rows)
    done = {_row_key(r) for r in rows}
    todo = list({s.key: s for s in specs if s.key not in done}.values())  # a spec given twice runs once
    # Largest maps first, so that no long episode starts last and leaves the other workers idle.
    todo.sort(key=lambda s: -_area_hint(s.map_path))
    total = len({s.key for s in specs})
    bar = Progress(total, "bench", "episodes", progress, initial=total - len(todo))
    workers = workers or os.cpu_count() or 1
    # Episodes already fill the cores: each local worker's kernels run on as many threads as are left over;
    # a Ray task has one CPU, so its kernels run on one thread.
    threads = max(1, (os.cpu_count() or 1) // workers)
    runner = JobRunner(episode or run_episode, workers, ray_address, _set_threads, (threads,), {THREADS_ENV: "1"})
    with runner:
        for row in runner.run(todo):
            append_row(results_csv, COLUMNS, row)
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


def expand_maps(items: Sequence[str]) -> list[str]:
    """Map files from paths, ``example:NAME`` and folders (folders: every map file below, sorted; DungeonMaps' and KTH's
    room-label images ``*_spaces.png`` and images that have a YAML beside them are skipped)."""
    out: list[str] = []
    for item in items:
        if is_generator_spec(item):
            out.append(item)
            continue
        if item.startswith("example:") and not Path(item).exists():  # a map shipped with the package
            from mrexplore.maps.datasets import example_path

            out.append(str(example_path(item.removeprefix("example:"))))
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
