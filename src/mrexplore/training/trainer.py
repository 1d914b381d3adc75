"""Training of the learned global layer: the heuristic start, DAgger rounds on the lookahead expert, PPO;
and of the NeuralCoMapping baseline (``strategy: ncm``): its untrained network, then its PPO.

The loop reads top to bottom (stages: baseline, dagger*, ppo*). Each stage collects episodes in worker
processes (or Ray tasks), updates the network, validates it on held-out maps with deterministic
decoding, logs, and checkpoints; ``resume`` continues after the last finished stage. The policy kept is
the one with the fewest validation steps, never the last by default.
"""

from __future__ import annotations

import csv
import functools
import io
import math
import os
import shutil
import sys
import time
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np
import torch
from tqdm import tqdm

from mrexplore.config import MapConfig, MissionConfig, SimConfig, TrainConfig, config_to_dict
from mrexplore.csv_append import append_row, drop_partial_tail, keep_rows
from mrexplore.global_planning.learned.checkpoint import VALUE_INPUTS, code_version, save_policy
from mrexplore.global_planning.learned.features import EDGE_FEATURES, GraphInputs, graph_inputs
from mrexplore.global_planning.learned.ncm_network import (
    NcmCritic,
    NcmNet,
    NcmPlanner,
    NcmStep,
    ncm_collate,
    ncm_log_prob,
)
from mrexplore.global_planning.learned.network import MultiGraphNet, collate
from mrexplore.global_planning.learned.policy import (
    LearnedPlanner,
    PolicyStep,
    assignment_score,
    sequential_log_prob,
)
from mrexplore.maps.ground_truth import GroundTruthMap
from mrexplore.maps.loaders import load_map
from mrexplore.mission import Mission, MissionSpec
from mrexplore.pipeline import ExplorationPipeline, NcmPipeline, make_strategy
from mrexplore.sim.measures import steps_to_coverage
from mrexplore.threads import THREADS_ENV
from mrexplore.training.curve import plot_learning_curve
from mrexplore.training.expert import (
    ExpertLabel,
    candidate_assignments,
    known_world_returns,
    lookahead_returns,
    privileged_scalars,
)
from mrexplore.training.ppo import PPOStats, gae, listwise_loss, ppo_loss
from mrexplore.training.search import cross_entropy_step, relative_score, search_candidates
from mrexplore.types import MrExploreError
from mrexplore.workers import stop_pool, worker_pool

__all__ = ["train", "validate_policy", "TrainResult", "split_maps", "LOG_COLUMNS", "FRESH_SEED0"]

LOG_COLUMNS = [
    "time_s", "stage", "episodes", "decisions", "labels", "loss", "expert_agreement", "expert_gain", "kl",
    "clip_fraction", "entropy", "value_loss", "return_mean", "steps_mean", "coverage_mean", "val_steps_mean",
    "val_coverage_mean", "val_score", "val_sampled_steps_mean", "val_sampled_coverage_mean", "decisions_per_s",
    "search_best_steps", "edge_weights",
]  # fmt: skip
_VAL_SEED0 = 1_000_000
"""Procedural validation plans use seeds from here; training plans draw seeds below it."""
FRESH_SEED0 = 2_000_000
"""Procedural plans from this seed on are never trained or validated on (validation takes ``val_maps``
seeds from ``_VAL_SEED0``): a test split of the training distribution that no run picked a stage on."""
_BATCH = 64


# -- maps -------------------------------------------------------------------------------------------------
def split_maps(train_dir: Path | None, val_maps: int, plans: str = "varied") -> tuple[list[str], list[str]]:
    """Training and validation map specs: training DungeonMaps (the last ones by name held out) and
    procedural floor plans (``PLANS:SEED``, ``plans`` being ``varied`` or ``generated``; validation seeds
    from 1,000,000). Half the validation maps are DungeonMaps where the folder exists."""
    dungeons: list[str] = []
    if train_dir is not None and train_dir.is_dir():
        dungeons = sorted(str(p) for p in train_dir.rglob("*.png"))
    n_dungeon_val = min(len(dungeons) // 10, val_maps // 2) if dungeons else 0
    val = dungeons[len(dungeons) - n_dungeon_val :] if n_dungeon_val else []
    val += [f"{plans}:{_VAL_SEED0 + i}" for i in range(val_maps - len(val))]
    return dungeons[: len(dungeons) - n_dungeon_val], val


@functools.lru_cache(maxsize=4)
def _map(spec: str, resolution_m: float) -> GroundTruthMap:
    truth = load_map(spec, MapConfig(resolution_m=resolution_m))
    truth.occupied.flags.writeable = False
    return truth


# -- what workers run -------------------------------------------------------------------------------------
@dataclass(frozen=True)
class _Job:
    kind: str
    """"expert" (DAgger collection), "ppo" (sampled rollout), "eval" (deterministic, None weights: heuristic)
    or, for NCM, "eval-sampled" (its own evaluation: seeded per-robot draws)."""
    map_spec: str
    robots: int
    seed: int
    weights: bytes | None
    cfg: TrainConfig
    index: int = 0
    """Position in its batch: results are put back in this order, so a run does not depend on which
    worker finished first."""
    sim: SimConfig | None = None
    """Sensor, motion and reward of the episode (None: defaults); the team size is ``robots``."""
    mission: MissionConfig | None = None
    """Replanning and faults of the episode (None: defaults); the budget is ``cfg.max_steps`` and
    failures of robots beyond the team are left out."""


class NcmActorCritic(torch.nn.Module):
    """NCM's actor and our critic, trained together (one state dict, one optimiser with two learning rates);
    only the actor is a policy file."""

    def __init__(self) -> None:
        super().__init__()
        self.actor = NcmNet()
        self.critic = NcmCritic(extra=VALUE_INPUTS)


def _new_net(cfg: TrainConfig) -> MultiGraphNet | NcmActorCritic:
    return NcmActorCritic() if cfg.strategy == "ncm" else MultiGraphNet(cfg.learned, VALUE_INPUTS)


def _policy_net(net: MultiGraphNet | NcmActorCritic) -> MultiGraphNet | NcmNet:
    """What a policy file holds: the whole mGNN (its critic included), or NCM's actor alone."""
    return net.actor if isinstance(net, NcmActorCritic) else net


def _weights(net: torch.nn.Module) -> bytes:
    buf = io.BytesIO()
    torch.save(net.state_dict(), buf)
    return buf.getvalue()


def _net_from(job: _Job) -> MultiGraphNet | NcmActorCritic:
    net = _new_net(job.cfg)
    if job.weights is not None:
        net.load_state_dict(torch.load(io.BytesIO(job.weights), weights_only=True))
    net.eval()
    return net


def _pipeline(planner: LearnedPlanner | None) -> ExplorationPipeline:
    """``hier`` with the given planner (its local layer in the loop); the heuristic one for None."""
    pipeline = make_strategy("hier-heuristic")
    if planner is not None:
        pipeline.planner = planner
        pipeline.name = "hier"
    return pipeline


def _mission(job: _Job, pipeline: ExplorationPipeline) -> Mission:
    truth = _map(job.map_spec, job.cfg.resolution_m)
    base = job.mission or MissionConfig()
    failures = tuple(f for f in base.faults.robot_failures if f[0] < job.robots)
    # Training reads steps and areas, never Table II's bytes: their grid baselines are left uncounted (the
    # same missions, cheaper rounds).
    cfg = replace(
        base,
        max_steps=job.cfg.max_steps,
        faults=replace(base.faults, robot_failures=failures),
        baseline_bytes=False,
    )
    sim = replace(job.sim or SimConfig(), robots=job.robots)
    return Mission(MissionSpec(truth, pipeline, sim, cfg, seed=job.seed), progress=False)


def _episode_stats(m: Mission, decisions: int) -> dict[str, float]:
    s99 = steps_to_coverage(np.asarray(m.record.curve), 0.99)
    return {
        "steps": m.steps,
        "steps_99": m.steps if s99 is None else s99,  # never there: all its steps, as the bench report counts
        "coverage": m.sim.coverage,
        "decisions": decisions,
        "done": float(m.done_reason != "max_steps"),
    }


def _run_job(job: _Job) -> dict[str, Any]:
    """One episode in a worker; returns plain data (labels, a trajectory, or an evaluation)."""
    return {"index": job.index, **_run_episode(job)}


def _run_episode(job: _Job) -> dict[str, Any]:
    net = _net_from(job)
    if isinstance(net, NcmActorCritic):
        return _run_ncm(job, net)
    if job.kind == "eval":
        m = _mission(job, _pipeline(LearnedPlanner(net) if job.weights is not None else None))
        decisions = 0
        while m.advance():
            m.decide()
            decisions += 1
        return {"map": job.map_spec, **_episode_stats(m, decisions)}
    if job.kind == "expert":
        return _run_expert(job, net)
    return _run_ppo(job, net)


def _run_expert(job: _Job, net: MultiGraphNet) -> dict[str, Any]:
    cfg = job.cfg
    student = LearnedPlanner(net)
    m = _mission(job, _pipeline(student))
    continuation = make_strategy("hier-heuristic").planner
    lookahead = known_world_returns if cfg.expert_world == "known" else lookahead_returns
    rng = np.random.default_rng([job.seed, 7])
    labels: list[ExpertLabel] = []
    gains: list[float] = []
    decisions = 0
    while m.advance():
        problem = m.pose()
        if problem is None:
            continue  # the end (advance says so next), or a round where the centre heard nobody
        own = student.assign(problem)
        if decisions % cfg.label_every == 0 and problem.n_clusters > 1:
            cands = candidate_assignments(problem, own, student.heuristic, cfg.noisy_candidates, cfg.noise_m, rng)
            if len(cands) > 1:
                returns = lookahead(m, cands, cfg.horizon_steps, continuation)
                gains.append(float(returns.max() - returns[0]))  # candidate 0 is the student's own
                if np.ptp(returns) > 0:  # a decision where every candidate is as good teaches nothing
                    g = graph_inputs(problem, net.cfg, student.heuristic)  # the inputs alone, no forward pass
                    labels.append(ExpertLabel(g, np.stack(cands), returns))
        m.commit(own)  # DAgger: the student's own action moves the episode on
        decisions += 1
    return {"labels": labels, "gains": gains, **_episode_stats(m, decisions)}


def _run_ppo(job: _Job, net: MultiGraphNet) -> dict[str, Any]:
    cfg = job.cfg
    record: list[PolicyStep] = []
    planner = LearnedPlanner(net, sample=True, rng=np.random.default_rng([job.seed, 11]), record=record)
    m = _mission(job, _pipeline(planner))
    rewards: list[float] = []
    discounts: list[float] = []
    last_step = 0
    before_pose = 0.0
    while m.advance():
        before_pose = m.reward_since_decision  # a pose that ends the mission resets it
        planner.value_extra = privileged_scalars(m)
        n_before = len(record)
        if m.pose() is None:
            continue  # the end (advance says so next), or a round where the centre heard nobody
        if record:  # close the interval of the previous decision
            rewards.append(m.reward_since_decision)
            discounts.append(cfg.gamma ** (m.steps - last_step))
        m.commit()
        last_step = m.steps
        if len(record) == n_before:  # no assignment was drawn (cannot happen after a posed problem)
            raise MrExploreError("the sampling planner recorded no step")
    if record:  # the last interval: up to the end at a pose, or to the budget
        ended_at_pose = m.decision is not None and m.decision.done_reason is not None
        rewards.append(before_pose if ended_at_pose else m.reward_since_decision)
        discounts.append(0.0 if ended_at_pose else cfg.gamma ** (m.steps - last_step))
    if m.done_reason != "max_steps" and discounts:
        discounts[-1] = 0.0  # explored: nothing follows
    return {
        "steps_rec": record,
        "rewards": np.asarray(rewards),
        "discounts": np.asarray(discounts),
        **_episode_stats(m, len(record)),
    }


def _ncm_pipeline(planner: NcmPlanner) -> ExplorationPipeline:
    """``ncm`` (or ``ncm-sampled``) with the given planner and the default preprocessing."""
    return NcmPipeline(planner.name, planner)


def _run_ncm(job: _Job, net: NcmActorCritic) -> dict[str, Any]:
    """An NCM episode: evaluated (``eval``: argmax; ``eval-sampled``: each robot draws, from the mission's
    seeded generator) or sampled and recorded for PPO (``ppo``), with NCM's
    reward area_reward * (new m^2 - area_offset_m2 * k / 25) for a decision of k steps."""
    ncfg = job.cfg.ncm
    if job.kind in ("eval", "eval-sampled"):
        m = _mission(job, _ncm_pipeline(NcmPlanner(net.actor, sample=job.kind == "eval-sampled")))
        decisions = 0
        while m.advance():
            m.decide()
            decisions += 1
        return {"map": job.map_spec, **_episode_stats(m, decisions)}
    record: list[NcmStep] = []
    planner = NcmPlanner(net.actor, sample=True, critic=net.critic, record=record)
    m = _mission(job, _ncm_pipeline(planner))
    cell_m2 = job.cfg.resolution_m**2
    rewards: list[float] = []
    discounts: list[float] = []
    last_known, last_step = m.sim.known_cells, m.steps

    def close_interval() -> None:
        k = m.steps - last_step
        gained = (m.sim.known_cells - last_known) * cell_m2
        rewards.append(ncfg.area_reward * (gained - ncfg.area_offset_m2 * k / 25.0))
        discounts.append(ncfg.gamma ** (k / 25.0))

    while m.advance():
        planner.value_extra = privileged_scalars(m)
        n_before = len(record)
        if m.pose() is None:
            continue  # the end (advance says so next), or a round where the centre heard nobody
        if n_before:  # close the interval of the previous decision
            close_interval()
        m.commit()
        last_known, last_step = m.sim.known_cells, m.steps
        if len(record) == n_before:
            raise MrExploreError("the sampling planner recorded no step")
    if record:
        close_interval()  # the last decision's interval: up to the end or the budget
        if m.done_reason != "max_steps":
            discounts[-1] = 0.0  # explored: nothing follows
    return {
        "steps_rec": record,
        "rewards": np.asarray(rewards),
        "discounts": np.asarray(discounts),
        **_episode_stats(m, len(record)),
    }


def _init_worker() -> None:
    os.environ[THREADS_ENV] = "1"
    torch.set_num_threads(1)


class _Runner:
    """Runs jobs in local worker processes (spawned) or as Ray tasks; yields results as they finish."""

    def __init__(self, workers: int, ray_address: str | None) -> None:
        self.workers = workers or os.cpu_count() or 1
        self.ray_address = ray_address
        self._pool: ProcessPoolExecutor | None = None
        self._remote: Any = None
        self._ray_started = False

    def __enter__(self) -> _Runner:
        if self.ray_address is not None:
            try:
                import ray
            except ImportError:
                raise MrExploreError("--ray-address needs Ray; install it with: pip install 'mrexplore[ray]'") from None
            if not ray.is_initialized():
                kwargs: dict[str, Any] = (
                    {"num_cpus": self.workers} if self.ray_address == "local" else {"address": self.ray_address}
                )
                ray.init(include_dashboard=False, log_to_driver=False, **kwargs)
                self._ray_started = True
            env = {"env_vars": {THREADS_ENV: "1", "OMP_NUM_THREADS": "1"}}
            self._remote = ray.remote(num_cpus=1, runtime_env=env)(_run_job)
        elif self.workers > 1:
            self._pool = worker_pool(self.workers, _init_worker)
        return self

    def __exit__(self, exc_type: type[BaseException] | None, *exc: object) -> None:
        if self._pool is not None:
            if exc_type is None:
                self._pool.shutdown(cancel_futures=True)
            else:
                stop_pool(self._pool)  # interrupted: what finished is saved; do not wait for the rest
        if self._ray_started:
            import ray

            ray.shutdown()

    def results(self, jobs: Sequence[_Job], deadline: float) -> list[dict[str, Any]]:
        """Results of the ``jobs`` that ran, in the jobs' order (jobs not started by ``deadline`` are dropped)."""
        return sorted(self.run(jobs, deadline), key=lambda r: int(r["index"]))

    def run(self, jobs: Sequence[_Job], deadline: float) -> Iterator[dict[str, Any]]:
        """Results of ``jobs`` as they finish; jobs not started by ``deadline`` (perf_counter) are dropped."""
        if self._remote is not None:
            import ray

            pending = [self._remote.remote(j) for j in jobs]
            while pending:
                done, pending = ray.wait(pending, num_returns=1)
                yield ray.get(done[0])
                if time.perf_counter() > deadline:
                    for ref in pending:
                        ray.cancel(ref)
                    return
        elif self._pool is not None:
            futures: set[Future[dict[str, Any]]] = {self._pool.submit(_run_job, j) for j in jobs}
            while futures:
                done_f, futures = wait(futures, return_when=FIRST_COMPLETED)
                for f in done_f:
                    yield f.result()
                if time.perf_counter() > deadline:
                    for f in futures:
                        f.cancel()
                    futures = {f for f in futures if f.running()}
                    deadline = math.inf  # let the running ones finish, start no more
        else:
            for j in jobs:
                if time.perf_counter() > deadline:
                    return
                yield _run_job(j)


# -- updates ----------------------------------------------------------------------------------------------
def _pad_rows(rows: Sequence[np.ndarray], width: int, fill: float) -> np.ndarray:
    out = np.full((len(rows), width), fill, dtype=np.asarray(rows[0]).dtype)
    for i, r in enumerate(rows):
        out[i, : len(r)] = r
    return out


def _label_batch(labels: Sequence[ExpertLabel]) -> tuple[Any, torch.Tensor, torch.Tensor, torch.Tensor]:
    batch = collate([lab.inputs for lab in labels])
    R = batch.robots.shape[1]
    M = max(len(lab.candidates) for lab in labels)
    cands = np.full((len(labels), M, R), -1, np.int64)
    rets = np.zeros((len(labels), M))
    valid = np.zeros((len(labels), M), bool)
    for b, lab in enumerate(labels):
        m, r = lab.candidates.shape
        cands[b, :m, :r] = lab.candidates
        rets[b, :m] = lab.returns
        valid[b, :m] = True
    return batch, torch.from_numpy(cands), torch.from_numpy(rets).float(), torch.from_numpy(valid)


def _imitation_loss(
    net: MultiGraphNet, labels: Sequence[ExpertLabel], temperature: float, residual_l2: float = 0.0
) -> tuple[torch.Tensor, float]:
    """Listwise loss of a minibatch (plus ``residual_l2`` times the mean squared residual over the allowed
    pairs) and the share of decisions where the student ranks the expert's best candidate (or one as good)
    first."""
    batch, cands, rets, valid = _label_batch(labels)
    aff, _, _ = net(batch)
    scores = assignment_score(aff, cands)
    loss = listwise_loss(scores, rets, valid, temperature)
    if residual_l2 > 0:
        # the scoring MLP's part only: the linear edge path is the policy search's, which this must not undo
        allowed = torch.isfinite(aff)
        residual = torch.where(allowed, aff - batch.base - net.edge_path(batch), torch.zeros_like(aff))
        loss = loss + residual_l2 * (residual**2).sum() / allowed.sum().clamp(min=1)
    with torch.no_grad():
        pick = torch.where(valid, scores, torch.full_like(scores, -1e9)).argmax(-1)
        best = torch.where(valid, rets, torch.full_like(rets, -1e9)).max(-1).values
        agree = float((rets.gather(1, pick[:, None]).squeeze(1) >= best - 1e-9).float().mean())
    return loss, agree


def _fit_imitation(
    net: MultiGraphNet,
    opt: torch.optim.Optimizer,
    data: Sequence[ExpertLabel],
    cfg: TrainConfig,
    rng: np.random.Generator,
) -> tuple[float, float]:
    net.train()
    losses, agrees = [], []
    for _ in range(cfg.imitation_epochs):
        order = rng.permutation(len(data))
        for s in range(0, len(order), _BATCH):
            batch = [data[i] for i in order[s : s + _BATCH]]
            loss, agree = _imitation_loss(net, batch, cfg.return_temperature, cfg.residual_l2)
            opt.zero_grad()
            loss.backward()
            torch.nn.utils.clip_grad_norm_(net.parameters(), 1.0)
            opt.step()
            losses.append(float(loss.detach()))
            agrees.append(agree)
    net.eval()
    last = max(1, len(losses) // max(1, cfg.imitation_epochs))  # the last epoch's batches
    return float(np.mean(losses[-last:])), float(np.mean(agrees[-last:]))


def _ppo(
    net: torch.nn.Module,
    opt: torch.optim.Optimizer,
    trajectories: Sequence[dict[str, Any]],
    reward_scale: float,
    gae_lambda: float,
    epochs: int,
    rng: np.random.Generator,
    minibatch_loss: Callable[[list[Any], torch.Tensor, torch.Tensor], tuple[torch.Tensor, PPOStats]],
) -> dict[str, float]:
    """PPO epochs over the decisions of ``trajectories`` (each with ``steps_rec``, whose steps carry the
    critic's ``value``; ``rewards``; ``discounts``): GAE per episode, advantages normalised over the batch,
    minibatches of 64 in a random order; ``minibatch_loss(steps, advantages, returns)`` is the strategy's
    loss. Returns the mean of each logged part."""
    steps: list[Any] = []
    adv_all, ret_all = [], []
    for tr in trajectories:
        rec = tr["steps_rec"]
        if not rec:
            continue
        values = np.array([s.value for s in rec])
        adv, ret = gae(tr["rewards"] * reward_scale, values, tr["discounts"], 0.0, gae_lambda)
        steps += rec
        adv_all.append(adv)
        ret_all.append(ret)
    if not steps:
        return {}
    adv = np.concatenate(adv_all)
    adv = (adv - adv.mean()) / (adv.std() + 1e-8)
    ret = np.concatenate(ret_all)
    net.train()
    stats: list[dict[str, float]] = []
    for _ in range(epochs):
        order = rng.permutation(len(steps))
        for s in range(0, len(order), _BATCH):
            idx = order[s : s + _BATCH]
            t = torch.from_numpy
            loss, st = minibatch_loss([steps[i] for i in idx], t(adv[idx]).float(), t(ret[idx]).float())
            opt.zero_grad()
            loss.backward()
            torch.nn.utils.clip_grad_norm_(net.parameters(), 1.0)
            opt.step()
            stats.append(
                {
                    "loss": float(loss.detach()),
                    "kl": st.approx_kl,
                    "clip_fraction": st.clip_fraction,
                    "entropy": st.entropy,
                    "value_loss": st.value,
                }
            )
    net.eval()
    return {k: float(np.mean([x[k] for x in stats])) for k in stats[0]}


def _ppo_update(
    net: MultiGraphNet,
    opt: torch.optim.Optimizer,
    trajectories: Sequence[dict[str, Any]],
    data: Sequence[ExpertLabel],
    cfg: TrainConfig,
    rng: np.random.Generator,
) -> dict[str, float]:
    """hier's PPO on eq. 9 (sequential sampling's log-probability), with the listwise expert loss kept."""

    def minibatch_loss(mb: list[PolicyStep], adv: torch.Tensor, ret: torch.Tensor) -> tuple[torch.Tensor, PPOStats]:
        batch = collate([st.inputs for st in mb])
        R = batch.robots.shape[1]
        aff, vr, vc = net(batch)
        v_new = net.value_of(vr, vc, batch, torch.from_numpy(np.stack([x.extra for x in mb])))
        o = torch.from_numpy(_pad_rows([st.order for st in mb], R, -1))
        c = torch.from_numpy(_pad_rows([st.choices for st in mb], R, -1))
        logp, ent = sequential_log_prob(aff, o, c)
        old = torch.tensor([x.logp for x in mb], dtype=torch.float32)
        loss, st = ppo_loss(logp, old, adv, v_new, ret, ent, cfg.clip, cfg.value_coef, cfg.entropy_coef)
        if data and cfg.imitation_coef > 0:
            pick = rng.choice(len(data), size=min(_BATCH, len(data)), replace=False)
            im, _ = _imitation_loss(net, [data[i] for i in pick], cfg.return_temperature, cfg.residual_l2)
            loss = loss + cfg.imitation_coef * im
        return loss, st

    return _ppo(net, opt, trajectories, cfg.reward_scale, cfg.gae_lambda, cfg.ppo_epochs, rng, minibatch_loss)


def _ncm_update(
    net: NcmActorCritic,
    opt: torch.optim.Optimizer,
    trajectories: Sequence[dict[str, Any]],
    cfg: TrainConfig,
    rng: np.random.Generator,
) -> dict[str, float]:
    """NCM's PPO: per-robot categoricals' joint log-probability, its critic, its coefficients (rewards
    already carry NCM's scale)."""
    n = cfg.ncm

    def minibatch_loss(mb: list[NcmStep], adv: torch.Tensor, ret: torch.Tensor) -> tuple[torch.Tensor, PPOStats]:
        logp, ent = ncm_log_prob(net.actor, mb)
        v_new = net.critic(ncm_collate([x.inputs for x in mb]), torch.from_numpy(np.stack([x.extra for x in mb])))
        old = torch.tensor([x.logp for x in mb], dtype=torch.float32)
        return ppo_loss(logp, old, adv, v_new, ret, ent, n.clip, n.value_coef, n.entropy_coef)

    return _ppo(net, opt, trajectories, 1.0, n.gae_lambda, n.ppo_epochs, rng, minibatch_loss)


def _search_generation(
    net: MultiGraphNet,
    st: _State,
    cfg: TrainConfig,
    rng: np.random.Generator,
    budget: int,
    train_maps: list[str],
    run: Callable[[list[_Job]], list[dict[str, Any]]],
) -> dict[str, Any]:
    """One generation of the cross-entropy search: candidates around the current edge weights, each run on
    the same training episodes (deterministic decoding); the network takes the elites' mean. Only episodes
    every candidate finished count (a deadline may cut the generation). ``budget``: episodes it may run,
    at least one per vector (the caller skips a generation that does not fit)."""
    n = budget // cfg.search_population
    sigma = np.asarray(st.search_sigma) if st.search_sigma is not None else np.full(EDGE_FEATURES, cfg.search_sigma)
    cands = search_candidates(net.edge_weights, sigma, cfg.search_population, rng)
    episodes = _episode_jobs("eval", n, train_maps, cfg, rng, None)
    jobs: list[_Job] = []
    for c, w in enumerate(cands):
        net.set_edge_weights(w)
        weights = _weights(net)
        jobs += [replace(j, weights=weights, index=c * n + e) for e, j in enumerate(episodes)]
    net.set_edge_weights(cands[0])
    results = run(jobs)
    steps = np.full((len(cands), n), np.nan)
    steps_99 = np.full((len(cands), n), np.nan)
    coverage = np.full((len(cands), n), np.nan)
    decisions = 0
    for r in results:
        c, e = divmod(int(r["index"]), n)
        steps[c, e], steps_99[c, e], coverage[c, e] = r["steps"], r["steps_99"], r["coverage"]
        decisions += int(r["decisions"])
    st.episodes += len(results)
    common = np.isfinite(steps).all(axis=0)
    if not common.any():
        return {}
    mean_steps = steps[:, common].mean(axis=1)
    score = mean_steps
    if cfg.score == "relative":  # against the current weights (candidate 0) on each episode
        score = relative_score(steps[:, common], steps_99[:, common], steps[0, common], steps_99[0, common])
    new_mean, new_sigma = cross_entropy_step(cands, score, cfg.search_elites, cfg.search_sigma_min)
    net.set_edge_weights(new_mean)
    st.search_sigma = [float(v) for v in new_sigma]
    return {
        "decisions": decisions,
        "steps_mean": float(mean_steps[0]),
        "coverage_mean": float(coverage[0, common].mean()),
        "search_best_steps": float(mean_steps[np.argmin(score)]),
        "edge_weights": " ".join(f"{v:.3f}" for v in new_mean),
    }


def _optimizer(net: MultiGraphNet | NcmActorCritic, cfg: TrainConfig) -> torch.optim.Optimizer:
    if isinstance(net, NcmActorCritic):
        return torch.optim.Adam(
            [
                {"params": net.actor.parameters(), "lr": cfg.ncm.lr},
                {"params": net.critic.parameters(), "lr": cfg.ncm.lr * cfg.ncm.critic_lr_ratio},
            ]
        )
    return torch.optim.Adam(net.parameters(), lr=cfg.lr, weight_decay=cfg.weight_decay)


# -- the run ----------------------------------------------------------------------------------------------
@dataclass
class _State:
    """What a resumed run needs besides the weights and the data (plain data: it goes into state.pt)."""

    stage: int = 0
    episodes: int = 0
    elapsed_s: float = 0.0
    best_val: float = math.inf
    best_stage: str = ""
    stage_rows: list[dict[str, Any]] = field(default_factory=list)
    search_sigma: list[float] | None = None
    """The policy search's spread per edge weight after the last generation (None: none ran yet)."""
    val_ref: list[list[float]] | None = None
    """The baseline stage's steps to the end and to 99% per validation map, in order (``score``
    ``relative`` compares every later stage with them; None: not run yet)."""
    log_rows: int = -1
    """Rows of log.csv when the state was saved (a resumed run drops later ones: it writes them again);
    -1: not recorded (a state from before this field), keep every row."""


@dataclass(frozen=True)
class TrainResult:
    """Where a run left its policy and what each stage measured on the validation maps."""

    policy_path: Path
    best_stage: str
    stages: list[dict[str, Any]]


def _stages(cfg: TrainConfig) -> list[str]:
    if cfg.strategy == "ncm":
        return ["baseline"] + [f"ppo{k}" for k in range(cfg.ncm.ppo_iterations)]
    return (
        ["baseline"]
        + [f"search{k}" for k in range(cfg.search_generations)]
        + [f"dagger{k}" for k in range(cfg.dagger_rounds)]
        + [f"ppo{k}" for k in range(cfg.ppo_iterations)]
    )


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

    def __init__(self, out: Path, keep: int | None = None) -> None:
        """``keep``: rows a resumed run keeps (those of the stages it saved); a cut last line goes too."""
        self.path = out / "log.csv"
        drop_partial_tail(self.path)
        if keep is not None:
            keep_rows(self.path, keep)
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


def _episode_jobs(
    kind: str, n: int, maps: list[str], cfg: TrainConfig, rng: np.random.Generator, weights: bytes | None
) -> list[_Job]:
    jobs: list[_Job] = []
    for _ in range(n):
        if not maps or rng.random() < cfg.generated_share:
            spec = f"{cfg.plans}:{int(rng.integers(0, _VAL_SEED0))}"
        else:
            spec = maps[int(rng.integers(len(maps)))]
        robots = int(rng.integers(cfg.robots_min, cfg.robots_max + 1))
        jobs.append(_Job(kind, spec, robots, int(rng.integers(0, 2**31 - 1)), weights, cfg, len(jobs)))
    return jobs


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
) -> TrainResult:
    """Train the learned global layer into ``out`` (``policy.pt``, ``best.pt``, ``state.pt``, ``log.csv``,
    ``stages.csv``, ``curve.png``). ``minutes`` and ``episodes`` bound the run (the later stages are skipped).
    ``sim`` and ``mission`` set the episodes' sensor, motion, replanning and faults (None: defaults)."""
    env = {"sim": config_to_dict(sim or SimConfig()), "mission": config_to_dict(mission or MissionConfig())}
    env["mission"].pop("baseline_bytes", None)  # rollouts never count them (:func:`_mission`): not a setting here

    def placed(jobs: list[_Job]) -> list[_Job]:
        return [replace(j, sim=sim, mission=mission) for j in jobs]

    out = Path(out)
    state_path = out / "state.pt"
    if state_path.exists() and not resume:
        raise MrExploreError(f"{out} already holds a training run; pass --resume to continue it, or another --out")
    if resume and not state_path.exists():
        raise MrExploreError(f"nothing to resume in {out} (no state.pt); drop --resume to start a run there")
    out.mkdir(parents=True, exist_ok=True)
    torch.manual_seed(seed)
    net = _new_net(cfg)
    opt = _optimizer(net, cfg)
    st = _State()
    data: list[ExpertLabel] = []
    rng = np.random.default_rng(seed)
    if resume:
        blob = torch.load(state_path, weights_only=True)
        if blob["config"] != config_to_dict(cfg) or blob.get("env", env) != env:
            raise MrExploreError(
                f"{out} was trained with another config; resume with the same --config, or a new --out"
            )
        net.load_state_dict(blob["net"])
        opt.load_state_dict(blob["opt"])
        st = _State(**blob["state"])
        data = _labels_from_blob(blob["data"])
        rng.bit_generator.state = blob["rng"]
        done = f"{st.episodes} episodes, {st.elapsed_s / 60:.1f} min so far"
        say(f"resuming {out} at stage {st.stage} of {len(_stages(cfg))} ({done})")
    train_maps, val_maps = split_maps(train_dir, cfg.val_maps, cfg.plans)
    if not train_maps:
        say("no training DungeonMaps found; training on procedural floor plans only")
    log = _Log(out, st.log_rows if resume and st.log_rows >= 0 else None)
    t_start = time.perf_counter() - st.elapsed_s
    deadline = t_start + minutes * 60 if minutes is not None else math.inf
    stages = _stages(cfg)
    show = sys.stderr.isatty() if progress is None else progress
    bar = tqdm(total=len(stages), initial=st.stage, unit="stage", disable=not show, desc="train")
    with _Runner(workers, ray_address) as runner:

        def budget_left(n: int) -> int:
            return n if episodes is None else max(0, min(n, episodes - st.episodes))

        def validate(weights: bytes | None, kind: str = "eval") -> tuple[float, float, np.ndarray]:
            """Mean steps and coverage, and the steps to the end and to 99% per map (2 x maps, in order)."""
            jobs = placed([_Job(kind, m, cfg.val_robots, i, weights, cfg, i) for i, m in enumerate(val_maps)])
            res = runner.results(jobs, math.inf)
            per_map = np.array([[r["steps"] for r in res], [r["steps_99"] for r in res]], dtype=np.float64)
            return float(per_map[0].mean()), float(np.mean([r["coverage"] for r in res])), per_map

        while st.stage < len(stages):
            stage = stages[st.stage]
            if time.perf_counter() > deadline or (
                episodes is not None and st.episodes >= episodes and stage != "baseline"
            ):
                say(f"budget spent before stage {stage}; stopping")
                break
            if stage.startswith("search") and (left := budget_left(cfg.search_population)) < cfg.search_population:
                # a generation needs an episode per vector at least: go on to the stages that fit the budget
                say(f"{left} episodes left, under a search generation's {cfg.search_population}; skipping {stage}")
                st.stage += 1
                bar.update()
                continue
            t0 = time.perf_counter()
            row: dict[str, Any] = {"stage": stage}
            if stage == "baseline":
                # The untrained network is the heuristic (zero residual): its validation is the yardstick.
                pass
            elif isinstance(net, NcmActorCritic):
                n = budget_left(cfg.ncm.ppo_episodes)
                results = runner.results(placed(_episode_jobs("ppo", n, train_maps, cfg, rng, _weights(net))), deadline)
                st.episodes += len(results)
                row |= _collect_row(results) | {
                    "return_mean": float(np.mean([r["rewards"].sum() for r in results])) if results else None
                }
                row |= _ncm_update(net, opt, results, cfg, rng)
            elif stage.startswith("search"):
                # cross-entropy search over the linear edge weights, every candidate on the same episodes
                row |= _search_generation(
                    net, st, cfg, rng, budget_left(cfg.search_population * cfg.search_episodes), train_maps,
                    lambda jobs: runner.results(placed(jobs), deadline),
                )  # fmt: skip
            elif stage.startswith("dagger"):
                # collect: the student drives, the expert labels its decisions
                jobs = placed(
                    _episode_jobs("expert", budget_left(cfg.episodes_per_round), train_maps, cfg, rng, _weights(net))
                )
                results = runner.results(jobs, deadline)
                new = [lab for r in results for lab in r["labels"]]
                data += new
                st.episodes += len(results)
                gains = [g for r in results for g in r["gains"]]
                row |= _collect_row(results) | {
                    "labels": len(data),
                    "expert_gain": float(np.mean(gains)) if gains else None,
                }
                # update: listwise imitation on everything gathered so far
                if data:
                    for g in opt.param_groups:
                        g["lr"] = cfg.lr
                    row["loss"], row["expert_agreement"] = _fit_imitation(net, opt, data, cfg, rng)
            else:
                jobs = placed(_episode_jobs("ppo", budget_left(cfg.ppo_episodes), train_maps, cfg, rng, _weights(net)))
                results = runner.results(jobs, deadline)
                st.episodes += len(results)
                row |= _collect_row(results) | {
                    "return_mean": float(np.mean([r["rewards"].sum() for r in results])) if results else None
                }
                for g in opt.param_groups:
                    g["lr"] = cfg.ppo_lr
                row |= _ppo_update(net, opt, results, data, cfg, rng)
            # validate (deterministic decoding, held-out maps) and keep the best
            # (hier's baseline is the heuristic, which None weights select; NCM's is its untrained network)
            weights = None if stage == "baseline" and cfg.strategy == "hier" else _weights(net)
            row["val_steps_mean"], row["val_coverage_mean"], per_map = validate(weights)
            chosen_by = "val_steps_mean"
            if cfg.score == "relative":  # against the baseline stage (the heuristic for hier), map by map
                if stage == "baseline":
                    st.val_ref = per_map.tolist()
                ref = np.asarray(st.val_ref)
                row["val_score"] = float(relative_score(per_map[0], per_map[1], ref[0], ref[1]))
                chosen_by = "val_score"
            cov_key = "val_coverage_mean"
            if cfg.strategy == "ncm":  # NCM's own evaluation samples: validate that too (seeded per map)
                row["val_sampled_steps_mean"], row["val_sampled_coverage_mean"], _ = validate(weights, "eval-sampled")
                if cfg.ncm.select == "sampled":
                    chosen_by, cov_key = "val_sampled_steps_mean", "val_sampled_coverage_mean"
            if stage == "baseline" or (
                row[chosen_by] < st.best_val and row[cov_key] >= st.stage_rows[0][cov_key] - 0.005
            ):
                st.best_val, st.best_stage = row[chosen_by], stage
                meta = {k: row[k] for k in row if k.startswith("val_")}
                save_policy(
                    out / "best.pt",
                    _policy_net(net),
                    {"stage": stage, **meta, "chosen_by": chosen_by, "train_config": config_to_dict(cfg)},
                )
            elapsed = time.perf_counter() - t0
            row["time_s"] = round(time.perf_counter() - t_start, 1)
            row["episodes"] = st.episodes
            if row.get("decisions"):
                row["decisions_per_s"] = round(row["decisions"] / elapsed, 2)
            st.stage_rows.append(
                {
                    k: row.get(k)
                    for k in (
                        "stage",
                        "episodes",
                        "labels",
                        "expert_gain",
                        "expert_agreement",
                        "val_steps_mean",
                        "val_coverage_mean",
                        "val_score",
                        "val_sampled_steps_mean",
                        "val_sampled_coverage_mean",
                        "edge_weights",
                        "time_s",
                    )
                    if k in row or not k.startswith(("val_sampled", "val_score"))
                }
            )
            log.row(row, st.stage)
            val = f"{row['val_steps_mean']:.1f} steps, coverage {row['val_coverage_mean']:.4f}"
            if "val_score" in row:
                val += f", score {row['val_score']:.4f} (the heuristic's: 1)"
            if "val_sampled_steps_mean" in row:
                val += f"; sampled {row['val_sampled_steps_mean']:.1f} steps, {row['val_sampled_coverage_mean']:.4f}"
            say(f"{stage}: validation {val} ({elapsed:.0f} s)")
            # checkpoint: everything a resume needs, written atomically
            st.stage += 1
            st.elapsed_s = time.perf_counter() - t_start
            st.log_rows = log.rows
            blob = {
                "config": config_to_dict(cfg), "env": env, "net": net.state_dict(), "opt": opt.state_dict(),
                "state": st.__dict__, "data": _labels_to_blob(data), "rng": rng.bit_generator.state,
                "code_version": code_version(),
            }  # fmt: skip
            tmp = state_path.with_name("state.pt.tmp")
            torch.save(blob, tmp)
            tmp.replace(state_path)
            bar.update()
    bar.close()
    shutil.copyfile(out / "best.pt", out / "policy.pt")
    plot_learning_curve(out / "log.csv", out / "curve.png")
    with open(out / "stages.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(st.stage_rows[0]))
        w.writeheader()
        w.writerows(st.stage_rows)
    return TrainResult(out / "policy.pt", st.best_stage, st.stage_rows)


def validate_policy(
    policy: Path | None, cfg: TrainConfig, train_dir: Path | None, workers: int = 0, maps: list[str] | None = None
) -> tuple[list[str], np.ndarray, np.ndarray]:
    """A policy file on ``cfg``'s validation maps (or on ``maps``), to compare runs on one set: the maps,
    in order, then ``(2, maps)`` steps to the end and to 99% coverage (all its steps where an episode never
    got there), and each map's final coverage. ``policy`` None: the heuristic, hier-heuristic (for
    ``cfg.strategy`` ncm, the shipped NCM policy)."""
    from mrexplore.global_planning.learned.checkpoint import load_ncm_policy, load_policy

    weights = None
    if cfg.strategy == "ncm":
        both = NcmActorCritic()
        both.actor.load_state_dict(load_ncm_policy(policy).net.state_dict())
        weights = _weights(both)
    elif policy is not None:
        weights = _weights(load_policy(policy).net)
    val_maps = maps if maps is not None else split_maps(train_dir, cfg.val_maps, cfg.plans)[1]
    with _Runner(workers, None) as runner:
        jobs = [_Job("eval", m, cfg.val_robots, i, weights, cfg, i) for i, m in enumerate(val_maps)]
        res = runner.results(jobs, math.inf)
    steps = np.array([[r["steps"] for r in res], [r["steps_99"] for r in res]], dtype=np.float64)
    return val_maps, steps, np.array([r["coverage"] for r in res], dtype=np.float64)


def _collect_row(results: Sequence[dict[str, Any]]) -> dict[str, Any]:
    if not results:
        return {}
    return {
        "decisions": int(sum(r["decisions"] for r in results)),
        "steps_mean": float(np.mean([r["steps"] for r in results])),
        "coverage_mean": float(np.mean([r["coverage"] for r in results])),
    }
