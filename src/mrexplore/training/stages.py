"""The trainer's stages, each with one small interface (:class:`Stage`): the yardstick (``baseline``), a
generation of the policy search (``search*``), a DAgger round (``dagger*``), a PPO iteration (``ppo*``) of
``hier`` or of NeuralCoMapping. Each collects episodes and trains; the loop around them
(:func:`~mrexplore.training.trainer.train`) owns the budget, validation, keep-best and checkpoints, as
Stable-Baselines3's ``learn()`` is collect + train with an evaluation callback."""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
import torch

from mrexplore.config import TrainConfig
from mrexplore.global_planning.learned.methods import learned_method
from mrexplore.training.episodes import EpisodeJob, JobKind, NcmActorCritic, training_jobs, weights_of
from mrexplore.training.expert import ExpertLabel
from mrexplore.training.hier_net import MultiGraphNet
from mrexplore.training.search import cross_entropy_step, relative_score, search_candidates
from mrexplore.training.twins import torch_twin
from mrexplore.training.updates import fit_imitation, hier_ppo_update, ncm_ppo_update

__all__ = ["TrainState", "StageContext", "Stage", "Baseline", "Search", "Dagger", "Ppo", "NcmPpo", "stages_of"]


@dataclass
class TrainState:
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


@dataclass
class StageContext:
    """What a stage works with: the run's settings, network, optimiser, expert labels, generator and state,
    the training maps, a way to run episodes and the episodes the budget has left."""

    cfg: TrainConfig
    net: MultiGraphNet | NcmActorCritic
    opt: torch.optim.Optimizer
    state: TrainState
    data: list[ExpertLabel]
    rng: np.random.Generator
    train_maps: list[str]
    run: Callable[[list[EpisodeJob]], list[dict[str, Any]]]
    """Runs jobs with the run's episode settings until its deadline; results in the jobs' order."""
    budget_left: Callable[[int], int]
    """``budget_left(n)``: how many of ``n`` episodes the budget still allows."""

    def collect(self, kind: JobKind, n: int) -> list[dict[str, Any]]:
        """``n`` training episodes (as many as the budget allows) with the current weights; counted."""
        jobs = training_jobs(kind, self.budget_left(n), self.train_maps, self.cfg, self.rng, weights_of(self.net))
        results = self.run(jobs)
        self.state.episodes += len(results)
        return results


class Stage(ABC):
    """One stage of a run: :meth:`learn` collects episodes and trains, and returns its log row's fields."""

    yardstick = False
    """The stage every later one is measured against (kept first, ``score relative``'s reference)."""
    unit = "a stage"
    """What :attr:`min_episodes` is the size of, for the message of a budget too small for it."""

    def __init__(self, name: str) -> None:
        self.name = name

    def min_episodes(self, cfg: TrainConfig) -> int:
        """Episodes the stage needs at least; the loop skips it where the budget holds fewer."""
        return 1

    @abstractmethod
    def learn(self, ctx: StageContext) -> dict[str, Any]:
        """Collect episodes and train; the stage's fields of the log row."""

    def validation_weights(self, ctx: StageContext) -> bytes | None:
        """The weights validated after the stage (None: the heuristic)."""
        return weights_of(ctx.net)


class Baseline(Stage):
    """The untrained network: for ``hier`` the heuristic (zero residual), validated as the yardstick."""

    yardstick = True

    def min_episodes(self, cfg: TrainConfig) -> int:
        return 0

    def learn(self, ctx: StageContext) -> dict[str, Any]:
        return {}

    def validation_weights(self, ctx: StageContext) -> bytes | None:
        # hier's baseline is the heuristic, which None weights select; NCM's is its untrained network
        return None if learned_method(ctx.cfg.strategy).starts_from_heuristic else weights_of(ctx.net)


class Search(Stage):
    """One generation of the cross-entropy search over the residual's linear edge weights, every candidate
    on the same training episodes (deterministic decoding); the network takes the elites' mean. Only
    episodes every candidate finished count (a deadline may cut the generation)."""

    unit = "a search generation"

    def min_episodes(self, cfg: TrainConfig) -> int:
        return cfg.search_population  # an episode per vector at least

    def learn(self, ctx: StageContext) -> dict[str, Any]:
        cfg, st, rng = ctx.cfg, ctx.state, ctx.rng
        net = ctx.net
        assert isinstance(net, MultiGraphNet)  # the search is hier's
        n = ctx.budget_left(cfg.search_population * cfg.search_episodes) // cfg.search_population
        sigma = (
            np.asarray(st.search_sigma)
            if st.search_sigma is not None
            else np.full(len(net.edge_weights), cfg.search_sigma)
        )
        cands = search_candidates(net.edge_weights, sigma, cfg.search_population, rng)
        episodes = training_jobs(JobKind.EVAL, n, ctx.train_maps, cfg, rng, None)
        jobs: list[EpisodeJob] = []
        for c, w in enumerate(cands):
            net.set_edge_weights(w)
            weights = weights_of(net)
            jobs += [replace(j, weights=weights, index=c * n + e) for e, j in enumerate(episodes)]
        net.set_edge_weights(cands[0])
        results = ctx.run(jobs)
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


class Dagger(Stage):
    """A DAgger round: the student drives, the lookahead expert labels its decisions (collect); listwise
    imitation on every label gathered so far (train)."""

    def learn(self, ctx: StageContext) -> dict[str, Any]:
        cfg = ctx.cfg
        results = ctx.collect(JobKind.EXPERT, cfg.episodes_per_round)
        ctx.data += [lab for r in results for lab in r["labels"]]
        gains = [g for r in results for g in r["gains"]]
        row = collect_row(results) | {
            "labels": len(ctx.data),
            "expert_gain": float(np.mean(gains)) if gains else None,
        }
        if ctx.data:
            for g in ctx.opt.param_groups:
                g["lr"] = cfg.lr
            assert isinstance(ctx.net, MultiGraphNet)  # DAgger is hier's
            row["loss"], row["expert_agreement"] = fit_imitation(ctx.net, ctx.opt, ctx.data, cfg, ctx.rng)
        return row


class Ppo(Stage):
    """A PPO iteration of ``hier`` on paper eq. 9: sampled rollouts (collect), PPO epochs with the listwise
    expert loss kept (train)."""

    def learn(self, ctx: StageContext) -> dict[str, Any]:
        cfg = ctx.cfg
        results = ctx.collect(JobKind.PPO, cfg.ppo_episodes)
        row = collect_row(results) | _return_mean(results)
        for g in ctx.opt.param_groups:
            g["lr"] = cfg.ppo_lr
        assert isinstance(ctx.net, MultiGraphNet)
        return row | hier_ppo_update(ctx.net, ctx.opt, results, ctx.data, cfg, ctx.rng)


class NcmPpo(Stage):
    """A PPO iteration of NeuralCoMapping with its own reward, critic and coefficients."""

    def learn(self, ctx: StageContext) -> dict[str, Any]:
        cfg = ctx.cfg
        results = ctx.collect(JobKind.PPO, cfg.ncm.ppo_episodes)
        row = collect_row(results) | _return_mean(results)
        assert isinstance(ctx.net, NcmActorCritic)
        return row | ncm_ppo_update(ctx.net, ctx.opt, results, cfg, ctx.rng)


def _hier_stages(cfg: TrainConfig) -> list[Stage]:
    return [
        Baseline("baseline"),
        *(Search(f"search{k}") for k in range(cfg.search_generations)),
        *(Dagger(f"dagger{k}") for k in range(cfg.dagger_rounds)),
        *(Ppo(f"ppo{k}") for k in range(cfg.ppo_iterations)),
    ]


def _ncm_stages(cfg: TrainConfig) -> list[Stage]:
    return [Baseline("baseline"), *(NcmPpo(f"ppo{k}") for k in range(cfg.ncm.ppo_iterations))]


STAGES: dict[str, Callable[[TrainConfig], list[Stage]]] = {"hier": _hier_stages, "ncm": _ncm_stages}
"""Each trainable learned method's stages (by its kind): hier's baseline, search, DAgger and PPO; NCM's
baseline and PPO."""


def stages_of(cfg: TrainConfig) -> list[Stage]:
    """A run's stages in order."""
    return STAGES[torch_twin(cfg.strategy).kind](cfg)


def collect_row(results: Sequence[dict[str, Any]]) -> dict[str, Any]:
    """The log fields of a stage's episodes: decisions, mean steps and coverage."""
    if not results:
        return {}
    return {
        "decisions": int(sum(r["decisions"] for r in results)),
        "steps_mean": float(np.mean([r["steps"] for r in results])),
        "coverage_mean": float(np.mean([r["coverage"] for r in results])),
    }


def _return_mean(results: Sequence[dict[str, Any]]) -> dict[str, Any]:
    return {"return_mean": float(np.mean([r["rewards"].sum() for r in results])) if results else None}
