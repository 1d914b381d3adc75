"""``mrexplore train``: the learned global layer (hier's search, imitation and PPO; NeuralCoMapping's PPO), or
the map predictor."""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path
from typing import Any

from mrexplore.cli.common import SEED, WORKERS, add_progress, check_output, need_torch
from mrexplore.cli.settings_flags import Alias, add_settings_flags, alias_given, run_config
from mrexplore.config import TRAINABLE, RunConfig
from mrexplore.runtime.example_maps import maps_dir
from mrexplore.runtime.kernel_cache import say_if_compiling
from mrexplore.types import MrExploreError

__all__ = ["add_train", "run_train", "train_maps"]

TRAIN_METHOD = (
    "train the learned global layer: hier by a cross-entropy search over its edge weights, then imitation of "
    "a lookahead expert (DAgger), PPO optional; ncm (NeuralCoMapping) by PPO"
)
TARGETS = ("policy", "predictor")
"""What ``train --target`` trains: a learned global layer's policy, or the map predictor."""


def train_maps(given: str | None) -> Path | None:
    """The training maps' folder: the one given, else ``train/`` of the example maps; None where absent."""
    folder = Path(given) if given is not None else maps_dir() / "train"
    return folder if folder.is_dir() else None


def add_train(sub: Any) -> None:
    tr = sub.add_parser("train", help=TRAIN_METHOD)
    tr.add_argument("--out", required=True, help="folder for policy.npz, checkpoints, log.csv and stages.csv")
    tr.add_argument(
        "--target",
        choices=TARGETS,
        default="policy",
        help="policy (default): the learned global layer of train.strategy (policy.npz, checkpoints, log.csv, "
        "stages.csv, curve.png); predictor: the map predictor (predictor.npz, beliefs.npz, checkpoints, log.csv, "
        "curve.png), from beliefs of missions on the training maps, the truth as the label (reads the predictor "
        "and sim sections)",
    )
    tr.add_argument(
        "--predictor",
        default=None,
        metavar="FILE|none",
        help="the map predictor of a policy that reads a prediction (train.learned.use_predicted_gain or "
        "use_predicted_path): a file 'mrexplore train --target predictor' wrote, or none (default: the shipped one)",
    )
    budget = tr.add_mutually_exclusive_group()
    budget.add_argument("--minutes", type=float, default=None, help="stop starting stages after this many minutes")
    budget.add_argument("--episodes", type=int, default=None, help="stop after this many training episodes")
    tr.add_argument("--workers", type=WORKERS, default=None, help="worker processes (default: one per core)")
    tr.add_argument("--ray-address", default=None, help="run episodes as Ray tasks: 'local', 'auto' or HOST:PORT")
    tr.add_argument("--resume", action="store_true", help="continue the run in --out after its last finished stage")
    tr.add_argument("--seed", type=SEED, default=0, help="seed of the run (default 0)")
    tr.add_argument(
        "--train-maps",
        default=None,
        help="folder of training maps (DungeonMaps PNGs; default: train/ of the example maps, --maps-dir); "
        "procedural plans always",
    )
    add_settings_flags(
        tr,
        ("--robot-failure", "--message-loss", "--centre-restart", "--comm-range"),
        "train reads its train, sim and mission sections; --set and the flags override it",
        own={"--strategy": Alias("train.strategy", metavar="|".join(TRAINABLE))},
    )
    add_progress(tr)


def run_train(args: argparse.Namespace) -> str:
    run = run_config(args)
    if args.minutes is not None and not (math.isfinite(args.minutes) and args.minutes > 0):
        raise MrExploreError(f"--minutes must be > 0, got {args.minutes}")
    return {"policy": _train_policy, "predictor": _train_predictor}[args.target](args, run)


def _run_options(args: argparse.Namespace) -> dict[str, Any]:
    """What both trainers take from the command line: the run's folder, training maps, budget, workers,
    resume, seed, progress and where to say what happens."""
    return {
        "out": Path(args.out),
        "train_dir": train_maps(args.train_maps),
        "minutes": args.minutes,
        "workers": args.workers or 0,
        "ray_address": args.ray_address,
        "resume": args.resume,
        "seed": args.seed,
        "progress": args.progress,
        "say": lambda s: print(s, file=sys.stderr),
    }


def _train_policy(args: argparse.Namespace, run: RunConfig) -> str:
    from mrexplore.global_planning.learned.methods import learned_method

    method = learned_method(run.train.strategy)
    if args.predictor is not None and not method.reads_prediction(run.train.learned):
        raise MrExploreError(
            f"--predictor {args.predictor} is for a policy that reads a prediction; set "
            "train.learned.use_predicted_gain or use_predicted_path: true, or give --target predictor to train a "
            "predictor"
        )
    if args.episodes is not None and args.episodes < 1:
        raise MrExploreError(f"--episodes must be >= 1, got {args.episodes}")
    check_output(args.out, "--out", folder=True)
    need_torch()
    say_if_compiling()
    from mrexplore.training.trainer import train

    result = train(
        run.train,
        episodes=args.episodes,
        sim=run.sim,
        mission=run.mission,
        predictor=args.predictor,
        **_run_options(args),
    )
    best = next(r for r in result.stages if r["stage"] == result.best_stage)
    sampled = f", sampled {best['val_sampled_steps_mean']:.1f}" if best.get("val_sampled_steps_mean") else ""
    wrote = f"wrote {result.policy_path} and {result.policy_path.parent / 'stages.csv'}"
    if result.best_stage == "baseline":
        start = method.untrained_start
        return (
            f"kept the baseline, no trained stage beat it on validation ({best['val_steps_mean']:.1f} steps"
            f"{sampled}): the policy is the untrained start ({start}); train longer; {wrote}"
        )
    return f"kept stage {result.best_stage} (validation {best['val_steps_mean']:.1f} steps{sampled}); {wrote}"


def _train_predictor(args: argparse.Namespace, run: RunConfig) -> str:
    given = [f for f, on in (("--strategy", alias_given(args, "--strategy")), ("--episodes", args.episodes is not None),
                             ("--predictor", args.predictor is not None)) if on]  # fmt: skip
    if given:
        raise MrExploreError(
            f"{given[0]} does not apply to --target predictor (it trains on collected beliefs); drop it"
        )
    check_output(args.out, "--out", folder=True)
    need_torch()
    say_if_compiling()
    from mrexplore.training.predictor import train_predictor

    path, best = train_predictor(run.predictor, sim=run.sim, **_run_options(args))
    log = path.parent / "log.csv"
    return f"kept epoch {best['epoch']} (validation loss {best['val_loss']:.4f}); wrote {path} and {log}"
