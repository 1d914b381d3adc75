"""How much of a mission's wall time goes to Table II's int8-grid baselines (``mission.baseline_bytes``):
the same stretch of one mission timed with them counted, on one thread, as the bench's workers run.

    MREXPLORE_THREADS=1 python perf/accounting_share.py --map ../shared/maps/kth_floorplans/50010535_PLAN1.yaml \\
        --strategy nearest --from-coverage 0.3 --steps 3000

The mission first runs untimed to ``--from-coverage``; then ``--steps`` steps are timed, and the time spent
in the baselines' two counts (:func:`~mrexplore.preprocessing.transmission.occupancy_grid_bytes` and
:meth:`~mrexplore.preprocessing.transmission.RobotSender.grid_delta_bytes`) is measured by wall-clock timers
round them. Leaving them out (``--no-baseline-bytes``) saves that time and changes no mission.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import mrexplore.preprocessing.transmission as transmission
import mrexplore.strategies as strategies
from mrexplore.cli import run_script
from mrexplore.config import MapConfig, MissionConfig, RunConfig, SimConfig
from mrexplore.maps.loaders import load_map
from mrexplore.mission import Mission


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--map", type=Path, required=True)
    ap.add_argument("--strategy", default="nearest")
    ap.add_argument("--robots", type=int, default=8)
    ap.add_argument("--resolution", type=float, default=0.05)
    ap.add_argument("--from-coverage", type=float, default=0.3)
    ap.add_argument("--steps", type=int, default=3000)
    args = ap.parse_args()
    cfg = RunConfig()
    truth = load_map(args.map, MapConfig(resolution_m=args.resolution))
    strategy = strategies.make_strategy(
        args.strategy, cfg.global_planning, cfg.preprocess, cfg.local_planning, coscan_cfg=cfg.coscan
    )
    mission = Mission(truth, strategy, SimConfig(robots=args.robots), MissionConfig(100_000), 0, progress=False)
    while mission.advance():
        mission.decide()
        if mission.curve[-1] >= args.from_coverage:
            break
    spent = [0.0]
    for owner, name in ((transmission, "occupancy_grid_bytes"), (transmission.RobotSender, "grid_delta_bytes")):
        plain = getattr(owner, name)

        def timed(*a: object, _plain: object = plain, **k: object) -> object:
            t = time.perf_counter()
            try:
                return _plain(*a, **k)  # type: ignore[operator]
            finally:
                spent[0] += time.perf_counter() - t

        setattr(owner, name, timed)
    first, t0 = mission.steps, time.perf_counter()
    while mission.steps - first < args.steps and mission.advance():
        mission.decide()
    wall = time.perf_counter() - t0
    print(
        f"{truth.name}, {args.strategy}, {args.robots} robots, {mission.steps - first} steps from coverage "
        f"{args.from_coverage} to {mission.curve[-1]:.3f}: wall {wall:.1f} s, grid baselines {spent[0]:.1f} s "
        f"({100 * spent[0] / wall:.0f}%)"
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(run_script(main))
