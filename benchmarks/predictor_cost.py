"""Where the map predictor's time goes at one decision: pooling the input, the U-Net's forward pass, the whole
``p_free`` (those two, the known cells, the sigmoid and the masks) and the predicted gain's scans from the
decision's cluster centres; median milliseconds over repeated calls on the same belief.

Run: python benchmarks/predictor_cost.py [--map MAP] [--robots 8] [--resolution 0.05] [--coverage 0.5]
     [--predictor FILE] [--repeats 20]
The belief is the centre's grid at the first decision past ``--coverage`` of a ``hier`` mission (seed 0) on
the largest HouseExpo map by default.
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
from _common import largest_houseexpo, run_script
from threadpoolctl import threadpool_limits

from mrexplore.config import GlobalPlanningConfig, MapConfig, SimConfig
from mrexplore.maps.loaders import load_map
from mrexplore.mission import MissionSpec, run_mission
from mrexplore.pipeline import make_strategy
from mrexplore.prediction.encoding import belief_channels, pool_factor
from mrexplore.prediction.gain import predicted_gain_m2
from mrexplore.prediction.network import load_predictor
from mrexplore.types import MrExploreError


def median_ms(f: Callable[[], Any], repeats: int) -> float:
    """Median wall time of ``f`` in milliseconds, after one untimed call (numba's compilation, caches)."""
    f()
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        f()
        times.append(time.perf_counter() - t0)
    return 1000.0 * float(np.median(times))


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--map", type=Path, default=None, help="default: the largest HouseExpo map")
    ap.add_argument("--robots", type=int, default=8)
    ap.add_argument("--resolution", type=float, default=0.05, help="cell size, metres (default 0.05)")
    ap.add_argument("--coverage", type=float, default=0.5, help="take the belief past this coverage (0-1)")
    ap.add_argument("--predictor", default=None, help="a file written by 'mrexplore train --target predictor'")
    ap.add_argument("--repeats", type=int, default=20)
    a = ap.parse_args()
    if not 0.0 <= a.coverage < 1.0:
        raise MrExploreError(f"--coverage must be in [0, 1), got {a.coverage}")
    path = a.map or largest_houseexpo()
    if not Path(path).is_file():
        raise MrExploreError(f"map file not found: {path}; pass an existing map file with --map")
    predictor = load_predictor(a.predictor)
    truth = load_map(path, MapConfig(resolution_m=a.resolution))
    taken: list[Any] = []

    def observe(sim, decision, goals, status) -> None:  # noqa: ANN001 - the mission's observer
        if decision is not None and not taken and sim.coverage >= a.coverage:
            taken.append(decision)

    run_mission(MissionSpec(truth, make_strategy("hier"), SimConfig(robots=a.robots), seed=0), observe, progress=False)
    if not taken:
        raise MrExploreError(f"the mission ended before coverage {a.coverage}; pass a lower --coverage")
    decision = taken[0]
    state, centres = decision.state, decision.clusters.centers_rc
    factor = pool_factor(a.resolution, predictor.cell_m)
    x = belief_channels(state, factor)
    p = predictor.p_free(state, a.resolution)
    range_m = GlobalPlanningConfig().gain_range_m
    with threadpool_limits(1, "blas"):  # as p_free runs the network: on one BLAS thread
        forward_ms = median_ms(lambda: predictor.net(x), a.repeats)
    rows = [
        ("pool the input (whole grid)", median_ms(lambda: belief_channels(state, factor), a.repeats)),
        ("U-Net forward (whole grid)", forward_ms),
        ("p_free (known box + reach)", median_ms(lambda: predictor.p_free(state, a.resolution), a.repeats)),
        (
            f"gain scans ({len(centres)} centres)",
            median_ms(lambda: predicted_gain_m2(state, p, centres, a.resolution, range_m), a.repeats),
        ),
    ]
    print(f"map {Path(path).stem}, {a.robots} robots, {a.resolution} m, grid {state.shape[0]} x {state.shape[1]}")
    for name, ms in rows:
        print(f"{name:32s} {ms:8.2f} ms")
    return 0


if __name__ == "__main__":
    raise SystemExit(run_script(main))
