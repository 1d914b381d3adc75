"""Learn the frontier codec's prior table from missions on the training maps (never the dev maps).

    python benchmarks/codec_prior.py --out src/mrexplore/preprocessing/codec_prior.npy

Runs missions on DungeonMaps training plans (``train/dungeon``) and on the procedural generator's ``varied:``
plans, with ``hier`` and ``utility``, 2, 3 and 5 robots at 0.1 m, and counts every decision of every
delta the robots send (nearly every message after a robot's first) in each context of the codec's model.
Each context's counts are scaled to at most ``--strength`` observations and stored in half units, so that
a message's own statistics soon outweigh them. A new table is a new wire format: bump ``sparse_codec.VERSION`` and
``PRIOR_SHA256`` with it (this script prints the digest).
"""

from __future__ import annotations

import argparse
import hashlib
from pathlib import Path

import numpy as np
from _common import run_script, skip

from mrexplore.config import MapConfig, MissionConfig, SimConfig
from mrexplore.maps.loaders import load_map
from mrexplore.mission import Mission, MissionSpec
from mrexplore.pipeline import make_strategy
from mrexplore.preprocessing import sparse_codec, transmission
from mrexplore.runtime.example_maps import maps_dir
from mrexplore.runtime.progress import Progress

TEAMS = (2, 3, 5)
STRATEGIES = ("hier", "utility")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, required=True, help="the table to write (.npy)")
    ap.add_argument("--maps", type=int, default=12, help="training plans of each source (default 12)")
    ap.add_argument("--strength", type=int, default=16, help="most observations a context's prior holds")
    args = ap.parse_args()
    train = maps_dir() / "train" / "dungeon"
    if not train.is_dir():
        return skip("DungeonMaps training plans", train)
    rng = np.random.default_rng(0)
    plans = sorted(train.glob("*.png"))
    picked = [str(plans[k]) for k in rng.choice(len(plans), args.maps, replace=False)]
    picked += [f"varied:{seed}" for seed in range(1, args.maps + 1)]
    counts = np.zeros((sparse_codec.N_CONTEXTS, 2), dtype=np.int64)
    encode = transmission.encode

    def counting(message, base=None):  # noqa: ANN001, ANN202 - stands in for the codec's encode
        if message.is_delta:
            counts[:] += sparse_codec.context_counts(message, base)
        return encode(message, base)

    transmission.encode = counting
    # The missions' own messages need some table; the counts do not depend on it.
    sparse_codec._prior_table = np.zeros((sparse_codec.N_CONTEXTS, 2), dtype=np.uint8)
    bar = Progress(len(picked), "counting codec contexts", "missions")
    for k, name in enumerate(picked):
        truth = load_map(name, MapConfig(resolution_m=0.1))
        sim = SimConfig(robots=TEAMS[k % len(TEAMS)])
        spec = MissionSpec(truth, make_strategy(STRATEGIES[k % 2]), sim, MissionConfig(), k)
        mission = Mission(spec, progress=False)
        while mission.advance():
            mission.decide()
        bar.update(1)
    bar.close()
    total = counts.sum(axis=1, keepdims=True)
    scale = np.minimum(1.0, args.strength / np.maximum(total, 1))
    table = np.rint(2 * counts * scale).astype(np.uint8)
    np.save(args.out, table)
    seen = int((total > 0).sum())
    print(f"{seen} of {sparse_codec.N_CONTEXTS} contexts seen, {int(total.sum())} decisions counted")
    print(f"wrote {args.out}: sha256 {hashlib.sha256(table.tobytes()).hexdigest()}")
    return 0


if __name__ == "__main__":
    raise SystemExit(run_script(main))
