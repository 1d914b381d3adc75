"""One strategy against others team size by team size, from a bench folder: paired differences in steps
(at the episodes' end and to 99% coverage) by team size and dataset class, as a table (``by_team.md``) and a
figure (``by_team.png``), with every pair whose interval lies wholly on the losing side marked.

Run: python benchmarks/team_sizes.py --runs DIR [--focus hier] [--against hier-heuristic,utility] [--out DIR]
``DIR`` holds a ``mrexplore bench`` run's ``results.csv`` with several ``--robots``; ``--out`` defaults to it.
"""

from __future__ import annotations

import argparse
from collections import defaultdict
from pathlib import Path

import numpy as np
from _common import run_script

from mrexplore.bench.report import paired_bootstrap, steps_of
from mrexplore.bench.runner import read_rows
from mrexplore.types import MrExploreError

METRICS = {"steps": "at the end", "steps_to_99": "to 99% coverage"}

Pairs = dict[tuple[int, str], tuple[list[float], list[float]]]


def pairs(rows: list[dict[str, str]], focus: str, other: str, metric: str) -> Pairs:
    """``(team, "dataset class") -> (focus's steps, other's)``, paired by map and seed."""
    by: dict[tuple[int, str, str, str], dict[str, float]] = defaultdict(dict)
    for r in rows:
        group = f"{r['dataset']} {r['size_class']}"
        by[(int(r["robots"]), group, r["map_resolved"], r["seed"])][r["strategy"]] = steps_of(r, metric)
    out: Pairs = defaultdict(lambda: ([], []))
    for (team, group, _, _), v in sorted(by.items()):
        if focus in v and other in v:
            out[(team, group)][0].append(v[focus])
            out[(team, group)][1].append(v[other])
    return dict(out)


Differences = dict[tuple[int, str], tuple[float, float, float]]


def differences(rows: list[dict[str, str]], focus: str, other: str, metric: str) -> Differences:
    """``(team, "dataset class") -> (estimate, low, high)``: :func:`paired_bootstrap` of :func:`pairs`."""
    return {k: paired_bootstrap(*v) for k, v in pairs(rows, focus, other, metric).items()}


def _cell(est: float, lo: float, hi: float) -> str:
    mark = " **behind**" if hi < 0 else ""
    return f"{est:+.1f} [{lo:+.1f}, {hi:+.1f}]{mark}"


def table(found: dict[str, Differences]) -> tuple[str, int]:
    """The markdown table of the differences against each strategy of ``found`` by team and group, and how
    many of its intervals lie wholly below zero."""
    keys = sorted({k for d in found.values() for k in d})
    groups = sorted({g for _, g in keys})
    lines = [f"| robots | vs | {' | '.join(groups)} |", "| --- | --- |" + " --- |" * len(groups)]
    behind = 0
    for team in sorted({t for t, _ in keys}):
        for o, d in found.items():
            cells = [_cell(*d[(team, g)]) if (team, g) in d else "–" for g in groups]
            behind += sum(d[(team, g)][2] < 0 for g in groups if (team, g) in d)
            lines.append(f"| {team} | `{o}` | {' | '.join(cells)} |")
    return "\n".join(lines), behind


def figure(found: dict[tuple[str, str], Differences], focus: str, out: Path) -> None:
    """Paired differences against team size, one panel per dataset class, one series per (strategy, metric)
    of ``found``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    groups = sorted({g for d in found.values() for _, g in d})
    fig, axes = plt.subplots(1, len(groups), figsize=(3.6 * len(groups), 3.4), sharey=True, squeeze=False)
    for ax, g in zip(axes[0], groups, strict=True):
        for j, ((o, m), d) in enumerate(found.items()):
            teams = sorted(t for t, gg in d if gg == g)
            if not teams:
                continue
            stats = np.array([d[(t, g)] for t in teams])
            x = np.array(teams) + (j - (len(found) - 1) / 2) * 0.12
            err = np.abs(stats[:, 1:] - stats[:, :1]).T
            style = "o-" if m == "steps" else "s--"
            ax.errorbar(x, stats[:, 0], yerr=err, fmt=style, ms=3, lw=1, capsize=2, label=f"vs {o}, {METRICS[m]}")
        ax.axhline(0.0, color="k", lw=0.8)
        ax.set_title(g)
        ax.set_xlabel("robots")
        ax.grid(alpha=0.3)
    axes[0][0].set_ylabel(f"{focus}: fewer steps, % (95% CI)")
    axes[0][-1].legend(fontsize=7, loc="lower right")
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    plt.close(fig)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--runs", type=Path, required=True, help="a mrexplore bench folder (results.csv)")
    ap.add_argument("--focus", default="hier", help="the strategy compared (default hier)")
    ap.add_argument("--against", default="hier-heuristic,utility", help="comma-separated strategies")
    ap.add_argument("--out", type=Path, default=None, help="folder for by_team.md and by_team.png (default --runs)")
    a = ap.parse_args()
    csv_path = a.runs / "results.csv"
    if not csv_path.is_file():
        raise MrExploreError(f"{csv_path} not found; pass --runs a folder written by 'mrexplore bench'")
    rows = read_rows(csv_path)
    against = [s for s in a.against.split(",") if s]
    present = {r["strategy"] for r in rows}
    missing = [s for s in [a.focus, *against] if s not in present]
    if missing:
        raise MrExploreError(
            f"{csv_path} has no episodes of {', '.join(missing)}; choose among {', '.join(sorted(present))}"
        )
    out = a.out or a.runs
    out.mkdir(parents=True, exist_ok=True)
    text = [
        f"# `{a.focus}` against {', '.join(f'`{s}`' for s in against)} by team size",
        "",
        "Fewer steps in % of the other's mean, paired by map and seed (positive: "
        f"`{a.focus}` is faster), 95% bootstrap interval; **behind**: the interval lies wholly below zero.",
    ]
    found = {(o, m): differences(rows, a.focus, o, m) for o in against for m in METRICS}
    for metric, words in METRICS.items():
        body, behind = table({o: found[(o, metric)] for o in against})
        text += ["", f"## Steps {words} ({behind} intervals wholly behind)", "", body]
        print(f"{metric}: {behind} intervals wholly behind")
    (out / "by_team.md").write_text("\n".join(text) + "\n")
    figure(found, a.focus, out / "by_team.png")
    print(f"wrote {out / 'by_team.md'} and {out / 'by_team.png'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(run_script(main))
