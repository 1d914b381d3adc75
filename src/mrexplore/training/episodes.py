"""What the trainer's workers run: one training or validation episode of the learned planner (``hier``) or of
NeuralCoMapping, through the package's one replanning loop, returned as plain data."""

from __future__ import annotations

import functools
import io
import os
from dataclasses import dataclass, replace
from enum import StrEnum
from typing import Any

import numpy as np
import torch

from mrexplore.config import MapConfig, MissionConfig, SimConfig, TrainConfig
from mrexplore.global_planning.learned.features import GraphInputs
from mrexplore.global_planning.learned.ncm_inputs import NcmInputs
from mrexplore.global_planning.learned.ncm_planner import NcmPlanner
from mrexplore.global_planning.learned.policy import LearnedPlanner
from mrexplore.maps.loaders import load_map_shared
from mrexplore.mission import Mission, MissionSpec
from mrexplore.pipeline import ExplorationPipeline, NcmPipeline, make_strategy
from mrexplore.pipeline.strategies import loaded_predictor
from mrexplore.prediction.network import MapPredictor
from mrexplore.runtime.threads import THREADS_ENV
from mrexplore.sim.measures import steps_to_coverage
from mrexplore.training.checkpoint import VALUE_INPUTS
from mrexplore.training.expert import (
    ExpertLabel,
    candidate_assignments,
    known_world_returns,
    lookahead_returns,
    privileged_scalars,
)
from mrexplore.training.hier_net import MultiGraphNet
from mrexplore.training.ncm_net import NcmActorCritic, NcmNet, NcmStep, ncm_collate
from mrexplore.training.ncm_policy import per_robot_log_prob
from mrexplore.training.sequential import PolicyStep
from mrexplore.training.twins import torch_twin
from mrexplore.types import MrExploreError

__all__ = [
    "JobKind",
    "EpisodeJob",
    "NcmActorCritic",
    "new_net",
    "policy_net",
    "weights_of",
    "hier_pipeline",
    "ncm_pipeline",
    "episode_mission",
    "run_job",
    "init_worker",
    "training_jobs",
    "VAL_SEED0",
    "FRESH_SEED0",
]


class JobKind(StrEnum):
    """What an episode is run for."""

    EXPERT = "expert"
    """DAgger collection: the student drives, the lookahead expert labels its decisions."""
    PPO = "ppo"
    """A sampled rollout, recorded for PPO."""
    EVAL = "eval"
    """Deterministic decoding (validation, the policy search); None weights: the heuristic."""
    EVAL_SAMPLED = "eval-sampled"
    """NCM's own evaluation: seeded per-robot draws."""


@dataclass(frozen=True)
class EpisodeJob:
    """One episode for a worker."""

    kind: JobKind
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
    """Replanning and faults of the episode (None: defaults); the budget is ``cfg.episodes.max_steps`` and
    failures of robots beyond the team are left out."""
    predictor: str | None = None
    """The map predictor of a policy that reads the predicted gain: a file, ``none`` (every unknown cell
    free) or None (the shipped one)."""


def new_net(cfg: TrainConfig) -> MultiGraphNet | NcmActorCritic:
    """A new torch network of the method ``cfg.strategy`` trains."""
    return torch_twin(cfg.strategy).new_net(cfg)


def policy_net(net: MultiGraphNet | NcmActorCritic) -> MultiGraphNet | NcmNet:
    """What a policy file holds: the whole mGNN (its critic included), or NCM's actor alone."""
    return net.actor if isinstance(net, NcmActorCritic) else net


def weights_of(net: torch.nn.Module) -> bytes:
    buf = io.BytesIO()
    torch.save(net.state_dict(), buf)
    return buf.getvalue()


def _net_from(job: EpisodeJob) -> MultiGraphNet | NcmActorCritic:
    net = new_net(job.cfg)
    if job.weights is not None:
        net.load_state_dict(torch.load(io.BytesIO(job.weights), weights_only=True))
    net.eval()
    return net


@functools.lru_cache(maxsize=4)
def _predictor(spec: str | None) -> MapPredictor | None:
    """A worker's map predictor, loaded once per file."""
    return loaded_predictor(spec)[0]


def _planner(job: EpisodeJob, net: MultiGraphNet, **kw: Any) -> LearnedPlanner:
    """The job's learned planner, with its map predictor where the network reads a prediction."""
    predictor = _predictor(job.predictor) if net.cfg.reads_prediction else None
    return LearnedPlanner(net, predictor=predictor, **kw)


def hier_pipeline(planner: LearnedPlanner | None) -> ExplorationPipeline:
    """``hier`` with the given planner (its local layer in the loop); the heuristic one for None."""
    pipeline = make_strategy("hier-heuristic")
    if planner is not None:
        pipeline.planner = planner
        pipeline.name = "hier"
    return pipeline


def ncm_pipeline(planner: NcmPlanner) -> ExplorationPipeline:
    """``ncm`` (or ``ncm-sampled``) with the given planner and the default preprocessing."""
    return NcmPipeline(planner.name, planner)


def episode_mission(job: EpisodeJob, pipeline: ExplorationPipeline) -> Mission:
    """The job's mission: its map, team and settings, the trainer's step budget."""
    truth = load_map_shared(job.map_spec, MapConfig(resolution_m=job.cfg.episodes.resolution_m))
    base = job.mission or MissionConfig()
    failures = tuple(f for f in base.faults.robot_failures if f[0] < job.robots)
    # Training reads steps and areas, never Table II's bytes: their grid baselines are left uncounted (the
    # same missions, cheaper rounds).
    cfg = replace(
        base,
        max_steps=job.cfg.episodes.max_steps,
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


def run_job(job: EpisodeJob) -> dict[str, Any]:
    """One episode in a worker; returns plain data (labels, a trajectory, or an evaluation) with the job's
    ``index``."""
    return {"index": job.index, **_run_episode(job)}


def _run_episode(job: EpisodeJob) -> dict[str, Any]:
    net = _net_from(job)
    if isinstance(net, NcmActorCritic):
        return _run_ncm(job, net)
    if job.kind == JobKind.EVAL:
        m = episode_mission(job, hier_pipeline(_planner(job, net) if job.weights is not None else None))
        decisions = 0
        while m.advance():
            m.decide()
            decisions += 1
        return {"map": job.map_spec, **_episode_stats(m, decisions)}
    if job.kind == JobKind.EXPERT:
        return _run_expert(job, net)
    return _run_ppo(job, net)


def _run_expert(job: EpisodeJob, net: MultiGraphNet) -> dict[str, Any]:
    cfg = job.cfg
    student = _planner(job, net)
    m = episode_mission(job, hier_pipeline(student))
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
                    g = student.inputs(problem)  # the inputs alone, no forward pass
                    labels.append(ExpertLabel(g, np.stack(cands), returns))
        m.commit(own)  # DAgger: the student's own action moves the episode on
        decisions += 1
    return {"labels": labels, "gains": gains, **_episode_stats(m, decisions)}


def _run_ppo(job: EpisodeJob, net: MultiGraphNet) -> dict[str, Any]:
    cfg = job.cfg
    record: list[PolicyStep] = []
    extra = [np.zeros(net.value_inputs, np.float32)]  # the critic's scalars at the coming decision

    def recorded(g: GraphInputs, order: np.ndarray, choices: np.ndarray, logp: float) -> None:
        record.append(PolicyStep(g, order, choices, logp, net.value_at(g, extra[0]), extra[0]))

    planner = _planner(job, net, sample=True, rng=np.random.default_rng([job.seed, 11]), on_sample=recorded)
    m = episode_mission(job, hier_pipeline(planner))
    rewards: list[float] = []
    discounts: list[float] = []
    last_step = 0
    before_pose = 0.0
    while m.advance():
        before_pose = m.reward_since_decision  # a pose that ends the mission resets it
        extra[0] = privileged_scalars(m)
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


def _run_ncm(job: EpisodeJob, net: NcmActorCritic) -> dict[str, Any]:
    """An NCM episode: evaluated (``eval``: argmax; ``eval-sampled``: each robot draws, from the mission's
    seeded generator) or sampled and recorded for PPO (``ppo``), with NCM's
    reward area_reward * (new m^2 - area_offset_m2 * k / 25) for a decision of k steps."""
    ncfg = job.cfg.ncm
    if job.kind in (JobKind.EVAL, JobKind.EVAL_SAMPLED):
        m = episode_mission(job, ncm_pipeline(NcmPlanner(net.actor, sample=job.kind == JobKind.EVAL_SAMPLED)))
        decisions = 0
        while m.advance():
            m.decide()
            decisions += 1
        return {"map": job.map_spec, **_episode_stats(m, decisions)}
    record: list[NcmStep] = []
    extra = [np.zeros(VALUE_INPUTS, np.float32)]  # the critic's scalars at the coming decision

    def recorded(inputs: NcmInputs, rows: np.ndarray, picks: np.ndarray, out: np.ndarray) -> None:
        with torch.no_grad():
            value = float(net.critic(ncm_collate([inputs]), torch.from_numpy(extra[0])[None])[0])
        logp = float(per_robot_log_prob(torch.from_numpy(rows), torch.from_numpy(np.asarray(picks, np.int64))))
        record.append(NcmStep(inputs, out.copy(), logp, value, extra[0]))

    planner = NcmPlanner(net.actor, sample=True, on_sample=recorded)
    m = episode_mission(job, ncm_pipeline(planner))
    cell_m2 = job.cfg.episodes.resolution_m**2
    rewards: list[float] = []
    discounts: list[float] = []
    last_known, last_step = m.sim.known_cells, m.steps

    def close_interval() -> None:
        k = m.steps - last_step
        gained = (m.sim.known_cells - last_known) * cell_m2
        rewards.append(ncfg.area_reward * (gained - ncfg.area_offset_m2 * k / 25.0))
        discounts.append(ncfg.gamma ** (k / 25.0))

    while m.advance():
        extra[0] = privileged_scalars(m)
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


def init_worker() -> None:
    """A local worker's kernels and torch run on one thread: the episodes fill the cores."""
    os.environ[THREADS_ENV] = "1"
    torch.set_num_threads(1)


VAL_SEED0 = 1_000_000
"""Procedural validation plans use seeds from here; training plans draw seeds below it."""
FRESH_SEED0 = 2_000_000
"""Procedural plans from this seed on are never trained or validated on (validation takes ``val_maps``
seeds from :data:`VAL_SEED0`): a test split of the training distribution that no run picked a stage on."""


def training_jobs(
    kind: JobKind, n: int, maps: list[str], cfg: TrainConfig, rng: np.random.Generator, weights: bytes | None
) -> list[EpisodeJob]:
    """``n`` training episodes: a procedural plan (seeds below :data:`VAL_SEED0`) or one of ``maps``, a team
    size and a seed, all drawn from ``rng``."""
    jobs: list[EpisodeJob] = []
    for _ in range(n):
        if not maps or rng.random() < cfg.episodes.generated_share:
            spec = f"{cfg.episodes.plans}:{int(rng.integers(0, VAL_SEED0))}"
        else:
            spec = maps[int(rng.integers(len(maps)))]
        robots = int(rng.integers(cfg.episodes.robots_min, cfg.episodes.robots_max + 1))
        jobs.append(EpisodeJob(kind, spec, robots, int(rng.integers(0, 2**31 - 1)), weights, cfg, len(jobs)))
    return jobs
