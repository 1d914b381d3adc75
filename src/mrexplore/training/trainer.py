"""Training of the learned global layer (``strategy: hier``): the heuristic start, the policy search, DAgger
rounds on the lookahead expert, PPO; and of the NeuralCoMapping baseline (``strategy: ncm``): its untrained
network, then its PPO.

One loop (:func:`train`) runs the stages of :mod:`~mrexplore.training.stages` in order and owns everything
around them: the budget (minutes or episodes), validation on held-out maps with deterministic decoding,
keeping the best stage, the log and the checkpoints; ``resume`` continues after the last finished stage.
The policy kept is the one with the fewest validation steps, never the last by default.
"""

from __future__ import annotations

import csv
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np
import torch

from mrexplore.config import MissionConfig, SimConfig, TrainConfig, config_to_dict
from mrexplore.global_planning.learned.features import GraphInputs
from mrexplore.global_planning.learned.methods import learned_method
from mrexplore.runtime.csv_append import append_row
from mrexplore.runtime.progress import Progress
from mrexplore.runtime.threads import THREADS_ENV
from mrexplore.runtime.workers import JobRunner
from mrexplore.training.checkpoint import code_version, save_policy
from mrexplore.training.curve import plot_learning_curve
from mrexplore.training.episodes import (
    FRESH_SEED0,
    VAL_SEED0,
    EpisodeJob,
    JobKind,
    init_worker,
    new_net,
    policy_net,
    run_job,
    weights_of,
)
from mrexplore.training.expert import ExpertLabel
from mrexplore.training.run_folder import RunFolder
from mrexplore.training.search import relative_score
from mrexplore.training.stages import StageContext, TrainState, stages_of
from mrexplore.training.twins import torch_twin
from mrexplore.training.updates import optimizer
from mrexplore.types import MrExploreError

__all__ = ["train", "validate_policy", "TrainResult", "split_maps", "LOG_COLUMNS", "FRESH_SEED0"]

LOG_COLUMNS = [
    "time_s", "stage", "episodes", "decisions", "labels", "loss", "expert_agreement", "expert_gain", "kl",
    "clip_fraction", "entropy", "value_loss", "return_mean", "steps_mean", "coverage_mean", "val_steps_mean",
    "val_coverage_mean", "val_score", "val_sampled_steps_mean", "val_sampled_coverage_mean", "decisions_per_s",
    "search_best_steps", "edge_weights",
]  # fmt: skip
_STAGE_COLUMNS = (
    "stage", "episodes", "labels", "expert_gain", "expert_agreement", "val_steps_mean", "val_coverage_mean",
    "val_score", "val_sampled_steps_mean", "val_sampled_coverage_mean", "edge_weights", "time_s",
)  # fmt: skip
"""The columns of ``stages.csv`` (the sampled and score ones only where the run has them), then ``kept``: 1 on
the stage whose policy the run kept (``baseline``: no trained stage beat the untrained start)."""
VALIDATION_MARGIN = 1.1
"""A stage's training stops this many validations' time before the deadline."""


def split_maps(train_dir: Path | None, val_maps: int, plans: str = "varied") -> tuple[list[str], list[str]]:
    """Training and validation map specs: training DungeonMaps (the last ones by name held out) and
    procedural floor plans (``PLANS:SEED``, ``plans`` being ``varied`` or ``generated``; validation seeds
    from 1,000,000). Half the validation maps are DungeonMaps where the folder exists."""
    dungeons: list[str] = []
    if train_dir is not None and train_dir.is_dir():
        dungeons = sorted(str(p) for p in train_dir.rglob("*.png"))
    n_dungeon_val = min(len(dungeons) // 10, val_maps // 2) if dungeons else 0
    val = dungeons[len(dungeons) - n_dungeon_val :] if n_dungeon_val else []
    val += [f"{plans}:{VAL_SEED0 + i}" for i in range(val_maps - len(val))]
    return dungeons[: len(dungeons) - n_dungeon_val], val


class _Runner(JobRunner[EpisodeJob, dict[str, Any]]):
    """The trainer's episodes in local workers or Ray tasks (one thread each), handed back in the jobs' order."""

    def __init__(self, workers: int, ray_address: str | None) -> None:
        super().__init__(run_job, workers, ray_address, init_worker, (), {THREADS_ENV: "1", "OMP_NUM_THREADS": "1"})
        self.on_result: Callable[[], None] | None = None
        """Called as each episode ends (the progress lines between stages)."""

    def results(self, jobs: Sequence[EpisodeJob], deadline: float) -> list[dict[str, Any]]:
        """Results of the ``jobs`` that ran, in the jobs' order (jobs not started by ``deadline`` are dropped)."""
        out = []
        for r in self.run(jobs, deadline):
            out.append(r)
            if self.on_result is not None:
                self.on_result()
        return sorted(out, key=lambda r: int(r["index"]))


@dataclass(frozen=True)
class TrainResult:
    """Where a run left its policy and what each stage measured on the validation maps."""

    policy_path: Path
    best_stage: str
    stages: list[dict[str, Any]]


def _labels_to_blob(labels: Sequence[ExpertLabel]) -> list[dict[str, torch.Tensor]]:
    t = torch.from_numpy
    return [
        {
            "robots": t(lab.inputs.robots),
            "clusters": t(lab.inputs.clusters),
            "edges": t(lab.inputs.edges),
            "reachable": t(lab.inputs.reachable),
            "base": t(lab.inputs.base),
            "candidates": t(lab.candidates),
            "returns": t(lab.returns),
        }  # fmt: skip
        for lab in labels
    ]


def _labels_from_blob(blob: Sequence[dict[str, torch.Tensor]]) -> list[ExpertLabel]:
    return [
        ExpertLabel(
            GraphInputs(
                d["robots"].numpy(),
                d["clusters"].numpy(),
                d["edges"].numpy(),
                d["reachable"].numpy(),
                d["base"].numpy(),
            ),
            d["candidates"].numpy(),
            d["returns"].numpy(),
        )
        for d in blob
    ]


class _Log:
    """CSV log (always) and TensorBoard (where the optional extra is installed)."""

    def __init__(self, run: RunFolder, keep: int | None = None) -> None:
        """``keep``: rows a resumed run keeps (those of the stages it saved); a cut last line goes too."""
        out = run.out
        self.path = run.log_path(keep)
        self.rows = max(0, len(self.path.read_bytes().splitlines()) - 1) if self.path.exists() else 0
        try:
            from torch.utils.tensorboard import SummaryWriter

            self.tb: Any = SummaryWriter(str(out / "tb"))
        except ImportError:
            self.tb = None

    def row(self, values: dict[str, Any], step: int) -> None:
        append_row(self.path, LOG_COLUMNS, values)
        self.rows += 1
        if self.tb is not None:
            for k, v in values.items():
                if isinstance(v, (int, float)) and k != "time_s":
                    self.tb.add_scalar(k, v, step)
            self.tb.flush()


def train(
    cfg: TrainConfig,
    out: Path,
    train_dir: Path | None,
    minutes: float | None = None,
    episodes: int | None = None,
    workers: int = 0,
    ray_address: str | None = None,
    resume: bool = False,
    seed: int = 0,
    progress: bool | None = None,
    say: Callable[[str], None] = lambda s: None,
    sim: SimConfig | None = None,
    mission: MissionConfig | None = None,
    predictor: str | None = None,
) -> TrainResult:
    """Train the learned global layer into ``out`` (``policy.npz``, ``best.npz``, ``state.pt``, ``log.csv``,
    ``stages.csv``, ``curve.png``). ``minutes`` and ``episodes`` bound the run (the later stages are skipped).
    ``sim`` and ``mission`` set the episodes' sensor, motion, replanning and faults (None: defaults);
    ``predictor`` the map predictor of a policy that reads the predicted gain (a file, ``none``; None: the
    shipped one)."""
    env = {"sim": config_to_dict(sim or SimConfig()), "mission": config_to_dict(mission or MissionConfig())}
    env["mission"].pop("baseline_bytes", None)  # rollouts never count them: not a setting here

    def placed(jobs: list[EpisodeJob]) -> list[EpisodeJob]:
        return [replace(j, sim=sim, mission=mission, predictor=predictor) for j in jobs]

    predictor_info = _predictor_info(cfg, predictor)  # a file that cannot be read fails before any work
    if predictor_info is not None:
        env["predictor"] = predictor_info
    run = RunFolder(out, resume, minutes, say)
    torch.manual_seed(seed)
    net = new_net(cfg)
    opt = optimizer(net, cfg)
    rng = np.random.default_rng(seed)
    stages = stages_of(cfg)
    st, data = _restore(run, cfg, env, net, opt, rng, len(stages)) if resume else (TrainState(), [])
    train_maps, val_maps = split_maps(train_dir, cfg.val_maps, cfg.episodes.plans)
    if not train_maps:
        say("no training DungeonMaps found; training on procedural floor plans only")
    log = _Log(run, st.log_rows if resume and st.log_rows >= 0 else None)
    run.start_clock(st.elapsed_s)
    bar = Progress(len(stages), "train", "stages", progress, initial=st.stage)
    bar.limit_s = run.deadline - time.perf_counter() if minutes is not None else None
    with _Runner(workers, ray_address) as runner:
        runner.on_result = _episode_counter(bar, stages, st)

        def budget_left(n: int) -> int:
            return n if episodes is None else max(0, min(n, episodes - st.episodes))

        def validate(weights: bytes | None, kind: JobKind = JobKind.EVAL) -> tuple[float, float, np.ndarray]:
            return _validate_on(runner, placed, cfg, val_maps, weights, kind)

        # The budget is a budget: a stage's training episodes stop early enough for its validation to end
        # by the deadline (as long as the last validation took), and no stage starts that has not that time.
        val_s = 0.0
        train_until = run.deadline
        ctx = StageContext(
            cfg,
            net,
            opt,
            st,
            data,
            rng,
            train_maps,
            lambda jobs: runner.results(placed(jobs), train_until),
            budget_left,
        )
        while st.stage < len(stages):
            stage = stages[st.stage]
            need = stage.min_episodes(cfg)
            if _out_of_budget(run, stage.name, st, need, episodes, val_s):
                break
            train_until = run.deadline - VALIDATION_MARGIN * val_s
            if (left := budget_left(need)) < need:
                # the stage needs more episodes than are left: go on to the stages that fit the budget
                say(f"{left} episodes left, under {stage.unit}'s {need}; skipping {stage.name}")
                st.stage += 1
                bar.update()
                continue
            t0 = time.perf_counter()
            # collect and train
            row: dict[str, Any] = {"stage": stage.name} | stage.learn(ctx)
            # validate (deterministic decoding, held-out maps) and keep the best
            t_val = time.perf_counter()
            chosen_by, cov_key = _validated(row, stage, ctx, validate)
            val_s = time.perf_counter() - t_val
            _keep_if_best(run, row, stage, ctx, chosen_by, cov_key, predictor_info)
            # log
            _log_stage(row, st, log, t0, run.elapsed_s)
            say(f"{stage.name}: validation {_validation_text(row)} ({time.perf_counter() - t0:.0f} s)")
            # checkpoint
            st.stage += 1
            st.elapsed_s = run.elapsed_s
            st.log_rows = log.rows
            _checkpoint(run, cfg, env, net, opt, st, data, rng)
            bar.update()
    bar.close()
    return _finish(run, cfg, st)


def _predictor_info(cfg: TrainConfig, predictor: str | None) -> dict[str, str] | None:
    """What the run's record says of the map predictor of a policy that reads one; None for the others."""
    if not learned_method(cfg.strategy).reads_prediction(cfg.learned):
        return None
    from mrexplore.pipeline.strategies import loaded_predictor

    return loaded_predictor(predictor)[1]


def _episode_counter(bar: Progress, stages: Sequence[Any], st: TrainState) -> Callable[[], None]:
    """What the runner calls as each episode ends: the progress line names the stage and counts episodes."""
    ended = [0]

    def episode_ended() -> None:
        ended[0] += 1
        bar.detail = f"{stages[min(st.stage, len(stages) - 1)].name}, {ended[0]} episodes"
        bar.set(bar.n)

    return episode_ended


def _validate_on(
    runner: _Runner,
    placed: Callable[[list[EpisodeJob]], list[EpisodeJob]],
    cfg: TrainConfig,
    val_maps: list[str],
    weights: bytes | None,
    kind: JobKind,
) -> tuple[float, float, np.ndarray]:
    """Mean steps and coverage, and the steps to the end and to 99% per map (2 x maps, in order)."""
    jobs = [EpisodeJob(kind, m, cfg.val_robots, i, weights, cfg, i) for i, m in enumerate(val_maps)]
    res = runner.results(placed(jobs), math.inf)  # a validation always ends: the budget leaves room
    per_map = np.array([[r["steps"] for r in res], [r["steps_99"] for r in res]], dtype=np.float64)
    return float(per_map[0].mean()), float(np.mean([r["coverage"] for r in res])), per_map


def _out_of_budget(run: RunFolder, name: str, st: TrainState, need: int, episodes: int | None, val_s: float) -> bool:
    """Whether the run stops before stage ``name``: its time or episodes spent, or too little time left for
    a validation (as long as the last one took); says why."""
    now = time.perf_counter()
    if now > run.deadline or (need > 0 and episodes is not None and st.episodes >= episodes):
        run.say(f"budget spent before stage {name}; stopping")
        return True
    if st.stage > 0 and now + VALIDATION_MARGIN * val_s > run.deadline:
        run.say(f"{run.deadline - now:.0f} s left, under a validation's {val_s:.0f} s; stopping before {name}")
        return True
    return False


def _validated(
    row: dict[str, Any],
    stage: Any,
    ctx: StageContext,
    validate: Callable[..., tuple[float, float, np.ndarray]],
) -> tuple[str, str]:
    """Validate the stage's weights into ``row``; the keys that choose the stage kept (a score, and the
    coverage it must not lose)."""
    cfg, st = ctx.cfg, ctx.state
    weights = stage.validation_weights(ctx)
    row["val_steps_mean"], row["val_coverage_mean"], per_map = validate(weights)
    chosen_by = "val_steps_mean"
    if cfg.score == "relative":  # against the yardstick stage (the heuristic for hier), map by map
        if stage.yardstick:
            st.val_ref = per_map.tolist()
        ref = np.asarray(st.val_ref)
        row["val_score"] = float(relative_score(per_map[0], per_map[1], ref[0], ref[1]))
        chosen_by = "val_score"
    cov_key = "val_coverage_mean"
    if learned_method(cfg.strategy).validates_sampled:  # NCM's own evaluation samples: validate it too (seeded)
        steps_s, cov_s, _ = validate(weights, JobKind.EVAL_SAMPLED)
        row["val_sampled_steps_mean"], row["val_sampled_coverage_mean"] = steps_s, cov_s
        if cfg.ncm.select == "sampled":
            chosen_by, cov_key = "val_sampled_steps_mean", "val_sampled_coverage_mean"
    return chosen_by, cov_key


def _keep_if_best(
    run: RunFolder,
    row: dict[str, Any],
    stage: Any,
    ctx: StageContext,
    chosen_by: str,
    cov_key: str,
    predictor_info: dict[str, str] | None,
) -> None:
    """Write ``best.npz`` where the stage is the yardstick or beats the best so far (fewest validation steps,
    or the best score) at no less coverage than the yardstick."""
    st = ctx.state
    if not (stage.yardstick or (row[chosen_by] < st.best_val and row[cov_key] >= st.stage_rows[0][cov_key] - 0.005)):
        return
    st.best_val, st.best_stage = row[chosen_by], stage.name
    meta = {k: row[k] for k in row if k.startswith("val_")}
    save_policy(
        run.out / "best.npz",
        policy_net(ctx.net),
        {
            "stage": stage.name,
            **meta,
            "chosen_by": chosen_by,
            "train_config": config_to_dict(ctx.cfg),
            **({"predictor": predictor_info} if predictor_info else {}),
        },
    )


def _log_stage(row: dict[str, Any], st: TrainState, log: _Log, t0: float, elapsed_s: float) -> None:
    """The stage's row in ``log.csv`` and in the state's stage rows (``stages.csv``)."""
    took = time.perf_counter() - t0
    row["time_s"] = round(elapsed_s, 1)
    row["episodes"] = st.episodes
    if row.get("decisions"):
        row["decisions_per_s"] = round(row["decisions"] / took, 2)
    st.stage_rows.append(
        {k: row.get(k) for k in _STAGE_COLUMNS if k in row or not k.startswith(("val_sampled", "val_score"))}
    )
    log.row(row, st.stage)


def _finish(run: RunFolder, cfg: TrainConfig, st: TrainState) -> TrainResult:
    """The kept stage's weights as ``policy.npz``, the learning curve and ``stages.csv``."""
    policy = run.keep_best("policy.npz", "no stage finished within the budget; give more --minutes")
    plot_learning_curve(run.out / "log.csv", run.out / "curve.png", cfg.strategy, st.best_stage)
    rows = [r | {"kept": int(r["stage"] == st.best_stage)} for r in st.stage_rows]
    with open(run.out / "stages.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    return TrainResult(policy, st.best_stage, st.stage_rows)


def _checkpoint(
    run: RunFolder,
    cfg: TrainConfig,
    env: dict[str, Any],
    net: torch.nn.Module,
    opt: torch.optim.Optimizer,
    st: TrainState,
    data: Sequence[ExpertLabel],
    rng: np.random.Generator,
) -> None:
    """Everything a resume needs, written atomically."""
    blob = {
        "config": config_to_dict(cfg), "env": env, "net": net.state_dict(), "opt": opt.state_dict(),
        "state": st.__dict__, "data": _labels_to_blob(data), "rng": rng.bit_generator.state,
        "code_version": code_version(),
    }  # fmt: skip
    run.save_state(blob)


def _restore(
    run: RunFolder,
    cfg: TrainConfig,
    env: dict[str, Any],
    net: torch.nn.Module,
    opt: torch.optim.Optimizer,
    rng: np.random.Generator,
    n_stages: int,
) -> tuple[TrainState, list[ExpertLabel]]:
    """Loads the run saved in ``run`` into ``net``, ``opt`` and ``rng``; its state and expert labels."""
    blob = run.load_state()
    if blob["config"] != config_to_dict(cfg) or blob.get("env", env) != env:
        raise MrExploreError(
            f"{run.out} was trained with another config; resume with the same --config, or a new --out"
        )
    net.load_state_dict(blob["net"])
    opt.load_state_dict(blob["opt"])
    rng.bit_generator.state = blob["rng"]
    st = TrainState(**blob["state"])
    done = f"{st.episodes} episodes, {st.elapsed_s / 60:.1f} min so far"
    run.say(f"resuming {run.out} at stage {st.stage} of {n_stages} ({done})")
    return st, _labels_from_blob(blob["data"])


def _validation_text(row: dict[str, Any]) -> str:
    val = f"{row['val_steps_mean']:.1f} steps, coverage {row['val_coverage_mean']:.4f}"
    if "val_score" in row:
        val += f", score {row['val_score']:.4f} (the heuristic's: 1)"
    if "val_sampled_steps_mean" in row:
        val += f"; sampled {row['val_sampled_steps_mean']:.1f} steps, {row['val_sampled_coverage_mean']:.4f}"
    return val


def validate_policy(
    policy: Path | None, cfg: TrainConfig, train_dir: Path | None, workers: int = 0, maps: list[str] | None = None
) -> tuple[list[str], np.ndarray, np.ndarray]:
    """A policy file on ``cfg``'s validation maps (or on ``maps``), to compare runs on one set: the maps,
    in order, then ``(2, maps)`` steps to the end and to 99% coverage (all its steps where an episode never
    got there), and each map's final coverage. ``policy`` None: the heuristic, hier-heuristic (for
    ``cfg.strategy`` ncm, the shipped NCM policy)."""
    weights = None
    if policy is not None or not learned_method(cfg.strategy).starts_from_heuristic:
        twin = torch_twin(cfg.strategy)
        weights = weights_of(twin.as_trained(twin.load(policy).net))
    val_maps = maps if maps is not None else split_maps(train_dir, cfg.val_maps, cfg.episodes.plans)[1]
    with _Runner(workers, None) as runner:
        jobs = [EpisodeJob(JobKind.EVAL, m, cfg.val_robots, i, weights, cfg, i) for i, m in enumerate(val_maps)]
        res = runner.results(jobs, math.inf)
    steps = np.array([[r["steps"] for r in res], [r["steps_99"] for r in res]], dtype=np.float64)
    return val_maps, steps, np.array([r["coverage"] for r in res], dtype=np.float64)
