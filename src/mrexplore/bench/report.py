"""The benchmark report: Table I (coverage, steps), Table II (bytes sent), bounds, collaboration, plots."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from mrexplore.bench.runner import parse_curve, read_rows
from mrexplore.preprocessing.transmission import GRID_BASELINE_FIELDS

__all__ = [
    "write_report",
    "steps_of",
    "steps_table",
    "bytes_table",
    "bound_table",
    "collaboration_table",
    "per_map_table",
    "paired_table",
    "paired_bootstrap",
    "YARDSTICKS",
]

CLASSES = ("small", "middle", "large")
YARDSTICKS = frozenset({"oracle"})
"""Strategies that know the map: shown, but never the "best other strategy" of an improvement."""
Row = dict[str, str]


def _classes(rows: list[Row]) -> list[str]:
    return [c for c in CLASSES if any(r["size_class"] == c for r in rows)]


def _mean_std(values: list[float]) -> str:
    a = np.asarray(values, dtype=np.float64)
    return f"{a.mean():.1f} ± {a.std():.1f}" if len(a) else "–"


def _steps(rows: list[Row], strategy: str, cls: str, key: str = "size_class") -> list[float]:
    return [float(r["steps"]) for r in rows if r["strategy"] == strategy and _key(r, key) == cls]


def _key(row: Row, key: str) -> str:
    return f"{row['dataset']} {row['size_class']}" if key == "dataset" else row[key]


def steps_table(rows: list[Row], strategies: Sequence[str], key: str = "size_class") -> str:
    """Table I: per size class (``key="dataset"``: per dataset and size class) and strategy, coverage %,
    steps mean ± std with the number of episodes the step budget cut short, and the improvement in mean
    steps over the best other (non-yardstick) strategy, in % (positive: fewer steps)."""
    classes = [f"{d} {c}" for d, c in _groups(rows)] if key == "dataset" else _classes(rows)
    head = "| strategy | " + " | ".join(f"{c} cov. % | {c} steps | {c} impr. %" for c in classes) + " |"
    lines = [head, "|" + " --- |" * (1 + 3 * len(classes))]
    for s in strategies:
        cells = []
        for c in classes:
            sel = [r for r in rows if r["strategy"] == s and _key(r, key) == c]
            cov = [100 * float(r["coverage"]) for r in sel]
            others = [np.mean(_steps(rows, o, c, key)) for o in strategies if o != s and o not in YARDSTICKS]
            others = [v for v in others if np.isfinite(v)]
            mine = np.mean(_steps(rows, s, c, key)) if sel else np.nan
            cut = sum(r["done_reason"] == "max_steps" for r in sel)
            # Where the budget cut every episode, steps say nothing (coverage does).
            ok = others and sel and cut < len(sel)
            impr = f"{100 * (min(others) - mine) / min(others):+.1f}" if ok else "–"
            steps = _mean_std(_steps(rows, s, c, key)) + (f" ({cut} cut)" if cut else "")
            cells += [f"{np.mean(cov):.2f}" if cov else "–", steps, impr]
        lines.append(f"| {s} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


BOOTSTRAP_RESAMPLES = 2000
"""Resamples of the paired bootstrap (seeded, so a report is reproducible)."""


def paired_bootstrap(
    mine: Sequence[float], other: Sequence[float], resamples: int = BOOTSTRAP_RESAMPLES, seed: int = 0
) -> tuple[float, float, float]:
    """Fewer steps than ``other`` in % of its mean, paired episode by episode, with a 95% percentile
    bootstrap interval over the pairs: ``(estimate, low, high)``; positive means fewer steps.

    Examples
    --------
    >>> paired_bootstrap([90.0, 90.0], [100.0, 100.0])
    (10.0, 10.0, 10.0)
    """
    a, b = np.asarray(mine, dtype=np.float64), np.asarray(other, dtype=np.float64)
    if len(a) != len(b) or len(a) == 0:
        raise ValueError(f"paired_bootstrap needs two equal, non-empty samples, got {len(a)} and {len(b)}")
    est = 100.0 * (b.mean() - a.mean()) / b.mean()
    idx = np.random.default_rng(seed).integers(0, len(a), size=(resamples, len(a)))
    denom = b[idx].mean(1)
    # A resample of episodes that all ended at step 0 (a map seen whole by the first scan) has no %.
    boot = 100.0 * (b[idx].mean(1) - a[idx].mean(1))[denom > 0] / denom[denom > 0]
    lo, hi = np.percentile(boot, [2.5, 97.5]) if len(boot) else (np.nan, np.nan)
    return float(round(est, 6)), float(round(lo, 6)), float(round(hi, 6))


def steps_of(row: Row, metric: str) -> float:
    """An episode's steps by ``metric`` (``steps``, or ``steps_to_99``: steps until 99% coverage; an episode
    that never got there counts with all its steps)."""
    value = row.get(metric, "")
    return float(value) if value not in ("", "nan") else float(row["steps"])


def paired_table(
    rows: list[Row], focus: str, strategies: Sequence[str], key: str = "dataset", metric: str = "steps"
) -> str:
    """``focus`` against each other strategy on the same (map, robots, seed) episodes: fewer steps in %
    with its bootstrap 95% interval, and the mean coverage difference in points, per dataset and size class
    (``key="size_class"``: per size class). ``metric="steps_to_99"`` compares the steps to 99% coverage,
    equal coverage for both sides of every pair."""
    groups = [f"{d} {c}" for d, c in _groups(rows)] if key == "dataset" else _classes(rows)
    teams = sorted({int(r["robots"]) for r in rows})
    if len(teams) > 1:  # one block per team size: pairs never mix them, and neither should the means
        return "\n\n".join(
            f"{n} robots:\n\n"
            + paired_table([r for r in rows if int(r["robots"]) == n], focus, strategies, key, metric)
            for n in teams
        )
    others = [o for o in strategies if o != focus]
    lines = [
        "| group | " + " | ".join(f"vs {o}: fewer steps % [95% CI] | cov. diff pts | pairs" for o in others) + " |",
        "|" + " --- |" * (1 + 3 * len(others)),
    ]
    for g in groups:
        sel = [r for r in rows if _key(r, key) == g]
        by = {(r["map_path"], r["robots"], r["seed"], r["strategy"]): r for r in sel}
        mine = {k[:3]: r for k, r in by.items() if k[3] == focus}
        cells = []
        for o in others:
            pairs = [(mine[k], by[(*k, o)]) for k in sorted(mine) if (*k, o) in by]
            if not pairs:
                cells += ["–", "–", "0"]
                continue
            est, lo, hi = paired_bootstrap(
                [steps_of(a, metric) for a, _ in pairs], [steps_of(b, metric) for _, b in pairs]
            )
            cov = 100 * np.mean([float(a["coverage"]) - float(b["coverage"]) for a, b in pairs])
            interval = f"[{lo:+.1f}, {hi:+.1f}]" if len(pairs) > 1 else "(n = 1, no interval)"
            cells += [f"{est:+.1f} {interval}", f"{cov:+.2f}", str(len(pairs))]
        lines.append(f"| {g} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def _groups(rows: list[Row]) -> list[tuple[str, str]]:
    keys = {(r["dataset"], r["size_class"]) for r in rows}
    return sorted(keys, key=lambda k: (k[0], CLASSES.index(k[1]) if k[1] in CLASSES else 9))


def bytes_table(rows: list[Row]) -> str:
    """Table II: per dataset and size class, mean kB sent per episode by each encoding, the reduction
    against the raw grid, the sparse delta against its generic competitor (the grid's changed cells since
    the last acknowledged round, zlib), and the centre map's free-space IoU (lowest round, mean over
    rounds). '–' where a group's rows lack the grids: written before the delta was counted, or by a run
    that left the baselines out (``--no-baseline-bytes``: the grids and the other transmission mode's
    sparse maps)."""
    lines = [
        "| scene | episodes | grid kB | grid zlib kB | grid delta zlib kB | sparse kB | sparse delta kB | "
        "sparse vs grid | delta vs grid | delta vs zlib | delta vs grid delta zlib | IoU min | IoU mean |",
        "|" + " --- |" * 13,
    ]

    def mean_kb(sel: list[Row], key: str) -> float | None:
        known = [float(r[key]) for r in sel if r.get(key)]
        return float(np.mean(known)) / 1e3 if known and len(known) == len(sel) else None

    def kb_text(v: float | None) -> str:
        return "–" if v is None else f"{v:.1f}"

    def versus(part: float | None, whole: float | None) -> str:
        return "–" if whole is None or part is None else _reduction(part, whole)

    for dataset, cls in _groups(rows):
        sel = [r for r in rows if r["dataset"] == dataset and r["size_class"] == cls]
        sparse, delta = (mean_kb(sel, k) for k in _SPARSE)
        grid, grid_zlib, grid_delta = (mean_kb(sel, k) for k in GRID_BASELINE_FIELDS)
        iou_min = min(float(r["reconstruction_iou_min"]) for r in sel)
        iou_mean = np.mean([float(r["reconstruction_iou_mean"]) for r in sel])
        lines.append(
            f"| {dataset} {cls} | {len(sel)} | {kb_text(grid)} | {kb_text(grid_zlib)} | {kb_text(grid_delta)} | "
            f"{kb_text(sparse)} | {kb_text(delta)} | {versus(sparse, grid)} | {versus(delta, grid)} | "
            f"{versus(delta, grid_zlib)} | {versus(delta, grid_delta)} | {iou_min:.4f} | {iou_mean:.5f} |"
        )
    return "\n".join(lines)


_SPARSE = ("bytes_sparse", "bytes_sparse_delta")


def _reduction(part: float, whole: float) -> str:
    """How much smaller ``part`` is than ``whole`` (↓), or larger (↑)."""
    if whole <= 0:
        return "–"
    change = 100 * (1 - part / whole)
    return f"{change:.2f}% ↓" if change >= 0 else f"{-change:.2f}% ↑"


def bound_table(rows: list[Row], strategies: Sequence[str]) -> str:
    """Steps over ``lower_bound_steps`` (mean ratio per size class, episodes with a positive bound)."""
    classes = _classes(rows)
    lines = ["| strategy | " + " | ".join(classes) + " |", "|" + " --- |" * (1 + len(classes))]
    for s in strategies:
        cells = []
        for c in classes:
            ratios = [
                float(r["steps"]) / float(r["lower_bound_steps"])
                for r in rows
                if r["strategy"] == s and r["size_class"] == c and float(r["lower_bound_steps"]) > 0
            ]
            cells.append(f"{np.mean(ratios):.2f}×" if ratios else "–")
        lines.append(f"| {s} | " + " | ".join(cells) + " |")
    bounds = [float(r["lower_bound_steps"]) for r in rows]
    note = f"\n\nlower_bound_steps over episodes: mean {np.mean(bounds):.0f}, max {max(bounds):.0f}." if bounds else ""
    return "\n".join(lines) + note


def collaboration_table(rows: list[Row], strategies: Sequence[str]) -> str:
    """Per strategy: overlap (sum of robot coverages less team coverage), longest and total driven path,
    decisions, their mean time, the largest p95 of a robot's on-board work in a round and the largest peak
    memory of an episode (– in results from before they were recorded)."""
    lines = [
        "| strategy | overlap | longest path m | team path m | decisions | plan ms mean | on-board ms p95 (max) "
        "| peak MB (max) |",
        "|" + " --- |" * 8,
    ]
    for s in strategies:
        sel = [r for r in rows if r["strategy"] == s]
        if not sel:
            continue
        mean = {k: np.mean([float(r[k]) for r in sel]) for k in _COLLAB}
        peaks = [float(r["peak_mb"]) for r in sel if r.get("peak_mb") not in (None, "")]
        onboard = [float(r["onboard_ms_p95"]) for r in sel if r.get("onboard_ms_p95") not in (None, "")]
        lines.append(
            f"| {s} | {mean['overlap']:.2f} | {mean['path_len_max_m']:.1f} | {mean['path_len_sum_m']:.1f} | "
            f"{mean['decisions']:.0f} | {mean['plan_ms_mean']:.1f} | {f'{max(onboard):.1f}' if onboard else '–'} | "
            f"{f'{max(peaks):.0f}' if peaks else '–'} |"
        )
    return "\n".join(lines)


_COLLAB = ("overlap", "path_len_max_m", "path_len_sum_m", "decisions", "plan_ms_mean")


def per_map_table(rows: list[Row], strategies: Sequence[str]) -> str:
    """Steps (mean over seeds) and the lowest coverage per map and strategy."""
    maps = sorted(
        {(r["size_class"], r["dataset"], r["map"]) for r in rows},
        key=lambda t: (CLASSES.index(t[0]) if t[0] in CLASSES else 9, t[1], t[2]),
    )
    head = "| map | dataset | area class | bound | " + " | ".join(strategies) + " |"
    lines = [head, "|" + " --- |" * (4 + len(strategies))]
    for cls, dataset, m in maps:
        cells = []
        here = [r for r in rows if r["map"] == m and r["dataset"] == dataset]
        for s in strategies:
            sel = [r for r in here if r["strategy"] == s]
            if not sel:
                cells.append("–")
                continue
            steps = np.mean([float(r["steps"]) for r in sel])
            cov = min(100 * float(r["coverage"]) for r in sel)
            cells.append(f"{steps:.0f} ({cov:.1f}%)")
        bound = np.mean([float(r["lower_bound_steps"]) for r in here])
        lines.append(f"| {m[:16]} | {dataset} | {cls} | {bound:.0f} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def _count(rows: list[Row], strategy: str) -> dict[str, int]:
    out: dict[str, int] = {}
    for r in rows:
        if r["strategy"] == strategy:
            out[r["done_reason"]] = out.get(r["done_reason"], 0) + 1
    return out


def write_plots(rows: list[Row], strategies: Sequence[str], out_dir: Path) -> list[str]:
    """``coverage.png`` (mean coverage against steps per strategy, one panel per size class) and
    ``steps.png`` (mean steps per size class and strategy, std as error bars). Returns the file names
    written; none where matplotlib is missing."""
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return []
    classes = _classes(rows)
    if not classes:
        return []
    fig, axes = plt.subplots(1, len(classes), figsize=(4.5 * len(classes), 3.6), squeeze=False)
    for ax, c in zip(axes[0], classes, strict=True):
        for s in strategies:
            curves = [parse_curve(r["coverage_curve"]) for r in rows if r["strategy"] == s and r["size_class"] == c]
            if not curves:
                continue
            end = max(int(steps[-1]) for steps, _ in curves)
            grid = np.linspace(0, end, 200)
            # A finished episode keeps its final coverage until the longest one ends.
            mean = np.mean([np.interp(grid, steps, cov) for steps, cov in curves], axis=0)
            ax.plot(grid, 100 * mean, label=s)
        ax.set_title(f"{c} scenes")
        ax.set_xlabel("steps")
        ax.set_ylabel("coverage %")
        ax.grid(alpha=0.3)
    axes[0][0].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out_dir / "coverage.png", dpi=110)
    plt.close(fig)
    fig, ax = plt.subplots(figsize=(max(4.5, 1.6 + 1.4 * len(classes) * len(strategies) / 3), 3.6))
    width = 0.8 / max(1, len(strategies))
    for k, s in enumerate(strategies):
        per_class = [_steps(rows, s, c) or [0.0] for c in classes]
        means = [float(np.mean(v)) for v in per_class]
        stds = [float(np.std(v)) for v in per_class]
        ax.bar(np.arange(len(classes)) + k * width, means, width, yerr=stds, capsize=2, label=s)
    ax.set_xticks(np.arange(len(classes)) + width * (len(strategies) - 1) / 2, classes)
    ax.set_ylabel("steps (mean ± std)")
    ax.legend(fontsize=8)
    ax.grid(axis="y", alpha=0.3)
    fig.tight_layout()
    fig.savefig(out_dir / "steps.png", dpi=110)
    plt.close(fig)
    return ["coverage.png", "steps.png"]


def _focuses(strategies: Sequence[str]) -> list[str]:
    """Strategies whose paired differences against every other are reported: the first listed, and every
    learned one (hier, ncm, ncm-sampled, ncm-matched), so a table of NCM's variants holds each against the
    rest."""
    learned = ("hier", "ncm", "ncm-sampled", "ncm-matched")
    return [s for i, s in enumerate(strategies) if i == 0 or s.removesuffix("-nolocal") in learned]


def _paired_section(rows: list[Row], focus: str, strategies: Sequence[str]) -> list[str]:
    return [
        f"## Paired differences: {focus} against each other strategy",
        "The same map, team, seed and starts for every strategy; fewer steps in % of the other's mean "
        f"(positive: {focus} is faster), 95% percentile bootstrap interval over the pairs "
        f"({BOOTSTRAP_RESAMPLES} resamples); coverage difference in percentage points.",
        paired_table(rows, focus, strategies, key="dataset"),
        paired_table(rows, focus, strategies, key="size_class"),
        f"At equal coverage: {focus}'s steps to 99% coverage against the other's, as above (strategies end "
        "on slightly different coverage; an episode that never reached 99% counts with all its steps; the "
        "coverage difference is still the one at the episodes' ends).",
        paired_table(rows, focus, strategies, key="dataset", metric="steps_to_99"),
    ]


def write_report(results_csv: Path, report_md: Path, strategies: Sequence[str], command: str) -> None:
    """Write the markdown report of a results CSV, with plots beside it and the command that made it."""
    unique = {(r["map_path"], r["strategy"], r["robots"], r["seed"]): r for r in read_rows(results_csv)}
    rows = [r for r in unique.values() if r["strategy"] in strategies]
    n_maps = len({r["map_path"] for r in rows})
    seeds = sorted({int(r["seed"]) for r in rows})
    plots = write_plots(rows, strategies, report_md.parent)
    pictures = [f"![{p}]({p})" for p in plots] or ["(plots need matplotlib: pip install 'mrexplore[plot]')"]
    text = "\n\n".join(
        [
            "# Benchmark report",
            f"Made by: `{command}`",
            f"{len(rows)} episodes: {n_maps} maps, strategies {', '.join(strategies)}, seeds {seeds}. "
            "Size classes by explorable free area, not difficulty: small < 100 m², middle 100-300 m², large > 300 m² "
            "(DungeonMaps' easy, medium and complex maps are all large). "
            "Steps: mean ± std over maps and seeds; coverage: mean; improvement: against the best other "
            f"strategy's mean steps in the class (yardsticks {', '.join(sorted(YARDSTICKS))} excluded).",
            "## Table I: coverage and steps by size class",
            'An episode the step budget cut short ("cut") counts with the budget as its steps and the '
            "coverage it reached by then.",
            steps_table(rows, strategies),
            *pictures,
            "## Table I by dataset",
            steps_table(rows, strategies, key="dataset"),
            *(part for focus in _focuses(strategies) for part in _paired_section(rows, focus, strategies)),
            "## Table II: bytes sent per episode, robots to centre",
            "Grid: each robot's int8 occupancy grid over its known bounding box every round (the paper's "
            "baseline); sparse: the frontier maps of IV-A; delta: changes since the last acknowledged map. "
            "IoU: free space of the centre's rebuilt map against the union of the robots' own grids.",
            bytes_table(rows),
            "## Steps against lower_bound_steps",
            bound_table(rows, strategies),
            "## Collaboration",
            collaboration_table(rows, strategies),
            "## Steps per map (mean over seeds; lowest coverage in brackets)",
            per_map_table(rows, strategies),
            "## Ends",
            "\n".join(
                f"- {s}: " + ", ".join(f"{k} {v}" for k, v in sorted(_count(rows, s).items())) for s in strategies
            ),
        ]
    )
    report_md.write_text(text + "\n")
