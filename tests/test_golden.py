"""Golden records: 40 missions (4 maps x coscan, oracle, utility, hier, hier-plan-nolocal, with and without
faults) give the records stored in tests/data/golden_records.json, every field but the timings. A change that
is meant to leave behaviour as it is (a refactor, a speed-up) must keep them; one that changes missions on
purpose rewrites the file (``python tests/test_golden.py``) and says why in its commit."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import pytest
from conftest import SHARED_MAPS, require_shared_maps

from mrexplore.config import FaultConfig, MapConfig, MissionConfig, SimConfig
from mrexplore.maps.loaders import load_map
from mrexplore.mission import MissionSpec, run_mission
from mrexplore.pipeline import make_strategy

RECORDS = Path(__file__).with_name("data") / "golden_records.json"
MAPS = (
    "generated:1",
    "dungeon/complex_img_43.png",
    "houseexpo/json/0004d52d1aeeb8ae6de39d6bd993e992.json",
    "houseexpo/png/00922f91aa09dbdda3a74489ea0e21eb.png",
)
STRATEGIES = ("coscan", "oracle", "utility", "hier", "hier-plan-nolocal")
MISSIONS = {
    "none": MissionConfig(max_steps=3000),
    "faults": MissionConfig(max_steps=3000, faults=FaultConfig(message_loss=0.3, robot_failures=((1, 60),))),
}
TIMINGS = ("wall_s", "plan_ms_mean", "plan_ms_p95", "peak_mb", "onboard_ms_median", "onboard_ms_p95")


def records() -> dict[str, dict[str, object]]:
    """Every mission's measures but the timings, keyed ``map|strategy|faults``; 3 robots, seed 1, 0.1 m."""
    out = {}
    for m in MAPS:
        truth = load_map(m if ":" in m else SHARED_MAPS / m, MapConfig(resolution_m=0.1))
        for s in STRATEGIES:
            for name, cfg in MISSIONS.items():
                spec = MissionSpec(truth, make_strategy(s), SimConfig(robots=3), cfg, seed=1)
                measures = run_mission(spec, progress=False).measures.to_dict()
                out[f"{truth.name}|{s}|{name}"] = {k: v for k, v in measures.items() if k not in TIMINGS}
    return out


@pytest.mark.slow
def test_the_golden_missions_give_their_records() -> None:
    require_shared_maps()
    want = json.loads(RECORDS.read_text())
    got = json.loads(json.dumps(records()))  # the same float and None forms as the file's
    assert got.keys() == want.keys()
    differ = [k for k in want if got[k] != want[k]]
    assert not differ, f"{len(differ)} of {len(want)} records differ: {differ}"


if __name__ == "__main__":
    RECORDS.write_text(json.dumps(records(), indent=1, sort_keys=True) + "\n")
    sys.exit(0)
