"""Record a mission's near/far distance calls late on a floor, then time any version of them on the same calls.

    python perf/replay_far_fields.py record --map ../shared/maps/kth_floorplans/50010535_PLAN2.yaml \
        --robots 8 --from-coverage 0.5 --calls 6 --out plan2.pkl
    python perf/replay_far_fields.py replay plan2.pkl              # this checkout
    PYTHONPATH=/tmp/before/src python perf/replay_far_fields.py replay plan2.pkl   # another one

``record`` runs one `hier` mission (0.05 m, seed 0) untimed until the team's coverage reaches
``--from-coverage``, then keeps the arguments of the next ``--calls`` calls of ``far_fields`` (the robots'
distances at a decision on a large floor): the passable grid, the robots, the cluster centres, the robots'
own goals. ``replay`` runs each kept call through the ``far_fields`` of whatever checkout it imports, once
untimed (it may compile numba's caches), then ``--repeats`` times, and prints the least of those runs'
milliseconds per call (the least disturbed: timings here swing by a fifth from run to run; since the
portal graph, a call's time counts pooling the blocks too, about 3 ms, which earlier figures left out)
and how many exact searches and near/far fields it made (``--save``: also the robots' distances at the
centres, for ``diff A.npz B.npz`` to say where two versions' differ; ``--factor F``: pool blocks of F
cells instead of the recorded size, ``--factor 1`` giving exact distances; ``--portals``: search far
distances on a portal graph kept from call to call, as a mission does, each call's time counting the
graph brought up to date from the previous call's). Versions compared this way see the same calls,
which whole missions do not once they part. The recording is a pickle of numpy arrays; read only files you made.
"""

from __future__ import annotations

import argparse
import copy
import pickle
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

import mrexplore.paths.far_field as far_field
import mrexplore.strategies as strategies
from mrexplore.cli import run_script
from mrexplore.config import GlobalPlanningConfig, MapConfig, MissionConfig, SimConfig
from mrexplore.maps.loaders import load_map
from mrexplore.mission import Mission


def _record(args: argparse.Namespace) -> None:
    truth = load_map(args.map, MapConfig(resolution_m=0.05))
    sim = SimConfig(robots=args.robots)
    mission = Mission(truth, strategies.make_strategy("hier"), sim, MissionConfig(100_000), 0, progress=False)
    while mission.advance():
        mission.decide()
        if mission.curve[-1] >= args.from_coverage:
            break
    calls: list[dict[str, Any]] = []
    original = strategies.far_fields

    def keep(passable: np.ndarray, sources: np.ndarray, radius: int, factor: int, *rest: Any) -> Any:
        must, own = (list(rest) + [None, None])[:2]
        calls.append(
            {
                "passable": np.packbits(passable),
                "shape": passable.shape,
                "sources": np.asarray(sources),
                "radius": radius,
                "factor": factor,
                "must": None if must is None else np.asarray(must),
                "own": None if own is None else [np.asarray(o) for o in own],
            }
        )
        return original(passable, sources, radius, factor, *rest)

    strategies.far_fields = keep  # type: ignore[assignment]
    while len(calls) < args.calls and mission.advance():
        mission.decide()
    strategies.far_fields = original
    with open(args.out, "wb") as f:
        pickle.dump(calls, f)
    print(f"{len(calls)} calls from step {mission.steps} to {args.out}")


def _replay(args: argparse.Namespace) -> None:
    with open(args.calls, "rb") as f:
        calls = pickle.load(f)  # noqa: S301 - a recording this script made
    counts: dict[str, int] = {}

    def counted(name: str, fn: Callable[..., Any]) -> Callable[..., Any]:
        def wrapper(*a: Any, **k: Any) -> Any:
            counts[name] = counts.get(name, 0) + 1
            return fn(*a, **k)

        return wrapper

    far_field.CoarseGrid.exact_at = counted("exact searches", far_field.CoarseGrid.exact_at)  # type: ignore[method-assign]
    far_field._one = counted("near/far fields", far_field._one)
    print(f"far_fields from {far_field.__file__}")
    read: list[np.ndarray] = []
    graph: Any = None
    for c in calls:
        h, w = c["shape"]
        passable = np.unpackbits(c["passable"])[: h * w].reshape(h, w).astype(bool)
        factor = args.factor or c["factor"]
        if args.portals and graph is None:  # the blocks' graph and the finer blocks' one, as a mission keeps
            from mrexplore.paths.portals import PortalGraph

            cfg = GlobalPlanningConfig()
            graph = [
                PortalGraph((-(-h // side), -(-w // side)), cfg.portal_sector_blocks, cfg.portal_spacing_blocks)
                for side in (factor, far_field.finer_side(factor))
                if side is not None
            ]
        before = copy.deepcopy(graph)  # each run brings the graphs from the previous call's state
        times = []
        for _ in range(1 + args.repeats):  # the first run may compile and is not timed
            kept = copy.deepcopy(before)
            counts.clear()
            t = time.perf_counter()
            grid = far_field.coarse_grid(passable, factor, *(kept if args.portals else []))
            fields = far_field.far_fields(passable, c["sources"], c["radius"], factor, c["must"], c["own"], grid)
            times.append(1e3 * (time.perf_counter() - t))
        graph = kept
        if args.save is not None:
            read.append(np.stack([f.at(c["must"]) for f in fields]))
        ms = min(times[1:])  # the least disturbed run: this machine's timings swing by a fifth
        made = ", ".join(f"{n} {k}" for k, n in sorted(counts.items()))
        print(f"{ms:8.1f} ms  ({len(c['sources'])} robots, {len(c['must'])} centres; {made})")
    if args.save is not None:
        np.savez(args.save, *read)


def _diff(args: argparse.Namespace) -> None:
    """Where two replays' robot-centre distances differ, call by call."""
    a, b = np.load(args.a), np.load(args.b)
    for key in a.files:
        x, y = a[key], b[key]
        moved = x != y
        rel = np.abs(y[moved] - x[moved]) / x[moved] if moved.any() else np.zeros(1)
        mean = float(np.mean(y[moved] - x[moved])) if moved.any() else 0.0
        print(f"{int(moved.sum())} of {x.size} differ, by at most {100 * rel.max():.1f}%, {mean:+.2f} cells on average")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = ap.add_subparsers(dest="what", required=True)
    rec = sub.add_parser("record")
    rec.add_argument("--map", type=Path, required=True)
    rec.add_argument("--robots", type=int, default=8)
    rec.add_argument("--from-coverage", type=float, default=0.5)
    rec.add_argument("--calls", type=int, default=6)
    rec.add_argument("--out", type=Path, required=True)
    rep = sub.add_parser("replay")
    rep.add_argument("calls", type=Path)
    rep.add_argument("--repeats", type=int, default=3, help="timed runs per call; the least is printed")
    rep.add_argument("--save", type=Path, default=None, help="the robots' distances at the centres (.npz)")
    rep.add_argument("--factor", type=int, default=None, help="pool blocks of this many cells a side instead")
    rep.add_argument("--portals", action="store_true", help="far distances on a portal graph kept from call to call")
    dif = sub.add_parser("diff")
    dif.add_argument("a", type=Path)
    dif.add_argument("b", type=Path)
    args = ap.parse_args()
    {"record": _record, "replay": _replay, "diff": _diff}[args.what](args)
    return 0


if __name__ == "__main__":
    raise SystemExit(run_script(main))
