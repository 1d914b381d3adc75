"""Comparisons over benches already run (``mrexplore report``): one strategy across separate benches,
paired episode by episode (policies, settings); the steps a larger team needs against a smaller one; and
how long a whole table would take, projected from episodes already timed."""

from __future__ import annotations

import csv
import statistics
from collections import defaultdict
from collections.abc import Sequence
from pathlib import Path

from mrexplore.bench.report import paired_bootstrap, paired_table, steps_of, steps_table
from mrexplore.bench.runner import read_rows
from mrexplore.pipeline.registry import TABLE_I
from mrexplore.types import MrExploreError

__all__ = ["compare_runs", "team_ratio", "table_time", "TABLE_I"]


_NOT_RESULTS = frozenset(
    {"plan_ms_mean", "plan_ms_p95", "wall_s", "peak_mb", "onboard_ms_median", "onboard_ms_p95"}  # timings
    | {"strategy", "settings", "policy_sha256", "map_path", "map_resolved"}  # which run it is
)
"""Columns left out when asking whether two runs of an episode are the same mission."""

Row = dict[str, str]


def _episode(row: Row) -> tuple[str, str, str]:
    return row["map_path"], row["robots"], row["seed"]


def _rows(folder: Path) -> list[Row]:
    rows = read_rows(folder / "results.csv")
    if not rows:
        raise MrExploreError(f"{folder}: no results.csv with rows; give folders that 'mrexplore bench --out' wrote")
    return rows


def _same_missions(rows: list[Row], labels: list[str]) -> str:
    """Per other run: the episodes it shares with the reference, how many differ in any result (every
    column but timings and the run's identity), and the planning time of the shared episodes summed
    (``plan_ms_mean`` x ``decisions``; a timing, so it moves with the machine too)."""
    by = {label: {_episode(r): r for r in rows if r["strategy"] == label} for label in labels}
    ref = by[labels[0]]

    def planning_s(r: Row) -> float:
        return float(r["plan_ms_mean"]) * int(r["decisions"]) / 1e3

    lines = [
        f"| run | shared episodes | results differ | planning s, {labels[0]} → run |",
        "| --- | --- | --- | --- |",
    ]
    for label in labels[1:]:
        shared = [e for e in by[label] if e in ref]
        differ = sum(any(ref[e][c] != by[label][e].get(c) for c in ref[e] if c not in _NOT_RESULTS) for e in shared)
        before = sum(planning_s(ref[e]) for e in shared)
        after = sum(planning_s(by[label][e]) for e in shared)
        lines.append(f"| {label} | {len(shared)} | {differ} | {before:,.0f} → {after:,.0f} |")
    return "\n".join(lines)


def _kept(train_dir: Path) -> tuple[str, str, str]:
    """The stage with the fewest validation steps (the trainer keeps it), its steps and the untrained
    baseline's."""
    path = train_dir / "stages.csv"
    if not path.is_file():
        raise MrExploreError(f"{path} not found; --train takes folders that 'mrexplore train --out' wrote")
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    best = min(rows, key=lambda r: float(r["val_steps_mean"]))
    base = next(r for r in rows if r["stage"] == "baseline")
    return best["stage"], f"{float(best['val_steps_mean']):.1f}", f"{float(base['val_steps_mean']):.1f}"


def compare_runs(runs: dict[str, str], strategy: str, trains: dict[str, Path], common: bool, command: str) -> str:
    """One strategy run by separate benches on the same episodes, as markdown.

    ``runs``: label -> bench folder, ``FOLDER@STRATEGY`` for another strategy's rows under that label (a
    yardstick); the first label is the reference that the paired differences hold against every other,
    episode by episode. ``trains``: label -> the ``mrexplore train`` folder that made the label's policy
    (its kept stage and validation steps). ``common``: only the episodes every run holds.
    """
    rows: list[Row] = []
    for label, where in runs.items():
        folder, _, own = where.partition("@")
        mine = [r for r in _rows(Path(folder)) if r["strategy"] == (own or strategy)]
        if not mine:
            raise MrExploreError(f"{folder} holds no {own or strategy} rows; bench that strategy")
        if len({r["policy_sha256"] for r in mine}) != 1:
            raise MrExploreError(f"{folder} mixes several policies; give each policy its own bench folder")
        rows += {_episode(r): dict(r, strategy=label) for r in mine}.values()
    labels = list(runs)
    if common:
        shared = set.intersection(*({_episode(r) for r in rows if r["strategy"] == label} for label in labels))
        if not shared:
            raise MrExploreError("the runs share no episode (map, robots, seed); bench the same maps")
        rows = [r for r in rows if _episode(r) in shared]
    parts = [f"# {strategy}: separate benches compared", f"Made by: `{command}`"]
    if trains:
        lines = ["| policy | kept stage | validation steps | untrained | sha256 |", "| --- | --- | --- | --- | --- |"]
        for label, train_dir in trains.items():
            stage, steps, base = _kept(train_dir)
            sha = next((r["policy_sha256"] for r in rows if r["strategy"] == label), "")[:12]
            lines.append(f"| {label} | {stage} | {steps} | {base} | {sha} |")
        parts += ["## Training (validation maps)", "\n".join(lines)]
    parts += [
        "## Steps by dataset (mean ± std)",
        steps_table(rows, labels, key="dataset"),
        f"## Paired: {labels[0]} against each other run (fewer steps %, 95% bootstrap interval)",
        paired_table(rows, labels[0], labels, key="dataset"),
        "At equal coverage (steps to 99%):",
        paired_table(rows, labels[0], labels, key="dataset", metric="steps_to_99"),
        f"## The same missions? Each run against {labels[0]}, episode by episode",
        _same_missions(rows, labels),
    ]
    return "\n\n".join(parts) + "\n"


def team_ratio(folders: Sequence[Path], small: int, large: int, strategy: str) -> str:
    """How many of a small team's steps a larger team needs, to 99% coverage and at the end, with a 95%
    paired bootstrap interval over the (map, seed) pairs, as markdown. A later folder's episode replaces an
    earlier one's. The same map and seed start the first robot on the same cell and the others within the
    same spread of it."""
    if large <= small:
        raise MrExploreError(f"--large must be more robots than --small, got {large} and {small}")
    episodes: dict[tuple[str, int, str], Row] = {}
    for folder in folders:
        for r in _rows(folder):
            if r["strategy"] == strategy:
                episodes[r["map"], int(r["robots"]), r["seed"]] = r
    pairs = sorted((m, s) for (m, n, s) in episodes if n == small and (m, large, s) in episodes)
    if not pairs:
        raise MrExploreError(
            f"no map and seed with both {small} and {large} robots of {strategy!r}: "
            f"run 'mrexplore bench --robots {small},{large}'"
        )
    lines = [
        f"{strategy}, {large} robots against {small}, {len(pairs)} pairs (map, seed)",
        "",
        f"| metric | mean steps, {small} | mean steps, {large} | ratio [95% CI] | per pair |",
        "| --- | --- | --- | --- | --- |",
    ]
    for metric, label in (("steps_to_99", "to 99%"), ("steps", "at the end")):
        a = [steps_of(episodes[m, small, s], metric) for m, s in pairs]
        b = [steps_of(episodes[m, large, s], metric) for m, s in pairs]
        est, lo, hi = paired_bootstrap(b, a)
        # paired_bootstrap gives % fewer steps than the small team; the ratio is 1 - that / 100.
        per = ", ".join(f"{y / x:.2f}" for x, y in zip(a, b, strict=True))
        interval = f"[{1 - hi / 100:.3f}, {1 - lo / 100:.3f}]" if len(pairs) > 1 else "(n = 1, no interval)"
        lines.append(
            f"| {label} | {sum(a) / len(a):,.1f} | {sum(b) / len(b):,.1f} | {1 - est / 100:.3f} {interval} | {per} |"
        )
    return "\n".join(lines) + "\n"


def table_time(folders: Sequence[Path], seeds: int, workers: int, strategies: Sequence[str]) -> str:
    """How long a whole bench table would take, projected from the episodes of ``folders`` (a later
    folder's episode replaces an earlier one's): each (map, strategy)'s mean episode wall time times
    ``seeds``, summed, over ``workers``. It assumes busy workers and a machine as fast as when the rows were
    made; (map, strategy) pairs no folder holds are listed, and the projection is then a lower bound."""
    episodes: dict[tuple[str, str, str, str], float] = {}
    for folder in folders:
        for r in _rows(folder):
            if r["strategy"] in strategies:
                episodes[(r["map"], r["strategy"], r["robots"], r["seed"])] = float(r["wall_s"])
    walls: dict[tuple[str, str], list[float]] = defaultdict(list)
    for (m, s, _, _), w in episodes.items():
        walls[(m, s)].append(w)
    maps = sorted({m for m, _ in walls})
    per_strategy: dict[str, float] = defaultdict(float)
    measured: dict[str, int] = defaultdict(int)
    for (_m, s), ws in walls.items():
        per_strategy[s] += statistics.mean(ws) * seeds
        measured[s] += len(ws)
    total = sum(per_strategy.values())
    lines = [
        f"{len(maps)} maps, {len(episodes)} episodes measured; projected for {seeds} seeds on {workers} workers",
        "",
        "| strategy | episodes measured | worker-minutes projected | share |",
        "| --- | --- | --- | --- |",
    ]
    lines += [
        f"| {s} | {measured[s]} | {per_strategy[s] / 60:.1f} | {per_strategy[s] / total:.0%} |"
        for s in strategies
        if measured[s]
    ]
    lines += ["", f"projected: {total / workers / 60:.1f} minutes"]
    # Only what the folders ran: a strategy no folder holds is named once, not listed map by map.
    missing = [f"{m} {s}" for m in maps for s in strategies if measured[s] and (m, s) not in walls]
    if missing:
        lines.append(f"not measured (left out, so a lower bound): {', '.join(missing)}")
    absent = [s for s in strategies if not measured[s]]
    if absent:
        lines.append(f"no episode of {', '.join(absent)} in these folders: left out of the projection")
    return "\n".join(lines) + "\n"
