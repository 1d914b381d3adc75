"""How a centre decision's time grows with the map's cells and the team's size: a log-log plot and slopes.

Run: python benchmarks/scaling.py [--map KTH.yaml] [--resolutions 0.4 0.2 0.1 0.05 0.035]
                                  [--robots 2 4 8 16] [--steps 300] [--out docs/results/scaling]

One KTH floor (default 50010535_PLAN1, 10,141 m² of interior) at several cell sizes gives maps of about
0.08 M to 10 M cells holding the same building; at each, teams of 2 to 16 robots run the first ``--steps``
steps of a `utility` mission (the package's one replanning loop, a decision at least every 10 steps), and
the median decision time is kept. The same steps cover the same metres at every cell size, so the cells
axis asks how the cost follows the resolution of one explored state, and the robots axis how it follows
the team. Slopes are least-squares fits of log(ms) on log(cells) per team and on log(robots) per cell size.
Writes ``scaling.csv`` and ``scaling.png`` under ``--out``; prints the table and the slopes.
"""

from __future__ import annotations

import argparse
import csv
import sys
from pathlib import Path

import numpy as np
from _common import run_script, time_mission

from mrexplore.runtime.example_maps import maps_dir

KTH = maps_dir() / "kth_floorplans"


def slope(x: list[float], y: list[float]) -> float:
    """Least-squares slope of log(y) on log(x)."""
    return float(np.polyfit(np.log(x), np.log(y), 1)[0])


def plot(rows: list[dict[str, float]], out: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (a, b) = plt.subplots(1, 2, figsize=(10, 4))
    for n in sorted({int(r["robots"]) for r in rows}):
        sel = sorted((r for r in rows if int(r["robots"]) == n), key=lambda r: r["cells"])
        x, y = [r["cells"] for r in sel], [r["decision_ms_median"] for r in sel]
        a.loglog(x, y, "o-", label=f"{n} robots (slope {slope(x, y):.2f})")
    for res in sorted({r["resolution_m"] for r in rows}, reverse=True):
        sel = sorted((r for r in rows if r["resolution_m"] == res), key=lambda r: r["robots"])
        x, y = [r["robots"] for r in sel], [r["decision_ms_median"] for r in sel]
        b.loglog(x, y, "o-", label=f"{res:g} m, {sel[0]['cells'] / 1e6:.2f} M cells (slope {slope(x, y):.2f})")
    a.set_xlabel("map cells")
    b.set_xlabel("robots")
    b.set_xticks([2, 4, 8, 16], ["2", "4", "8", "16"])
    for ax in (a, b):
        ax.set_ylabel("centre decision, median ms")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7)
    from matplotlib.ticker import NullFormatter

    b.xaxis.set_minor_formatter(NullFormatter())
    for ax in (a, b):  # room above the lines for the legends
        lo, hi = ax.get_ylim()
        ax.set_ylim(lo, hi * 4)
        ax.legend(fontsize=7, loc="upper left")
    fig.suptitle("Decision time against map cells and team size (log-log)")
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    plt.close(fig)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--map", type=Path, default=KTH / "50010535_PLAN1.yaml")
    ap.add_argument("--resolutions", type=float, nargs="+", default=[0.4, 0.2, 0.1, 0.05, 0.035])
    ap.add_argument("--robots", type=int, nargs="+", default=[2, 4, 8, 16])
    ap.add_argument("--steps", type=int, default=300)
    ap.add_argument("--out", type=Path, default=Path("docs/results/scaling"))
    ap.add_argument("--replot", action="store_true", help="only redraw the plot from --out's scaling.csv")
    args = ap.parse_args()
    if args.replot:
        with open(args.out / "scaling.csv") as f:
            plot([{k: float(v) for k, v in r.items()} for r in csv.DictReader(f)], args.out / "scaling.png")
        return 0
    if not args.map.exists():
        print(f"skipped: map not found at {args.map} (the KTH floors live in ../shared/maps)", file=sys.stderr)
        return 0
    time_mission(args.map, 2, 20, "utility", 0.2)  # compile the numba kernels outside the timings
    args.out.mkdir(parents=True, exist_ok=True)
    rows: list[dict[str, float]] = []
    print("resolution m  cells      robots  coverage  decision ms (median / p95)")
    for res in args.resolutions:
        for n in args.robots:
            r = time_mission(args.map, n, args.steps, "utility", res)
            rows.append({"resolution_m": res, "robots": n, **r})
            print(
                f"{res:12g}  {r['cells']:9d}  {n:6d}  {r['coverage']:8.3f}"
                f"  {r['decision_ms_median']:8.2f} / {r['decision_ms_p95']:7.2f}",
                flush=True,
            )
            with open(args.out / "scaling.csv", "w", newline="") as f:  # rewritten as rows come: kept on a kill
                w = csv.DictWriter(f, fieldnames=list(rows[0]))
                w.writeheader()
                w.writerows(rows)
    for n in args.robots:
        sel = [r for r in rows if r["robots"] == n]
        ms = [r["decision_ms_median"] for r in sel]
        print(f"{n} robots: slope in cells {slope([r['cells'] for r in sel], ms):.2f}")
    for res in args.resolutions:
        sel = [r for r in rows if r["resolution_m"] == res]
        ms = [r["decision_ms_median"] for r in sel]
        print(f"{res:g} m: slope in robots {slope([r['robots'] for r in sel], ms):.2f}")
    plot(rows, args.out / "scaling.png")
    print(f"wrote {args.out / 'scaling.csv'} and {args.out / 'scaling.png'}")
    return 0


if __name__ == "__main__":
    sys.exit(run_script(main))
