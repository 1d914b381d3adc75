"""The whole 0.05 m Table I projected at today's code, from the episodes run whole (`dev3/`, `kth8/`, at the
speed of that day) and the speed-ups each measured side by side since, the same missions at two versions:

    python docs/results/table005/project.py

- HouseExpo, DungeonMaps, ROS (3 robots) and the seven smaller KTH floors (8 robots): each strategy's
  episode walls times its own factor from Table I's seed 0 run at two versions at once, one worker and one
  thread each: `paired/` (dc7085f -> 7f1ddda, every strategy) and `paired_reads/` (4d01012 -> 0294536, `ncm`
  and the oracle; 4d01012 differs from 7f1ddda by review mends alone).
- PLAN1-3 (not run that way: 79 worker-minutes a seed): one mission per strategy, seed 0, the two versions
  at once, one thread each (`PLAN_FACTORS` below, each with its mission and walls). CoScan-2D's also carries
  the 14-21% of `coscan_reach/` (bbda3a6 -> 12e547d, before dc7085f), given as a range.

The rows were run at 75d3e9c/a1fb2ab; between them and dc7085f only CoScan-2D's change on PLAN1-3 (12e547d)
moved any time. Prints worker-minutes per part and the table's minutes on two workers.
"""

from __future__ import annotations

import csv
from collections import defaultdict
from pathlib import Path

HERE = Path(__file__).parent

PLAN_FACTORS = {
    # strategy: (after / before wall, the paired mission, dc7085f-or-earlier -> a later version)
    "hier": (74.5 / 86.5, "PLAN3, dc7085f -> 7f1ddda"),
    "utility": (76.5 / 84.2, "PLAN3, dc7085f -> 7f1ddda"),
    "hier-heuristic": (117.4 / 128.3, "PLAN2, dc7085f -> 1d7ec9c"),
    "nearest": (413.6 / 477.3, "PLAN1, dc7085f -> 1d7ec9c"),
    "ncm": (455.7 / 477.3, "PLAN2, dc7085f -> 1d7ec9c"),
    "oracle": (112.3 / 124.9, "PLAN2, dc7085f -> 1d7ec9c"),
    "coscan": ((382.4 / 383.7 + 404.2 / 395.2) / 2, "PLAN1, dc7085f -> 1d7ec9c and -> 5ebd823, the mean"),
}
COSCAN_REACH = (1 - 0.21, 1 - 0.14)
"""CoScan-2D's searches for tasks it may keep (12e547d), paired on PLAN3: 14-21% less."""


def rows(path: Path) -> list[dict[str, str]]:
    with path.open() as f:
        return list(csv.DictReader(f))


def walls(path: Path) -> dict[str, float]:
    out: dict[str, float] = defaultdict(float)
    for r in rows(path):
        out[r["strategy"]] += float(r["wall_s"])
    return out


def factors(part: str) -> dict[str, float]:
    """Per strategy, after / before over the seed-0 episodes of ``part`` (dev3 or kth7)."""
    before, after = walls(HERE / f"paired/before_{part}/results.csv"), walls(HERE / f"paired/after_{part}/results.csv")
    f = {s: after[s] / before[s] for s in before}
    b2, a2 = (walls(HERE / f"paired_reads/{v}_{part}/results.csv") for v in ("before", "after"))
    for s in b2:
        f[s] *= a2[s] / b2[s]
    return f


def main() -> None:
    parts: dict[str, list[float]] = {}
    f3, f7 = factors("dev3"), factors("kth7")
    dev3 = sum(float(r["wall_s"]) * f3[r["strategy"]] for r in rows(HERE / "dev3/results.csv")) / 60
    parts["3-robot maps"] = [dev3, dev3]
    small, plan = [0.0, 0.0], [0.0, 0.0]
    for r in rows(HERE / "kth8/results.csv"):
        w, s = float(r["wall_s"]) / 60, r["strategy"]
        if "PLAN" not in r["map"]:
            small = [x + w * f7[s] for x in small]
            continue
        f = PLAN_FACTORS[s][0]
        if f is None:
            raise SystemExit(f"no PLAN factor measured for {s}")
        lo, hi = (f * c for c in COSCAN_REACH) if s == "coscan" else (f, f)
        plan = [plan[0] + w * lo, plan[1] + w * hi]
    parts["smaller KTH floors"], parts["PLAN1-3"] = small, plan
    for name, (lo, hi) in parts.items():
        print(f"{name}: {lo:.1f}" + (f"-{hi:.1f}" if hi != lo else "") + " worker-minutes")
    lo = sum(p[0] for p in parts.values()) / 2
    hi = sum(p[1] for p in parts.values()) / 2
    print(f"whole table on two workers: {lo:.1f}-{hi:.1f} minutes at the speed of the day the rows were run")


if __name__ == "__main__":
    main()
