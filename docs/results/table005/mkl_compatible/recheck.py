"""Rerun, one `mrexplore explore --json` each, the episodes of a bench run that differ from recorded rows, and
say how many are the same as recorded now (3-robot maps at 0.05 m, as `../dev3/`):

    python docs/results/table005/mkl_compatible/recheck.py RUN.csv RECORDED.csv [MKL_CBWR]

MKL_CBWR, where given, is set for the reruns; otherwise they run with whatever importing mrexplore sets.
Run from the repository root with `../shared/maps/` beside it.
"""

from __future__ import annotations

import csv
import json
import os
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

TIMING = {"wall_s", "plan_ms_mean", "plan_ms_p95", "peak_mb", "onboard_ms_median", "onboard_ms_p95", "map_resolved"}
COMPARED = ("steps", "coverage", "steps_to_99", "path_len_sum_m", "bytes_sparse", "bytes_sparse_delta", "decisions")


def main() -> None:
    run_csv, recorded_csv = sys.argv[1], sys.argv[2]
    recorded = {(r["map"], r["strategy"], r["seed"]): r for r in csv.DictReader(open(recorded_csv))}
    run = list(csv.DictReader(open(run_csv)))
    keys = [k for k in run[0] if k not in TIMING]
    differ = [r for r in run if any(recorded[r["map"], r["strategy"], r["seed"]][k] != r[k] for k in keys)]
    print(f"{len(run)} episodes, {len(differ)} unlike the recorded rows in {len(keys)} columns")
    files = {
        p.stem: p
        for d in ("houseexpo", "dungeon", "ros")
        for p in Path("../shared/maps", d).rglob("*")
        if p.suffix in (".json", ".png", ".yaml")
    }
    env = {k: v for k, v in os.environ.items() if k != "MKL_CBWR"}
    env["MREXPLORE_THREADS"] = "1"
    if len(sys.argv) > 3:
        env["MKL_CBWR"] = sys.argv[3]

    def rerun(r: dict[str, str]) -> bool:
        cmd = [sys.executable, "-m", "mrexplore", "explore", "--map", str(files[r["map"]]), "--robots", "3"]
        cmd += ["--seed", r["seed"], "--resolution", "0.05", "--strategy", r["strategy"], "--max-steps", "60000"]
        cmd += ["--no-baseline-bytes", "--no-progress", "--json"]
        got = json.loads(subprocess.run(cmd, env=env, capture_output=True, text=True, check=True).stdout)
        old = recorded[r["map"], r["strategy"], r["seed"]]
        same = all(str(got[k]) == old[k] or abs(float(got[k]) - float(old[k])) < 1e-9 for k in COMPARED)
        print(r["map"], r["strategy"], r["seed"], "steps", old["steps"], "recorded,", r["steps"], "in the run,", got["steps"], "now")
        return same

    with ThreadPoolExecutor(2) as pool:
        same = list(pool.map(rerun, differ))
    print(f"{sum(same)} of {len(differ)} now the same as recorded")


if __name__ == "__main__":
    main()
