"""Two bench folders of the same episodes, row for row: per strategy, how many episodes both hold and in how
many any result column differs (timings, paths and hashes aside). What a change that is meant to keep every
mission shows: run ``mrexplore bench`` with the same flags on the code before (a worktree) and after, then

Run: python benchmarks/same_rows.py BEFORE_DIR AFTER_DIR
It exits 1 where an episode differs, naming its first differing columns.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from _common import run_script

from mrexplore.bench.compare import _NOT_RESULTS
from mrexplore.bench.runner import read_rows
from mrexplore.types import MrExploreError


def _rows(folder: Path) -> dict[tuple[str, str, str, str], dict[str, str]]:
    path = folder / "results.csv"
    if not path.is_file():
        raise MrExploreError(f"{path} not found; give folders that 'mrexplore bench --out' wrote")
    return {(r["map_path"], r["strategy"], r["robots"], r["seed"]): r for r in read_rows(path)}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("before", type=Path)
    ap.add_argument("after", type=Path)
    args = ap.parse_args()
    a, b = _rows(args.before), _rows(args.after)
    shared = sorted(set(a) & set(b))
    print("| strategy | episodes in both | differ |\n| --- | --- | --- |")
    differ = []
    for strategy in sorted({k[1] for k in shared}):
        keys = [k for k in shared if k[1] == strategy]
        bad = [k for k in keys if any(a[k][c] != b[k].get(c) for c in a[k] if c not in _NOT_RESULTS)]
        differ += bad
        print(f"| {strategy} | {len(keys)} | {len(bad)} |")
    for k in differ:
        cols = [c for c in a[k] if c not in _NOT_RESULTS and a[k][c] != b[k].get(c)]
        print(f"- {k[1]}, {Path(k[0]).name}, robots {k[2]}, seed {k[3]}: {', '.join(cols[:5])}")
    only = len(set(a) ^ set(b))
    print(f"{len(shared)} episodes in both, {len(differ)} differ; {only} in one folder only")
    return 1 if differ else 0


if __name__ == "__main__":
    sys.exit(run_script(main))
