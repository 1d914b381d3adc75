"""A robot's on-board work a round, part by part, late in one mission, and how its seeds were found.

    python perf/onboard_parts.py --map ../shared/maps/ros/willow-2010-02-18-0.10.yaml --strategy nearest

Runs one mission (0.05 m, seed 0) untimed to step ``--from``, then times the next ``--rounds`` rounds:
each robot's grid update, its seeds, the message built from them, and the encoding of the message it sends
in the default delta mode (the delta, compared where the grid changed, or the full message where that is
shorter; at checkouts before 2026-12-03 the robot encoded both every round, timed together). Prints each
part's median, p95 and maximum in ms per robot and round, and how the seeds came: the one-piece shortcut,
the pieces kept (no free cell lost, or some lost), or a whole fill (plain, or labelling the pieces).
"""

from __future__ import annotations

import argparse
from collections import Counter, defaultdict
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
from decision_split import timed

import mrexplore.preprocessing.onboard as onboard
import mrexplore.preprocessing.transmission as transmission
from mrexplore.cli import run_script
from mrexplore.config import MapConfig, MissionConfig, SimConfig
from mrexplore.maps.loaders import load_map
from mrexplore.mission import Mission
from mrexplore.strategies import make_strategy


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--map", type=Path, required=True)
    ap.add_argument("--strategy", default="nearest")
    ap.add_argument("--robots", type=int, default=3)
    ap.add_argument("--from", dest="start", type=int, default=11_000, help="untimed up to this step")
    ap.add_argument("--rounds", type=int, default=150)
    args = ap.parse_args()
    truth = load_map(args.map, MapConfig(resolution_m=0.05))
    m = Mission(truth, make_strategy(args.strategy), SimConfig(robots=args.robots), MissionConfig(100_000), 0)
    while m.steps < args.start and m.advance():
        m.decide()
    spent: dict[str, list[float]] = defaultdict(list)
    how: Counter[str] = Counter()

    def timed_as(owner: Any, name: str, label: str) -> None:
        setattr(owner, name, timed(getattr(owner, name), spent[label]))

    def counted(name: str, outcome: Callable[[Any], str]) -> None:
        fn = getattr(onboard, name, None)
        if fn is None:  # an older checkout
            return

        def wrapper(*a: Any) -> Any:
            v = fn(*a)
            how[outcome(v)] += 1
            return v

        setattr(onboard, name, wrapper)

    counted("joined_in_box", lambda v: "one piece kept" if v else "one piece: not joined")
    counted("joined_to_label", lambda v: "pieces kept, none lost" if v else "pieces: not joined")
    counted("kept_in_label", lambda v: "pieces kept, cells lost" if v else "pieces: lost cells not kept")
    counted("pick_seeds", lambda v: "whole fill")
    counted("pick_seeds_labelled", lambda v: "whole fill, labelled")
    timed_as(onboard.OnBoardGrid, "update", "grid update")
    timed_as(onboard.OnBoardGrid, "seeds", "seeds")
    timed_as(transmission, "coded_frontier_map", "message")
    outgoing = getattr(transmission, "Outgoing", None)
    if outgoing is None:  # before 2026-12-03 the robot encoded both messages every round
        timed_as(transmission.RobotSender, "_both", "encoding (full and delta)")
    else:  # the message sent, encoded on board; the accounting encodes the other one, and asks again
        encode_sent = timed(outgoing.incremental, spent["encoding (the one sent)"])
        ask_again = outgoing.incremental

        def incremental(self: Any) -> bytes:
            return (encode_sent if self._incremental is None else ask_again)(self)

        outgoing.incremental = incremental
    first = len(m.onboard_ms)
    for _ in range(args.rounds):
        if not m.advance():
            break
        m.decide()
    work = np.asarray(m.onboard_ms[first:])
    who = f"{truth.name}, {args.strategy}, {args.robots} robots"
    print(f"{who}: steps {args.start}-{m.steps}, {len(work)} robot rounds")
    print(f"{'part':28s} {'median':>8s} {'p95':>8s} {'max':>8s}")
    parts = {"on board, all": list(work), **{k: [1e3 * t for t in v] for k, v in spent.items()}}
    for label, ms in parts.items():
        a = np.asarray(ms)
        print(f"{label:28s} {np.median(a):8.2f} {np.percentile(a, 95):8.2f} {a.max():8.2f}")
    for outcome, n in sorted(how.items()):
        print(f"seeds: {outcome}: {n}")
    return 0


if __name__ == "__main__":
    raise SystemExit(run_script(main))
