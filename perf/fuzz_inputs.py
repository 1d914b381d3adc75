"""Long fuzz run of everything that reads users' or robots' bytes: map loaders (mutations of every dev map
format), the frontier-message decoder, and the policy loader. Counts outcomes, keeps any input that ends
in anything but a result or one MrExploreError line, and reports the slowest load and the peak memory.

    python perf/fuzz_inputs.py --minutes 10 --out docs/results/fuzz

The CI tests (tests/maps/test_fuzz_inputs.py, tests/preprocessing/test_sparse_codec.py) run the same
mutations briefly.
"""

from __future__ import annotations

import argparse
import collections
import resource
import sys
import time
import traceback
from dataclasses import replace
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "maps"))

from conftest import SHARED_MAPS  # noqa: E402
from test_fuzz_inputs import FUZZ_CFG, load_outcome, mutate, mutated_copy  # noqa: E402

from mrexplore.cli import run_script
from mrexplore.global_planning.learned.checkpoint import default_policy_path, load_policy  # noqa: E402
from mrexplore.maps.loaders import load_map  # noqa: E402
from mrexplore.preprocessing.sparse_codec import decode, encode  # noqa: E402
from mrexplore.preprocessing.sparse_map import sparse_frontier_map  # noqa: E402
from mrexplore.types import CellState, MrExploreError  # noqa: E402

MAP_FILES = (
    ("houseexpo/json/0004d52d1aeeb8ae6de39d6bd993e992.json",),
    ("houseexpo/png/00922f91aa09dbdda3a74489ea0e21eb.png",),
    ("dungeon/easy_img_15.png",),
    ("ros/basement_hallways_5cm.yaml", "ros/basement_hallways_5cm.png"),
    ("ros/willow-2010-02-18-0.10.yaml", "ros/willow-2010-02-18-0.10.pgm"),
    ("kth_floorplans/50010535_PLAN1.yaml", "kth_floorplans/50010535_PLAN1.png"),
)


def _message_bytes() -> bytes:
    truth = load_map("generated:1", FUZZ_CFG)
    state = np.where(truth.occupied, CellState.OCCUPIED, CellState.FREE).astype(np.uint8)
    state[:, state.shape[1] // 2 :] = CellState.UNKNOWN
    return encode(sparse_frontier_map(state, 0, 3, (5, 5)))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--minutes", type=float, default=10.0)
    ap.add_argument("--out", default="docs/results/fuzz")
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    if not SHARED_MAPS.is_dir():
        sys.exit(f"shared maps not found at {SHARED_MAPS}")
    out = Path(args.out)
    work = out / "work"
    crashes = out / "crashes"
    work.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(args.seed)
    message = _message_bytes()
    policy = default_policy_path().read_bytes()
    tally: dict[str, collections.Counter[str]] = collections.defaultdict(collections.Counter)
    slowest: dict[str, float] = collections.defaultdict(float)
    kept = 0
    deadline = time.perf_counter() + args.minutes * 60
    n = 0
    targets = [*(f[0] for f in MAP_FILES), "message", "policy"]
    while time.perf_counter() < deadline:
        target = targets[n % len(targets)]
        n += 1
        t0 = time.perf_counter()
        try:
            if target == "message":
                data = mutate(message, rng)
                try:
                    decode(data)
                    outcome = "decoded"
                except MrExploreError as exc:
                    outcome = "error: " + " ".join(str(exc).split()[:5])
            elif target == "policy":
                data = mutate(policy, rng)
                (work / "p.pt").write_bytes(data)
                try:
                    load_policy(work / "p.pt")
                    outcome = "loaded"
                except MrExploreError as exc:
                    outcome = "error: " + " ".join(str(exc).split()[3:8])
            else:
                files = next(f for f in MAP_FILES if f[0] == target)
                entry = mutated_copy(SHARED_MAPS, files, work, rng)
                data = entry.read_bytes()
                cfg = replace(FUZZ_CFG, resolution_m=0.5) if "kth" in target else FUZZ_CFG  # KTH floors are big
                outcome = load_outcome(entry, cfg).replace(str(work) + "/", "")
        except Exception as exc:  # noqa: BLE001 - what this run looks for
            outcome = f"CRASH {type(exc).__name__}"
            crashes.mkdir(parents=True, exist_ok=True)
            (crashes / f"{kept:04d}-{Path(target).name}").write_bytes(data)
            (crashes / f"{kept:04d}.txt").write_text(traceback.format_exc())
            kept += 1
        slowest[target] = max(slowest[target], time.perf_counter() - t0)
        tally[target][outcome] += 1
    peak_mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    lines = [
        "# Fuzz run of the input readers",
        "",
        f"Made by: `python perf/fuzz_inputs.py --minutes {args.minutes:g} --out {args.out} --seed {args.seed}`",
        f"({n} inputs; peak memory of the process {peak_mb:.0f} MB; inputs that crashed: {kept}).",
        "",
        "| target | inputs | slowest (s) | outcomes (most frequent first) |",
        "|---|---:|---:|---|",
    ]
    for target in targets:
        c = tally[target]
        top = "; ".join(f"{k} ({v})" for k, v in c.most_common(6))
        lines.append(f"| {Path(target).name} | {sum(c.values())} | {slowest[target]:.2f} | {top} |")
    (out / "README.md").write_text("\n".join(lines) + "\n")
    for f in work.iterdir():
        f.unlink()
    work.rmdir()
    print("\n".join(lines))


if __name__ == "__main__":
    sys.exit(run_script(main))
