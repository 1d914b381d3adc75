"""Training of the map predictor (``mrexplore train --target predictor``): beliefs taken at random decisions of
missions on the training maps, the truth as the label, a small U-Net fitted to them on random crops.

One loop (:func:`train_predictor`) with marked stages: collect (training missions, then validation
missions, in workers), then epochs of (train on crops, validate on whole beliefs, keep the best, log,
checkpoint). ``resume`` continues after the last finished epoch; the beliefs collected are kept in
``beliefs.npz`` and never collected twice. The predictor kept is the epoch of least validation loss.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np
import torch

from mrexplore.config import MapConfig, MissionConfig, PredictorTrainConfig, SimConfig, config_to_dict
from mrexplore.maps.loaders import load_map_shared
from mrexplore.mission import Mission, MissionSpec
from mrexplore.pipeline import make_strategy
from mrexplore.prediction.encoding import belief_channels, pool_factor
from mrexplore.prediction.network import PREDICTOR_FORMAT
from mrexplore.prediction.targets import pooled_targets
from mrexplore.runtime.csv_append import append_row
from mrexplore.runtime.progress import Progress
from mrexplore.runtime.threads import THREADS_ENV
from mrexplore.runtime.weights_archive import code_version, write_weights_archive
from mrexplore.runtime.workers import JobRunner
from mrexplore.training.curve import plot_predictor_curve
from mrexplore.training.episodes import VAL_SEED0, init_worker
from mrexplore.training.predictor_net import PredictorUNet
from mrexplore.training.run_folder import RunFolder
from mrexplore.training.trainer import split_maps
from mrexplore.types import MrExploreError

__all__ = [
    "BeliefJob",
    "BeliefSet",
    "collect_beliefs",
    "belief_jobs",
    "masked_bce",
    "free_scores",
    "train_predictor",
    "PREDICTOR_LOG_COLUMNS",
]

PREDICTOR_LOG_COLUMNS = [
    "time_s", "epoch", "beliefs", "loss", "val_loss", "val_accuracy", "val_iou", "crops_per_s",
]  # fmt: skip


@dataclass(frozen=True)
class BeliefJob:
    """One collection mission for a worker."""

    map_spec: str
    robots: int
    seed: int
    cfg: PredictorTrainConfig
    sim: SimConfig | None = None
    index: int = 0


@dataclass
class BeliefSet:
    """Beliefs on the predictor's cells, each its own size: ``x`` ``(3, h, w) float16`` (shares of free,
    occupied, unknown), ``label`` ``(h, w) bool`` (free in truth), ``mask`` ``(h, w) bool`` (counts)."""

    x: list[np.ndarray]
    label: list[np.ndarray]
    mask: list[np.ndarray]

    def __len__(self) -> int:
        return len(self.x)

    def to_arrays(self, prefix: str) -> dict[str, np.ndarray]:
        """Flat arrays for ``np.savez`` (shapes kept apart)."""
        shapes = np.array([m.shape for m in self.mask], np.int64).reshape(-1, 2)
        return {
            f"{prefix}_shapes": shapes,
            f"{prefix}_x": np.concatenate([a.reshape(3, -1) for a in self.x], axis=1) if self.x else np.zeros((3, 0)),
            f"{prefix}_label": np.concatenate([a.ravel() for a in self.label]) if self.x else np.zeros(0, bool),
            f"{prefix}_mask": np.concatenate([a.ravel() for a in self.mask]) if self.x else np.zeros(0, bool),
        }

    @classmethod
    def from_arrays(cls, z: Any, prefix: str) -> BeliefSet:
        """The set :meth:`to_arrays` wrote, from ``np.load``'s archive ``z`` (each array read once: every
        access to an archive member decompresses it anew)."""
        shapes, xs = z[f"{prefix}_shapes"], z[f"{prefix}_x"]
        labels, masks = z[f"{prefix}_label"], z[f"{prefix}_mask"]
        out = cls([], [], [])
        at = 0
        for h, w in shapes:
            n = int(h * w)
            out.x.append(xs[:, at : at + n].reshape(3, h, w))
            out.label.append(labels[at : at + n].reshape(h, w))
            out.mask.append(masks[at : at + n].reshape(h, w))
            at += n
        return out

    def extend(self, other: BeliefSet) -> None:
        self.x += other.x
        self.label += other.label
        self.mask += other.mask


def collect_beliefs(job: BeliefJob) -> dict[str, Any]:
    """The team's belief at ``cfg.moments`` random decisions of one mission (coverage within the range),
    pooled onto the predictor's cells with their labels and masks; plain data for a worker to return."""
    cfg = job.cfg
    truth = load_map_shared(job.map_spec, MapConfig(resolution_m=cfg.episodes.resolution_m))
    sim_cfg = replace(job.sim or SimConfig(), robots=job.robots)
    mission = MissionConfig(max_steps=cfg.episodes.max_steps, baseline_bytes=False)
    states: list[np.ndarray] = []
    last: list[Any] = [None]

    def observe(sim: Any, decision: Any, goals: Any, status: Any) -> None:
        if decision is not None and decision is not last[0]:
            last[0] = decision
            if cfg.min_coverage <= sim.coverage <= cfg.max_coverage:
                states.append(decision.state)

    strategy = make_strategy(cfg.collector)
    Mission(MissionSpec(truth, strategy, sim_cfg, mission, seed=job.seed), observe, progress=False).run()
    rng = np.random.default_rng([job.seed, 3])
    picks = sorted(rng.choice(len(states), size=min(cfg.moments, len(states)), replace=False).tolist())
    factor = pool_factor(cfg.episodes.resolution_m, cfg.cell_m)
    out = BeliefSet([], [], [])
    for i in picks:
        label, mask = pooled_targets(states[i], ~truth.occupied, cfg.episodes.resolution_m, factor, cfg.band_m)
        if mask.any():
            out.x.append(belief_channels(states[i], factor).astype(np.float16))
            out.label.append(label)
            out.mask.append(mask)
    return {"index": job.index, "set": out}


def belief_jobs(
    n: int, maps: Sequence[str], cfg: PredictorTrainConfig, rng: np.random.Generator, sim: SimConfig | None
) -> list[BeliefJob]:
    """``n`` collection missions: a procedural plan (seeds below the validation ones) or one of ``maps``, a
    team size and a seed, all drawn from ``rng``."""
    jobs = []
    for i in range(n):
        if not maps or rng.random() < cfg.episodes.generated_share:
            spec = f"{cfg.episodes.plans}:{int(rng.integers(0, VAL_SEED0))}"
        else:
            spec = maps[int(rng.integers(len(maps)))]
        robots = int(rng.integers(cfg.episodes.robots_min, cfg.episodes.robots_max + 1))
        jobs.append(BeliefJob(spec, robots, int(rng.integers(0, 2**31 - 1)), cfg, sim, i))
    return jobs


def masked_bce(logits: torch.Tensor, label: torch.Tensor, mask: torch.Tensor) -> torch.Tensor:
    """Mean binary cross-entropy of ``logits`` against ``label`` over the cells of ``mask`` (0 for none).

    Examples
    --------
    >>> z = torch.tensor([[0.0, 5.0]]); y = torch.tensor([[1.0, 0.0]]); m = torch.tensor([[True, False]])
    >>> round(float(masked_bce(z, y, m)), 4)  # log 2: only the first cell counts
    0.6931
    """
    n = mask.sum()
    if n == 0:
        return logits.sum() * 0.0
    loss = torch.nn.functional.binary_cross_entropy_with_logits(logits, label, reduction="none")
    return (loss * mask).sum() / n


def free_scores(pred_free: np.ndarray, label: np.ndarray) -> np.ndarray:
    """``(4,)``: cells, cells right, predicted-and-true free, predicted-or-true free (accuracy and IoU pool
    these over beliefs)."""
    return np.array(
        [pred_free.size, (pred_free == label).sum(), (pred_free & label).sum(), (pred_free | label).sum()], np.float64
    )


def _crops(data: BeliefSet, n: int, side: int, rng: np.random.Generator) -> tuple[torch.Tensor, ...]:
    """``n`` crops of ``side`` cells, each around a random counted cell of a random belief (padded like the
    belief: unknown, not counted)."""
    x = np.zeros((n, 3, side, side), np.float32)
    x[:, 2] = 1.0
    y = np.zeros((n, side, side), np.float32)
    m = np.zeros((n, side, side), bool)
    for k in range(n):
        i = int(rng.integers(len(data)))
        rs, cs = np.nonzero(data.mask[i])
        j = int(rng.integers(len(rs)))
        r0 = rs[j] - int(rng.integers(side))
        c0 = cs[j] - int(rng.integers(side))
        h, w = data.mask[i].shape
        a0, a1, b0, b1 = max(r0, 0), min(r0 + side, h), max(c0, 0), min(c0 + side, w)
        x[k, :, a0 - r0 : a1 - r0, b0 - c0 : b1 - c0] = data.x[i][:, a0:a1, b0:b1]
        y[k, a0 - r0 : a1 - r0, b0 - c0 : b1 - c0] = data.label[i][a0:a1, b0:b1]
        m[k, a0 - r0 : a1 - r0, b0 - c0 : b1 - c0] = data.mask[i][a0:a1, b0:b1]
    if rng.random() < 0.5:  # the world has no preferred orientation: mirror half the batches, turn them all
        x, y, m = x[..., ::-1], y[..., ::-1], m[..., ::-1]
    turns = int(rng.integers(4))
    x, y, m = np.rot90(x, turns, (-2, -1)), np.rot90(y, turns, (-2, -1)), np.rot90(m, turns, (-2, -1))
    t = torch.from_numpy
    return t(np.ascontiguousarray(x)), t(np.ascontiguousarray(y)), t(np.ascontiguousarray(m))


def _validate(net: PredictorUNet, data: BeliefSet) -> tuple[float, float, float]:
    """Loss, accuracy and IoU of predicted free space over every counted cell of ``data`` (whole beliefs)."""
    net.eval()
    loss_sum, cells, scores = 0.0, 0, np.zeros(4)
    with torch.no_grad():
        for x, label, mask in zip(data.x, data.label, data.mask, strict=True):
            logits = net(torch.from_numpy(x.astype(np.float32))[None])[0]
            y, m = torch.from_numpy(label.astype(np.float32)), torch.from_numpy(mask)
            n = int(mask.sum())
            loss_sum += float(masked_bce(logits, y, m)) * n
            cells += n
            scores += free_scores((logits.numpy() > 0)[mask], label[mask])
    net.train()
    return loss_sum / max(cells, 1), scores[1] / max(scores[0], 1), scores[2] / max(scores[3], 1)


def _save(path: Path, net: PredictorUNet, cfg: PredictorTrainConfig, meta: dict[str, Any]) -> None:
    header = {
        "format": PREDICTOR_FORMAT, "width": cfg.width, "cell_m": cfg.cell_m, "meta": meta,
        "train_config": config_to_dict(cfg),
    }  # fmt: skip
    write_weights_archive(path, header, net.state_dict())


@dataclass
class _State:
    epoch: int = 0
    elapsed_s: float = 0.0
    best_loss: float = math.inf
    best_epoch: int = -1
    log_rows: int = 0


def train_predictor(
    cfg: PredictorTrainConfig,
    out: Path,
    train_dir: Path | None,
    minutes: float | None = None,
    workers: int = 0,
    ray_address: str | None = None,
    resume: bool = False,
    seed: int = 0,
    progress: bool | None = None,
    say: Callable[[str], None] = lambda s: None,
    sim: SimConfig | None = None,
) -> tuple[Path, dict[str, Any]]:
    """Train the map predictor into ``out`` (``predictor.npz``, ``best.npz``, ``beliefs.npz``, ``state.pt``,
    ``log.csv``, ``curve.png``); returns the predictor's path, the kept epoch and its validation loss."""
    run = RunFolder(out, resume, minutes, say)
    env = {"config": config_to_dict(cfg), "sim": config_to_dict(sim or SimConfig()), "seed": seed}
    torch.manual_seed(seed)
    net = PredictorUNet(cfg.width)
    opt = torch.optim.Adam(net.parameters(), lr=cfg.lr, weight_decay=cfg.weight_decay)
    rng = np.random.default_rng(seed)
    st = _State()
    if resume:
        blob = run.load_state()
        if blob["env"] != env:
            raise MrExploreError(
                f"{run.out} was trained with another config; resume with the same --config and --seed, or a new --out"
            )
        net.load_state_dict(blob["net"])
        opt.load_state_dict(blob["opt"])
        rng.bit_generator.state = blob["rng"]
        st = _State(**blob["state"])
        say(f"resuming {run.out} after epoch {st.epoch} ({st.elapsed_s / 60:.1f} min so far)")
    log_path = run.log_path(st.log_rows if resume else None)
    run.start_clock(st.elapsed_s)
    # collect: beliefs of training and validation missions (once; a resumed run reads them back)
    train_set, val_set = _beliefs(run, cfg, train_dir, seed, sim, workers, ray_address, progress)
    bar = Progress(cfg.epochs, "train predictor", "epochs", progress, initial=st.epoch)
    epoch_s = 0.0
    while st.epoch < cfg.epochs:
        now = time.perf_counter()
        if st.epoch > 0 and now + epoch_s > run.deadline:
            say(f"{run.deadline - now:.0f} s left, under an epoch's {epoch_s:.0f} s; stopping after epoch {st.epoch}")
            break
        t0 = time.perf_counter()
        # train: fresh random crops each step
        losses = _train_epoch(net, opt, cfg, train_set, rng)
        crops_per_s = cfg.steps_per_epoch * cfg.batch / (time.perf_counter() - t0)
        # validate: whole held-out beliefs
        val_loss, val_acc, val_iou = _validate(net, val_set)
        st.epoch += 1
        # keep the best
        if val_loss < st.best_loss:
            st.best_loss, st.best_epoch = val_loss, st.epoch
            meta = {"epoch": st.epoch, "val_loss": val_loss, "val_accuracy": val_acc, "val_iou": val_iou}
            _save(run.out / "best.npz", net, cfg, meta)
        # log
        row: dict[str, Any] = {
            "time_s": round(run.elapsed_s, 1), "epoch": st.epoch, "beliefs": len(train_set),
            "loss": float(np.mean(losses)), "val_loss": val_loss, "val_accuracy": val_acc, "val_iou": val_iou,
            "crops_per_s": round(crops_per_s, 1),
        }  # fmt: skip
        append_row(log_path, PREDICTOR_LOG_COLUMNS, row)
        st.log_rows += 1
        bar.detail = f"validation loss {val_loss:.4f}, accuracy {val_acc:.3f}, IoU {val_iou:.3f}"
        bar.update()
        # checkpoint
        st.elapsed_s = run.elapsed_s
        run.save_state(
            {
                "env": env,
                "net": net.state_dict(),
                "opt": opt.state_dict(),
                "rng": rng.bit_generator.state,
                "state": st.__dict__,
                "code_version": code_version(),
            }  # fmt: skip
        )
        epoch_s = time.perf_counter() - t0
    bar.close()
    kept = run.keep_best(
        "predictor.npz", f"no epoch finished within the budget; give more --minutes (an epoch took {epoch_s:.0f} s)"
    )
    plot_predictor_curve(log_path, run.out / "curve.png", st.best_epoch)
    return kept, {"epoch": st.best_epoch, "val_loss": st.best_loss}


def _train_epoch(
    net: PredictorUNet, opt: torch.optim.Optimizer, cfg: PredictorTrainConfig, train_set: BeliefSet, rng: Any
) -> list[float]:
    """One epoch of gradient steps, each on fresh random crops; the steps' losses."""
    losses = []
    for _ in range(cfg.steps_per_epoch):
        x, y, m = _crops(train_set, cfg.batch, cfg.crop_cells, rng)
        loss = masked_bce(net(x), y, m)
        opt.zero_grad()
        loss.backward()
        opt.step()
        losses.append(float(loss.detach()))
    return losses


def _beliefs(
    run: RunFolder,
    cfg: PredictorTrainConfig,
    train_dir: Path | None,
    seed: int,
    sim: SimConfig | None,
    workers: int,
    ray_address: str | None,
    progress: bool | None,
) -> tuple[BeliefSet, BeliefSet]:
    """The training and validation beliefs: collected from missions once, then read back from
    ``beliefs.npz`` (a resumed run's, or a run's whose collection finished before it stopped)."""
    beliefs_path = run.out / "beliefs.npz"
    if beliefs_path.exists():
        with np.load(beliefs_path, allow_pickle=False) as z:
            return BeliefSet.from_arrays(z, "train"), BeliefSet.from_arrays(z, "val")
    train_maps, val_maps = split_maps(train_dir, cfg.val_missions, cfg.episodes.plans)
    if not train_maps:
        run.say("no training DungeonMaps found; collecting on procedural floor plans only")
    jobs = belief_jobs(cfg.missions, train_maps, cfg, np.random.default_rng([seed, 1]), sim)
    val_rng = np.random.default_rng([seed, 2])
    teams = [int(val_rng.integers(cfg.episodes.robots_min, cfg.episodes.robots_max + 1)) for _ in val_maps]
    val_jobs = [
        BeliefJob(m, n, i, cfg, sim, len(jobs) + i) for i, (m, n) in enumerate(zip(val_maps, teams, strict=True))
    ]
    train_set, val_set = BeliefSet([], [], []), BeliefSet([], [], [])
    bar = Progress(len(jobs) + len(val_jobs), "collect beliefs", "missions", progress)
    env_vars = {THREADS_ENV: "1", "OMP_NUM_THREADS": "1"}
    with JobRunner(collect_beliefs, workers, ray_address, init_worker, (), env_vars) as runner:
        results = []
        for r in runner.run(jobs + val_jobs):
            results.append(r)
            bar.update()
    bar.close()
    for r in sorted(results, key=lambda r: int(r["index"])):
        (train_set if r["index"] < len(jobs) else val_set).extend(r["set"])
    if not len(train_set) or not len(val_set):
        raise MrExploreError("the collection missions left no belief with unknown cells near a frontier")
    tmp = run.out / "beliefs.tmp.npz"
    arrays: dict[str, Any] = train_set.to_arrays("train") | val_set.to_arrays("val")
    np.savez_compressed(tmp, **arrays)
    tmp.replace(beliefs_path)
    run.say(f"collected {len(train_set)} training and {len(val_set)} validation beliefs")
    return train_set, val_set
