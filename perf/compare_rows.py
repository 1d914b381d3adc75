"""Episode records of a fixed set of missions, to check that a refactor leaves results unchanged.

    python perf/compare_rows.py --out before.json      # at the commit before the change
    python perf/compare_rows.py --out after.json       # after it
    python perf/compare_rows.py --compare before.json after.json
    (--no-faults at commits before the fault work: only the fault-free missions)

Missions: 4 maps (generated:1, DungeonMaps complex_img_43, HouseExpo 0004d52d... JSON and 00922f91... PNG) x
coscan, oracle, utility, hier x no fault / (30% loss + robot 1 lost at step 60); 3 robots, seed 1, 0.1 m,
3,000-step budget. Timings are left out of the records; every field both versions record must match.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from mrexplore.cli import run_script
from mrexplore.config import MapConfig, MissionConfig, SimConfig
from mrexplore.maps.loaders import load_map
from mrexplore.mission import MissionSpec, run_mission
from mrexplore.pipeline import make_strategy

SHARED = Path(__file__).resolve().parents[2] / "shared" / "maps"
MAPS = (
    "generated:1",
    str(SHARED / "dungeon" / "complex_img_43.png"),
    str(SHARED / "houseexpo" / "json" / "0004d52d1aeeb8ae6de39d6bd993e992.json"),
    str(SHARED / "houseexpo" / "png" / "00922f91aa09dbdda3a74489ea0e21eb.png"),
)
STRATEGIES = ("coscan", "oracle", "utility", "hier")
TIMINGS = ("wall_s", "plan_ms_mean", "plan_ms_p95", "peak_mb", "onboard_ms_median", "onboard_ms_p95")


def _missions(with_faults: bool) -> dict[str, MissionConfig]:
    cfgs = {"none": MissionConfig(max_steps=3000)}
    if with_faults:  # FaultConfig exists from the fault work on; older commits compare the fault-free part
        from mrexplore.config import FaultConfig

        cfgs["faults"] = MissionConfig(max_steps=3000, faults=FaultConfig(message_loss=0.3, robot_failures=((1, 60),)))
    return cfgs


def records(with_faults: bool = True) -> dict[str, dict[str, object]]:
    out = {}
    for m in MAPS:
        truth = load_map(m, MapConfig(resolution_m=0.1))
        for s in STRATEGIES:
            for name, cfg in _missions(with_faults).items():
                r = run_mission(MissionSpec(truth, make_strategy(s), SimConfig(robots=3), cfg, seed=1), progress=False)
                d = {k: v for k, v in r.measures.to_dict().items() if k not in TIMINGS}
                out[f"{truth.name}|{s}|{name}"] = d
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", help="write the records here")
    ap.add_argument("--no-faults", action="store_true", help="only the fault-free missions (for older commits)")
    ap.add_argument("--compare", nargs=2, metavar=("BEFORE", "AFTER"), help="compare two record files")
    args = ap.parse_args()
    if args.compare:
        a, b = (json.loads(Path(p).read_text()) for p in args.compare)
        common = a.keys() & b.keys()
        # a field only one version records (added by the change) is not a difference
        differ = sorted(k for k in common if any(a[k][f] != b[k][f] for f in a[k].keys() & b[k].keys())) + sorted(
            a.keys() ^ b.keys()
        )
        print(f"{len(a)} and {len(b)} records; {len(differ)} differ" + "".join(f"\n  {k}" for k in differ))
        sys.exit(1 if differ else 0)
    Path(args.out).write_text(json.dumps(records(not args.no_faults), indent=0))


if __name__ == "__main__":
    sys.exit(run_script(main))
