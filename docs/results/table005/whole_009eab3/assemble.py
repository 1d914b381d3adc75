"""The whole 0.05 m Table I at today's code, from its three parts run whole on 2026-12-04's machine, each
alone on it under `/usr/bin/time -v`:

    python docs/results/table005/whole_009eab3/assemble.py

- the 3-robot half (HouseExpo, DungeonMaps, ROS): `../mkl_compatible/avx512_1219982/` for every strategy
  but the learned ones, whose rows moved with MKL's path there, and `../mkl_compatible/learned_4d2a3ed/` for
  `hier` and `ncm` (MKL pinned);
- the seven smaller KTH floors with 8 robots: `../mkl_compatible/kth7_4d2a3ed/`;
- PLAN1-3 with 8 robots: `plan_009eab3/`.

Between 1219982 and 009eab3 only the MKL pin (4d2a3ed) and a mend of NCM's input that leaves every result as
it was (009eab3) changed the source, so the rows are those of one code version. Writes `dev3/` and `kth8/`
here (the rows and a bench report each, as `../dev3/` and `../kth8/`), and prints each part's wall clock
and the whole table's.
"""

from __future__ import annotations

import csv
import re
from pathlib import Path

from mrexplore.bench.report import write_report

HERE = Path(__file__).parent
RUNS = HERE.parent / "mkl_compatible"
LEARNED = ("hier", "ncm")
STRATEGIES = ("hier", "hier-heuristic", "utility", "nearest", "coscan", "ncm", "oracle")
PARTS = {
    # part: (folder, strategies taken from it, whether its wall clock counts in the table's). The whole
    # 3-robot run's time holds its learned episodes (on MKL's AVX-512 path, 4.88 and 8.30 worker-minutes for
    # hier and ncm, against 4.71 and 8.23 in the rerun with MKL pinned), so the rerun's is left out.
    "3-robot half, but learned (1219982)": (RUNS / "avx512_1219982", set(STRATEGIES) - set(LEARNED), True),
    "3-robot half, learned (4d2a3ed)": (RUNS / "learned_4d2a3ed", set(LEARNED), False),
    "seven smaller KTH floors (4d2a3ed)": (RUNS / "kth7_4d2a3ed", set(STRATEGIES), True),
    "PLAN1-3 (009eab3)": (HERE / "plan_009eab3", set(STRATEGIES), True),
}
COMMANDS = {
    "dev3": "mrexplore bench --maps ../shared/maps/houseexpo ../shared/maps/dungeon ../shared/maps/ros "
    "--strategies hier,hier-heuristic,utility,nearest,coscan,ncm,oracle --robots 3 --seeds 3 --resolution 0.05 "
    "--workers 2 --max-steps 60000 --no-baseline-bytes --no-progress (two runs: every strategy at 1219982, "
    "hier and ncm again at 4d2a3ed)",
    "kth8": "mrexplore bench --maps ../shared/maps/kth_floorplans --strategies "
    "hier,hier-heuristic,utility,nearest,coscan,ncm,oracle --robots 8 --seeds 3 --resolution 0.05 --workers 2 "
    "--max-steps 100000 --no-baseline-bytes --no-progress (two runs: the seven smaller floors at 4d2a3ed, "
    "PLAN1-3 at 009eab3)",
}


def wall_s(folder: Path) -> float:
    """The run's wall clock from its `/usr/bin/time -v` output."""
    text = (folder / "time.txt").read_text()
    clock = re.search(r"Elapsed \(wall clock\) time \(h:mm:ss or m:ss\): ([\d:.]+)", text)
    if clock is None:
        raise SystemExit(f"{folder / 'time.txt'} holds no wall clock line")
    seconds = 0.0
    for part in clock.group(1).split(":"):
        seconds = seconds * 60 + float(part)
    return seconds


def main() -> None:
    halves: dict[str, list[dict[str, str]]] = {"dev3": [], "kth8": []}
    for name, (folder, keep, _) in PARTS.items():
        with (folder / "results.csv").open(newline="") as f:
            rows = [r for r in csv.DictReader(f) if r["strategy"] in keep]
        halves["dev3" if team_size(rows) == "3" else "kth8"].extend(rows)
        print(f"{name}: {len(rows)} episodes from {folder.relative_to(HERE.parent)}")
    for half, rows in halves.items():
        out = HERE / half
        out.mkdir(exist_ok=True)
        with (out / "results.csv").open("w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=list(rows[0]))
            w.writeheader()
            w.writerows(rows)
        write_report(out / "results.csv", out / "report.md", STRATEGIES, COMMANDS[half])
        cut = sum(r["done_reason"] == "max_steps" for r in rows)
        peak = max(float(r["peak_mb"]) for r in rows)
        print(f"{half}: {len(rows)} episodes, {cut} cut by the budget, largest peak {peak:.0f} MB")
    walls = {name: wall_s(folder) for name, (folder, _, timed) in PARTS.items() if timed}
    for name, s in walls.items():
        print(f"{name}: {s / 60:.1f} min wall")
    print(f"whole table: {sum(walls.values()) / 60:.1f} min wall on two workers")


def team_size(rows: list[dict[str, str]]) -> str:
    """The one team size of a part's rows."""
    robots = {r["robots"] for r in rows}
    if len(robots) != 1:
        raise SystemExit(f"a part mixes team sizes {sorted(robots)}")
    return robots.pop()


if __name__ == "__main__":
    main()
