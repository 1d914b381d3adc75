"""What the benchmarks share: the example maps (``mrexplore.runtime.example_maps``: ``$MREXPLORE_MAPS`` or
../shared/maps), the largest HouseExpo map, timed missions, and one way to end a script on bad input.

Run a benchmark from the repository root: ``python benchmarks/NAME.py --help``.
"""

from __future__ import annotations

import csv
import sys
from collections.abc import Callable
from pathlib import Path

import numpy as np

from mrexplore.config import MapConfig, MissionConfig, SimConfig
from mrexplore.maps.loaders import load_map
from mrexplore.mission import Mission, MissionSpec
from mrexplore.pipeline import make_strategy
from mrexplore.runtime.example_maps import maps_dir
from mrexplore.runtime.timing import PhaseTimes
from mrexplore.types import MrExploreError

EXIT_BAD_INPUT = 2
EXIT_INTERRUPTED = 130


def run_script(script_main: Callable[[], int | None], name: str | None = None) -> int:
    """Run a benchmark's ``main`` as the ``mrexplore`` command runs: bad input is one line naming the
    problem and the fix with exit code 2, an interrupt exit code 130, no traceback."""
    name = name or Path(sys.argv[0]).name
    try:
        return int(script_main() or 0)
    except MrExploreError as exc:
        print(f"{name}: error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:
        print(f"{name}: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED


def houseexpo_dir() -> Path:
    return maps_dir() / "houseexpo"


def largest_houseexpo() -> Path:
    """The HouseExpo dev map with the most cells at 0.05 m (from its ``index.csv``)."""
    with open(houseexpo_dir() / "index.csv") as f:
        rows = list(csv.DictReader(f))
    best = max(rows, key=lambda r: np.prod([int(v) for v in r["cells_at_0.05m"].split("x")]))
    return houseexpo_dir() / best["file"]


def skip(what: str, where: Path) -> int:
    """Say that the maps a benchmark needs are absent (set ``MREXPLORE_MAPS``), and end without failing."""
    print(f"skipped: {what} not found at {where}; set MREXPLORE_MAPS to the example maps' folder", file=sys.stderr)
    return 0


def time_mission(
    map_path: Path,
    robots: int,
    steps: int,
    strategy: str,
    resolution_m: float = 0.05,
    from_coverage: float | None = None,
) -> dict[str, float]:
    """Median and p95 milliseconds of the simulation steps and of the centre's decisions over ``steps``
    steps of one mission (a decision at least every 10 steps, close to missions' rate), after running it
    untimed to ``from_coverage`` where given; a robot's on-board work and the byte accounting apart."""
    truth = load_map(map_path, MapConfig(resolution_m=resolution_m))
    budget = steps if from_coverage is None else 100_000
    pipeline = make_strategy(strategy)
    m = Mission(MissionSpec(truth, pipeline, SimConfig(robots=robots), MissionConfig(budget, 10), 0), progress=False)
    if from_coverage is not None:
        while m.sim.coverage < from_coverage and m.advance():
            m.decide()
    first_step, first_decision = m.steps, len(m.record.plan_ms)
    pipeline.timer = times = PhaseTimes()
    robot_ms: list[float] = []
    accounting_ms: list[float] = []
    while m.steps - first_step < steps and m.advance():
        m.decide()
        robot_ms.append(m.link.robot_ms / robots)
        accounting_ms.append(m.link.accounting_ms / robots)
    plan_ms = m.record.plan_ms[first_decision:]
    step_ms = times.ms["step"]
    return {
        "cells": truth.shape[0] * truth.shape[1],
        "coverage": m.sim.coverage,
        "step_ms_median": float(np.median(step_ms)),
        "step_ms_p95": float(np.percentile(step_ms, 95)),
        "decision_ms_median": float(np.median(plan_ms)),
        "decision_ms_p95": float(np.percentile(plan_ms, 95)),
        "robot_ms_median": float(np.median(robot_ms)),
        "robot_ms_p95": float(np.percentile(robot_ms, 95)),
        "accounting_ms_median": float(np.median(accounting_ms)),
    }
