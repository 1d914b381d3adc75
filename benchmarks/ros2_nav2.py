"""A Nav2 team through ROS 2: ``mrexplore ros2 launch --nav2``, the simulator standing in for Nav2 and
slam_toolbox as they behave (docs/ros2.md), on a HouseExpo and a DungeonMaps dev map.

    python benchmarks/ros2_nav2.py --out docs/results/ros2_nav2

Each map three times, 3 robots, ``hier``, a 0.1 m team grid under 0.05 m SLAM maps, every node on sim time
running twice the wall clock: as it is, with robot 2's node killed at step 150, and with the centre killed at
step 150 and started again. Per run: coverage, steps, the goals the centre sent and sent again, the aborts the
double caused, those a new goal crossed, those the centre read, and the robots it declared lost.

Writes OUT/report.md.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

from _common import houseexpo_dir, run_script, skip

from mrexplore.runtime.example_maps import maps_dir

HOUSE = "houseexpo/json/0a1b29dba355df2ab02630133187bfab.json"
DUNGEON = "dungeon/complex_img_43.png"
FAULTS = {
    "none": [],
    "robot node killed": ["--robot-failure", "1@150"],
    "centre restarted": ["--centre-restart", "150"],
}


def launch(*args: str) -> dict[str, Any]:
    t0 = time.monotonic()
    cmd = [sys.executable, "-m", "mrexplore", "ros2", "launch", *args, "--json"]
    out = subprocess.run(cmd, capture_output=True, text=True)
    if out.returncode != 0:
        raise SystemExit(f"mrexplore ros2 launch {' '.join(args)} failed: {out.stderr.strip().splitlines()[-1:]}")
    record = json.loads(out.stdout.strip().splitlines()[-1])
    record["run_s"] = round(time.monotonic() - t0, 1)
    return record


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, required=True, help="folder for report.md")
    ap.add_argument("--clock-rate", type=float, default=2.0, help="sim time against the wall clock")
    args = ap.parse_args()
    if not houseexpo_dir().is_dir():
        return skip("HouseExpo maps", houseexpo_dir())
    args.out.mkdir(parents=True, exist_ok=True)
    nav2 = ["--nav2", "--resolution", "0.1", "--slam-resolution", "0.05", "--clock-rate", str(args.clock_rate)]
    lines = [
        "# A Nav2 team through ROS 2",
        "",
        "`mrexplore ros2 launch --nav2`: the simulator, a robot node per robot and the centre as separate processes",
        "on one machine (2 cores), DDS on loopback; the simulator stands in for each robot's Nav2 and slam_toolbox",
        "as they behave (a map frame per robot a quarter turn from the last, 0.05 m SLAM maps under a 0.1 m team",
        f"grid, goals stamped on sim time at {args.clock_rate:g}x the wall clock, a new goal aborting the last, goals",
        "within 0.1 m of an obstacle refused); 3 robots, `hier`, seed 0.",
        "",
        "| map | fault | coverage | steps | goals sent | sent again | aborts caused | crossed by a new goal |"
        " read by the centre | robots lost | wall s |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for rel in (HOUSE, DUNGEON):
        path = str(maps_dir() / rel)
        for fault, flags in FAULTS.items():
            r = launch("--map", path, "--robots", "3", *nav2, *flags)
            d = r["nav2_double"]
            lines.append(
                f"| {Path(rel).name[:12]} | {fault} | {r['coverage']:.4f} | {r['steps']} | {r['goals_sent']} | "
                f"{r['goals_resent']} | {d['aborts_caused']} | {d['aborts_crossed']} | {r['aborts_read']} | "
                f"{r['robots_lost']} | {r['run_s']:.0f} |"
            )
            print(lines[-1], file=sys.stderr)
    lines += [
        "",
        "An abort is crossed when the robot's next goal reached the double within 0.5 s of sim time after it: the",
        "centre sent that goal before the abort could reach it, so the abort is of a goal the centre had already",
        "replaced. Every other abort should be read.",
    ]
    (args.out / "report.md").write_text("\n".join(lines) + "\n")
    print(f"report: {args.out / 'report.md'}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(run_script(main))
